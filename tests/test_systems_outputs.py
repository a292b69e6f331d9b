"""The compiled outputs (dynamics/compiled/systems_outputs, `outputs.evaluate`, `energies`,
`body_states`) against the numpy reference they replace (`outputs.reference`, `System.energy`):
the same bodies, joint coordinates and rates, reactions, points, residuals and energies at random
states of the sample systems, every joint kind, reversed joints, loaded cut joints, couplings and
a floating system in the falling frame (the numpy path is the independent reference: written
separately, from `System.solve` with numpy's SVD where the kernel solves by loops)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml
from test_systems_compiled import EVERY_KIND, THROWN_DRAG
from test_systems_couplings import _gears, _scene

from massprops.dynamics.systems import tree as tr
from massprops.dynamics.systems.outputs import body_states, energies, evaluate, reference
from massprops.dynamics.systems.robot_scene import load_any_system
from massprops.dynamics.systems.run import prepare
from massprops.dynamics.systems.scene import load_system, parse_system

SAMPLES = Path(__file__).resolve().parents[1] / "sample_scenes"
BOX = "[[0.02, 0, 0], [0, 0.03, 0], [0, 0, 0.04]]"
RTOL = 1e-12

PENDULUM = ("bodies:\n  rod: {mass: 2.0, inertia: [[0.16673333333333333, 0, 0], "
            "[0, 0.16673333333333333, 0], [0, 0, 1.3333333333333333e-4]], "
            "position: [0, 0.25, -0.4330127018922193]}\n"
            "joints:\n  - {name: hinge, type: revolute, bodies: [world, rod], point: [0, 0, 0], "
            "axis: [1, 0, 0]}\nforces: [{type: gravity, g: [0, 0, -9.81]}]\n"
            "time: {duration: 3.0}\n")

REVERSED = f"""bodies:
  a: {{mass: 1.0, inertia: {BOX}, position: [0, 0, -0.5]}}
  b: {{mass: 1.2, inertia: {BOX}, position: [0.1, 0, -1.0]}}
  c: {{mass: 0.8, inertia: {BOX}, position: [0.2, 0.1, -1.5]}}
  d: {{mass: 0.5, inertia: {BOX}, position: [0.3, 0.1, -2.0]}}
joints:
  - {{name: r, type: revolute, bodies: [a, world], point: [0, 0, 0], axis: [0, 1, 0],
     stiffness: 2.0, rest: 0.1, damping: 0.3, torque: 0.4, end: 0.5}}
  - {{name: u, type: universal, bodies: [b, a], point: [0.05, 0, -0.8],
     axes: [[1, 0, 0], [0, 1, 0]]}}
  - {{name: s, type: spherical, bodies: [c, b], point: [0.15, 0, -1.2]}}
  - {{name: p, type: prismatic, bodies: [d, c], point: [0.25, 0.1, -1.8], axis: [0.6, 0, 0.8],
     stiffness: 4.0, damping: 0.5, force: -0.7}}
initial:
  rates: {{r: 0.5, u: [0.4, -0.1], s: [0.3, -0.2, 0.5], p: 0.2}}
forces:
  - {{type: gravity, g: [0, 0, -9.81]}}
time: {{duration: 1.0}}
"""

FALLING = f"""bodies:
  a: {{mass: 1.0, inertia: {BOX}, position: [0, 0, 0]}}
  b: {{mass: 0.6, inertia: {BOX}, position: [0.4, 0, 0.1]}}
  c: {{mass: 0.4, inertia: {BOX}, position: [0.4, 0.3, 0.1]}}
joints:
  - {{name: h, type: revolute, bodies: [a, b], point: [0.2, 0, 0], axis: [0, 1, 0],
     stiffness: 1.5}}
  - {{name: ball, type: spherical, bodies: [b, c], point: [0.4, 0.15, 0.1]}}
initial:
  bodies: {{a: {{velocity: [3, 0, 2], angular_velocity: [0.2, 0.5, -0.1]}}}}
  rates: {{h: 0.8, ball: [0.1, 0.2, -0.3]}}
forces:
  - {{type: gravity, g: [0, 0, -9.81]}}
  - {{type: spring, bodies: [a, c], points: [[0, 0, 0], [0.4, 0.3, 0.1]], stiffness: 2.0,
     rest_length: 0.3}}
time: {{duration: 1.0}}
"""

OSCILLATING = f"""bodies:
  crank: {{mass: 1.0, inertia: {BOX}, position: [0.15, 0, 0]}}
  rod: {{mass: 0.8, inertia: {BOX}, position: [0.5, 0, 0.114]}}
  rocker: {{mass: 1.5, inertia: {BOX}, position: [0.92, 0, 0.354]}}
joints:
  - {{name: O, type: revolute, bodies: [world, crank], point: [0, 0, 0], axis: [0, 1, 0],
     stiffness: 1.0, torque: 2.0, end: 0.5}}
  - {{name: R, type: revolute, bodies: [world, rocker], point: [1.0, 0, 0.4], axis: [0, 1, 0],
     damping: 0.2}}
  - {{name: H, type: revolute, bodies: [crank, rod], point: [0.3, 0, 0], axis: [0, 1, 0],
     damping: 0.1}}
  - {{name: P, type: prismatic, bodies: [rocker, rod], point: [0.3, 0, 0],
     axis: [0.868243142124459, 0, 0.496138938356834], stiffness: 30.0, rest: 0.05,
     damping: 2.0, force: 4.0, end: 0.5}}
initial:
  rates: {{O: 3.0}}
  project_initial: true
time: {{duration: 1.0}}
"""
"""An oscillating-cylinder mechanism whose breadth-first tree closes at the prismatic P (the
world's joints O, R, then H reach the rod before P does), every joint loaded so that the cut
keeps its load: a loaded cut prismatic."""


def _changed(text: str, changes: dict) -> str:
    """A scene whose joints get the keys ``changes`` (by name; None drops a key). A loop with
    a spring, damper or drive on every joint keeps its breadth-first cut (`assemble`), which
    then carries its load."""
    data = yaml.safe_load(text)
    for j in data["joints"]:
        j.update(changes.get(j["name"], {}))
        for key in [k for k, v in j.items() if v is None]:
            del j[key]
    return yaml.safe_dump(data)


def _system(scene: str, tmp_path: Path):
    if scene in ("four_bar", "andrews", "chain10", "slider_crank", "double_pendulum",
                 "mesh_pendulum"):
        loaded = load_system(SAMPLES / f"{scene}.yaml")
    elif scene == "gears":  # a coupling (mimic), driven
        loaded = load_any_system(_scene(tmp_path, _gears(-2.0, 0.3), body="wheel1"))
    else:
        four_bar = (SAMPLES / "four_bar.yaml").read_text()
        text = {"every_kind": EVERY_KIND, "thrown_drag": THROWN_DRAG, "pendulum": PENDULUM,
                "reversed": REVERSED, "falling": FALLING,
                "four_bar_loaded": _changed(four_bar, {
                    "A": {"damping": 0.1}, "B": {"stiffness": 1.0}, "D": {"torque": 0.3},
                    "C": {"stiffness": 3.0, "rest": 0.2, "damping": 0.4, "torque": 0.6,
                          "end": 0.5}}),
                "four_bar_ball": _changed(four_bar, {"C": {"type": "spherical",
                                                           "axis": None}}),
                "four_bar_universal": _changed(four_bar, {"C": {
                    "type": "universal", "axis": None, "axes": [[0, 1, 0], [1, 0, 0]]}}),
                "oscillating": OSCILLATING,
                "oscillating_cylinder": _changed(OSCILLATING, {"P": {
                    "type": "cylindrical", "rest": None, "force": None, "stiffness": None,
                    "damping": None, "end": None}})}[scene]
        loaded = parse_system(text, source=f"{scene}.yaml", base_dir=SAMPLES)
    return prepare(loaded)[:2]


def _states(system, y0, rng, count=4, spread=0.1):
    """y0 and random states near it, on the joints (projected) and, with loops, off them (the
    outputs are the same function of any state)."""
    out = [y0]
    for _ in range(count):
        y = y0 + spread * rng.standard_normal(y0.size)
        tr.normalize(system.tree, y[:system.nq])
        out += [system.project(y)[0], y] if system.m else [y]
    return np.array(out)


def _close(got, want, what, rtol=RTOL):
    got, want = np.asarray(got), np.asarray(want)
    assert got.shape == want.shape, what
    scale = max(1.0, float(np.abs(want).max(initial=0.0)))
    assert np.abs(got - want).max(initial=0.0) <= rtol * scale, what


SCENES = ["pendulum", "four_bar", "andrews", "chain10", "slider_crank", "double_pendulum",
          "mesh_pendulum", "every_kind", "thrown_drag", "reversed", "gears", "falling",
          "four_bar_loaded", "four_bar_ball", "four_bar_universal", "oscillating",
          "oscillating_cylinder"]


@pytest.mark.parametrize("scene", SCENES)
def test_compiled_outputs_equal_numpy(scene, tmp_path):
    system, y0 = _system(scene, tmp_path)
    if scene == "falling":
        assert system.falling is not None
    ys = _states(system, y0, np.random.default_rng(5))
    for t0 in (0.15, 0.7):  # inside and outside the load windows
        t = t0 + 1e-3 * np.arange(len(ys))
        energy = np.array([system.energy(y) for y in ys])
        got, want = evaluate(system, t, ys, energy), reference(system, t, ys, energy)
        for name in ("position", "orientation", "velocity", "angular_velocity", "force",
                     "torque", "joint_points", "energy"):
            _close(getattr(got, name), getattr(want, name), name)
        _close(got.residual, want.residual, "residual", rtol=1e-12 * system.tree.size)
        for k, j in enumerate(system.scene.joints):
            _close(got.coordinates[k], want.coordinates[k], f"{j.name} coordinates")
            _close(got.rates[k], want.rates[k], f"{j.name} rates")
    scale = max(1.0, float(np.abs(energy).max()))
    assert np.abs(energies(system, ys) - energy).max() <= RTOL * scale
    for got_b, want_b in zip(body_states(system, ys), (want.position, want.orientation,
                                                        want.velocity, want.angular_velocity)):
        if system.falling is None:
            _close(got_b, want_b, "body state")


def test_the_scenes_cover_what_the_outputs_distinguish(tmp_path):
    """The scenes above have a cut joint of every kind with coordinates, a loaded cut revolute
    and prismatic, reversed tree joints of every kind with a load, a coupling and a redundant
    loop: every branch of the outputs."""
    loaded_cut, reversed_kinds, cut = set(), set(), set()
    for scene in ("four_bar_loaded", "oscillating", "reversed", "gears", "four_bar",
                  "four_bar_ball", "four_bar_universal", "oscillating_cylinder"):
        system, _ = _system(scene, tmp_path)
        tree = system.tree
        loaded_cut |= {system.scene.joints[tree.cut[n]].kind for n in tree.cut_loaded}
        cut |= {system.scene.joints[k].kind for k in tree.cut}
        reversed_kinds |= {j.kind for j in tree.joints if j.reversed}
        if scene == "gears":
            assert tree.couplings
        if scene == "four_bar":
            assert system.m > system.rank if system.rank is not None else True
    assert loaded_cut == {"revolute", "prismatic"}
    assert cut == {"revolute", "prismatic", "spherical", "universal", "cylindrical"}
    assert {"revolute", "universal", "spherical", "prismatic"} <= reversed_kinds


def test_no_samples_and_a_wild_state():
    """No samples give empty outputs; a wild state (NaN) still has an energy, NaN, for the run's
    divergence check (`run._check_energy`) to report."""
    system, y0 = _system("double_pendulum", Path("."))
    empty = evaluate(system, np.zeros(0), np.zeros((0, y0.size)))
    assert empty.position.shape == (0, 2, 3) and empty.force.shape == (0, 2, 3)
    energy = energies(system, np.array([y0, np.full(y0.size, np.nan)]))
    assert energy[0] == pytest.approx(system.energy(y0), rel=RTOL) and np.isnan(energy[1])
