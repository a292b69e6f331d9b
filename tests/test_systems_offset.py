"""A system is the same run wherever it sits: the double pendulum and the four-bar moved 1e3,
1e6 and 1e8 m away (along every axis) give the joint coordinates and reactions of the run at the
origin, and positions moved by exactly that much up to the output's rounding.

The only difference allowed is the moved scene's own: its numbers are rounded to eps × d (the
four-bar's 17-digit points, moved, no longer close its loop exactly; its start is projected).
Computed about the world origin, the engine lost (d / size)² × eps instead: 2.6e-9 rad for the
double pendulum at 1e3 m, and at 1e6 m it could not run at all."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from massprops.dynamics.systems.run import simulate_system
from massprops.dynamics.systems.scene import parse_system

SAMPLES = Path(__file__).resolve().parent.parent / "sample_scenes"
EPS = np.finfo(float).eps


def _moved(text: str, d: float) -> str:
    """Every `position:` and `point:` of ``text`` moved by (d, d, d)."""
    def move(match: re.Match) -> str:
        values = [float(v) + d for v in match.group(2).split(",")]
        return f"{match.group(1)}[{', '.join(repr(v) for v in values)}]"

    return re.sub(r"((?:position|point): )\[([^\]]*)\]", move, text)


def _run(text: str):
    scene = parse_system(text, source="moved.yaml", base_dir=SAMPLES)
    return simulate_system(scene, rtol=1e-11, every=0.25, estimate=False)


@pytest.mark.parametrize("name", ["double_pendulum", "four_bar"])
@pytest.mark.parametrize("d", [1e3, 1e6, 1e8])
def test_far_from_the_origin(name, d):
    text = re.sub(r"duration: [0-9.]+", "duration: 1.0", (SAMPLES / f"{name}.yaml").read_text())
    here, there = _run(text), _run(_moved(text, d))
    allowed = max(1e-13, 4 * EPS * d)  # the moved input's rounding, relative to ~1 m parts
    for k in range(len(here.samples.coordinates)):
        assert np.abs(here.samples.coordinates[k] - there.samples.coordinates[k]).max() < allowed
    scale = np.abs(here.samples.force).max()
    assert np.abs(here.samples.force - there.samples.force).max() < allowed * scale
    assert np.abs(here.samples.torque - there.samples.torque).max() < allowed * scale
    gap = np.abs(there.samples.position - d - here.samples.position).max()
    assert gap <= 8 * EPS * d, gap


FLOATING = """bodies:
  upper: {{mass: 1.0, inertia: [[0.0834, 0, 0], [0, 0.0834, 0], [0, 0, 0.00007]],
          position: [0, 0, -0.5]}}
  lower: {{mass: 2.0, inertia: [[0.1, 0.01, 0], [0.01, 0.2, 0], [0, 0, 0.15]],
          position: [0.1, 0, -1.5]}}
joints:
  - {{name: elbow, type: revolute, bodies: [upper, lower], point: [0, 0, -1], axis: [0, 1, 0]}}
initial:
  bodies:
    upper: {{velocity: [{v}, 0, 0], angular_velocity: [0.3, 1.0, 0.2]}}
  rates: {{elbow: 2.0}}
forces: [{{type: gravity, g: [0, 0, {g}]}}]
time: {{duration: 4.0}}
"""


def _floating(v: float, g: float):
    scene = parse_system(FLOATING.format(v=v, g=g), source="thrown.yaml", base_dir=SAMPLES)
    return simulate_system(scene, rtol=1e-12, every=0.5, estimate=False)


@pytest.mark.parametrize("v", [1e3, 1e5])
def test_a_floating_system_thrown_far_moves_as_at_rest(v):
    """A free two-link system thrown at v m/s travels v × 4 s: by Galilean invariance its joint
    angle and reactions are those of the same throw at 0 m/s, its positions those plus v t.
    Computed about a point fixed in the world, at 1e3 m/s it could not be run (two million
    steps by 9.7 s of 10) and at 10 m/s its angle was 5e-11 rad off; in the falling frame
    (falling.py) it is the same run to round-off."""
    rest, thrown = _floating(0.0, 0.0), _floating(v, 0.0)
    a, b = rest.samples, thrown.samples
    assert np.abs(a.coordinates[0] - b.coordinates[0]).max() < 1e-12
    assert np.abs(a.force - b.force).max() < 1e-12 * np.abs(a.force).max()
    shift = np.array([v, 0.0, 0.0]) * a.t[:, None, None]
    assert np.abs(b.position - shift - a.position).max() <= 4 * EPS * v * a.t[-1]
    assert np.abs(b.velocity - [v, 0.0, 0.0] - a.velocity).max() <= 4 * EPS * v
    assert thrown.steps == rest.steps


def test_gravity_moves_a_floating_system_as_a_whole():
    """Uniform gravity on a system held by nothing moves its centre by ½ g t² and nothing
    else: the joint angle is that of the same system without gravity, every position is moved
    by ½ g t², every velocity by g t, and the energy (with gravity's potential) is conserved."""
    g = -9.81
    free, falling = _floating(3.0, 0.0), _floating(3.0, g)
    a, b = free.samples, falling.samples
    assert np.abs(a.coordinates[0] - b.coordinates[0]).max() < 1e-12
    drop = np.array([0.0, 0.0, 0.5 * g]) * a.t[:, None, None] ** 2
    assert np.abs(b.position - drop - a.position).max() < 1e-12
    assert np.abs(b.velocity - np.array([0.0, 0.0, g]) * a.t[:, None, None]
                  - a.velocity).max() < 1e-12
    assert falling.diagnostics["energy_rel_drift"] < 1e-11
    assert abs(b.energy[-1] - b.energy[0]) < 1e-10 * abs(b.energy).max()


@pytest.mark.parametrize("push", [1e4, 1e5])
def test_a_floating_system_pushed_far_moves_as_unpushed(push):
    """Forces F m_i / M (world, at each centre of mass) on the free two-link system accelerate
    every body alike: it is the run without them, moved by ½ (F / M) t² (2.7e4 and 2.7e5 m by
    4 s). The falling frame follows gravity only; the kinematics measure from the moving base
    (`tree.reference_point`): computed about a point fixed in the world, one body pushed
    2500 m at rtol 1e-12 took 175,579 steps and gave no estimate. What remains is the speed's:
    the spatial accelerations carry v × ω terms that cancel, so at 1.3e6 m/s (F = 1e6 N) the
    run at rtol 1e-12 takes 36,000 steps where this takes 110 (docs/systems.md)."""
    text = FLOATING.format(v=0.0, g=0.0).replace("forces: [{type: gravity, g: [0, 0, 0.0]}]", (
        f"forces:\n  - {{type: force, body: upper, vector: [{push / 3}, 0, 0]}}\n"
        f"  - {{type: force, body: lower, vector: [{2 * push / 3}, 0, 0]}}"))
    assert text.count("type: force") == 2
    scene = parse_system(text, source="pushed.yaml", base_dir=SAMPLES)
    pushed = simulate_system(scene, rtol=1e-12, every=0.5, estimate=False)
    rest = _floating(0.0, 0.0)
    a, b = rest.samples, pushed.samples
    # the runs step differently (the error scales see the speed, 1.3e6 m/s at the end, whose
    # own rounding is 3e-10 m/s): differences of the tolerance's size, not of the travel's
    assert np.abs(a.coordinates[0] - b.coordinates[0]).max() < 1e-9
    assert np.abs(a.angular_velocity - b.angular_velocity).max() < 1e-8
    assert np.abs(a.force - b.force).max() < 1e-8 * np.abs(a.force).max()
    travel = 0.5 * push / 3.0 * a.t[-1] ** 2
    shift = np.array([0.5 * push / 3.0, 0.0, 0.0]) * a.t[:, None, None] ** 2
    assert np.abs(b.position - shift - a.position).max() <= 16 * EPS * travel
    assert pushed.steps < 2 * rest.steps


def test_the_mass_matrix_is_factored_by_subtree():
    """M is block diagonal over the subtrees that hang from the world (a rate moves only its
    own subtree): `MassFactor` factors the blocks (a forest of free bodies: 6 × 6 each) and
    solves as the dense matrix does."""
    from massprops.dynamics.systems import tree as tr
    from massprops.dynamics.systems.run import prepare
    from massprops.dynamics.systems.system import MassFactor

    box = "inertia: [[0.01, 0, 0], [0, 0.02, 0], [0, 0, 0.025]]"
    more = (f"  third: {{mass: 0.5, {box}, position: [2, 0, 0]}}\n"
            f"  fourth: {{mass: 0.7, {box}, position: [3, 0, -0.5]}}\njoints:\n"
            "  - {name: hinge, type: revolute, bodies: [world, fourth], point: [3, 0, 0], "
            "axis: [0, 1, 0]}\n")
    text = FLOATING.format(v=1.0, g=-9.81).replace("joints:\n", more)
    system, y0, _ = prepare(parse_system(text, source="forest.yaml", base_dir=SAMPLES))
    assert sorted(len(b) for b in system.blocks) == [1, 6, 7]  # hinge; third; upper + elbow
    assert sorted(np.concatenate(system.blocks).tolist()) == list(range(system.nv))
    kin = tr.kinematics(system.tree, y0[:system.nq], y0[system.nq:])
    mass = tr.mass_matrix(system.tree, kin)
    factor = MassFactor(mass, system.blocks)
    rhs = np.random.default_rng(3).standard_normal((system.nv, 2))
    assert np.allclose(factor.solve(rhs), np.linalg.solve(mass, rhs), rtol=1e-12, atol=0)
    s_inv = factor.lower(np.eye(system.nv))
    assert np.allclose(s_inv.T @ s_inv, np.linalg.inv(mass), rtol=1e-12, atol=1e-14)
