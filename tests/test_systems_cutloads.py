"""Springs, dampers and drives on joints that close a loop (issue 17). The truths are
independent of the code under test: energy summed here from the bodies' states and the joints'
coordinates (kinetic + gravity + every spring) is conserved, or changes by exactly the drive's
torque times the turn it drove through; the same mechanism with its loaded joint in the tree
(the spanning tree keeps loaded joints there where the loop has an unloaded one) moves the same;
a hinge or a slide cut from a ball or cylinder joint moves as the same joint in the tree; and the
compiled right-hand side equals the numpy model's at random states."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from massprops.dynamics.compiled.systems_step import rhs, workspace
from massprops.dynamics.systems import tree as tr
from massprops.dynamics.systems.assemble import build_tree
from massprops.dynamics.systems.run import prepare, simulate_system
from massprops.dynamics.systems.scene import load_system, parse_system
from massprops.errors import SceneError
from massprops.rotation import quat_to_matrix, rotation_angle_between

SAMPLES = Path(__file__).resolve().parent.parent / "sample_scenes"
G = np.array([0.0, 0.0, -9.81])

# the sample four-bar (four revolutes about y), with {A}, {B}, {C}, {D} the joints' extra keys
FOUR_BAR = """bodies:
  crank: {{mass: 1.0, inertia: [[0.06254166666666665, 0.0, -0.03606995806762188], [0.0, 0.08336666666666666, 0.0], [-0.03606995806762188, 0.0, 0.020891666666666676]], position: [0.25000000000000006, 0.0, 0.4330127018922193]}}
  coupler: {{mass: 3.0, inertia: [[0.667596712341228, 0.0, -1.0276952327673072], [0.0, 2.250100000000001, 0.0], [-1.0276952327673072, 0.0, 1.5827032876587732]], position: [1.758003825218467, 0.0, 1.6829870771423172]}}
  rocker: {{mass: 2.5, inertia: [[1.3021132857348252, 0.0, -0.008336613445144213], [0.0, 1.3021666666666667, 0.0], [-0.008336613445144213, 0.0, 0.00022004759850816327]], position: [3.0080038252184673, 0.0, 1.2499743752500978]}}
joints:
  - {{name: A, type: revolute, bodies: [world, crank], point: [0, 0, 0], axis: [0, 1, 0]{A}}}
  - {{name: B, type: revolute, bodies: [crank, coupler], point: [0.5000000000000001, 0.0, 0.8660254037844386], axis: [0, 1, 0]{B}}}
  - {{name: C, type: revolute, bodies: [coupler, rocker], point: [3.016007650436934, 0.0, 2.4999487505001956], axis: [0, 1, 0]{C}}}
  - {{name: D, type: revolute, bodies: [world, rocker], point: [3, 0, 0], axis: [0, 1, 0]{D}}}
initial:
  rates: {{A: 2.0}}
  project_initial: true
forces: [{forces}]
time: {{duration: {duration}}}
"""  # noqa: E501


def _four_bar(duration=1.0, gravity=True, **loads):
    keys = {k: (", " + loads[k]) if k in loads else "" for k in "ABCD"}
    forces = "{type: gravity, g: [0, 0, -9.81]}" if gravity else ""
    return parse_system(FOUR_BAR.format(**keys, forces=forces, duration=duration),
                        source="t.yaml", base_dir=SAMPLES)


def _cut(scene) -> list[str]:
    return [scene.joints[k].name for k in build_tree(scene).cut]


def _run(scene, every=0.1, rtol=1e-11):
    return simulate_system(scene, rtol=rtol, every=every, estimate=False)


def _energy(scene, samples, gravity=G) -> np.ndarray:
    """J at each sample, from the outputs alone: ½ m v² + ½ ωᵀ R J Rᵀ ω − m g·x per body, and
    ½ k (coordinate − rest)² per joint spring (the joints' reported coordinates)."""
    e = np.zeros(len(samples.t))
    for i, b in enumerate(scene.bodies):
        v, w = samples.velocity[:, i], samples.angular_velocity[:, i]
        r = quat_to_matrix(samples.orientation[:, i])
        jw = np.einsum("nij,jk,nlk->nil", r, b.inertia, r)
        e += 0.5 * b.mass * np.sum(v * v, axis=1) + 0.5 * np.einsum("ni,nij,nj->n", w, jw, w)
        e -= b.mass * samples.position[:, i] @ gravity
    for k, j in enumerate(scene.joints):
        if j.stiffness:
            e += 0.5 * j.stiffness * (samples.coordinates[k][:, 0] - j.rest) ** 2
    return e


def test_a_loop_whose_every_joint_has_a_spring_conserves_energy():
    springs = {"A": "stiffness: 4.0, rest: 0.3", "B": "stiffness: 6.0, rest: -0.2",
               "C": "stiffness: 5.0, rest: 0.25", "D": "stiffness: 3.0, rest: -0.1"}
    scene = _four_bar(duration=2.0, gravity=False, **springs)
    assert _cut(scene) == ["C"]  # every joint loaded: the cut carries its spring
    res = _run(scene, every=0.05)
    e = _energy(scene, res.samples, gravity=np.zeros(3))
    spring_c = 0.5 * 5.0 * (res.samples.coordinates[2][:, 0] - 0.25) ** 2
    assert np.ptp(spring_c) > 0.05 * np.max(np.abs(e))  # the cut's spring does work
    assert np.ptp(e) < 1e-9 * np.max(np.abs(e))
    assert res.diagnostics["energy_rel_drift"] < 1e-9  # the run's own energy counts it too


def test_a_spring_on_the_cut_joint_moves_as_the_same_spring_in_the_tree():
    spring = "stiffness: 8.0, rest: 0.4, damping: 0.3"
    in_tree = _four_bar(C=spring)
    # B and D loaded too (drives that act only after the run) leave no unloaded joint to cut
    late = "torque: 1.0, start: 50.0, end: 60.0"
    on_cut = _four_bar(C=spring, B=late, D=late)
    assert _cut(in_tree) == ["D"] and _cut(on_cut) == ["C"]
    a, b = _run(in_tree).samples, _run(on_cut).samples
    assert np.max(np.abs(a.position - b.position)) < 1e-9
    assert np.max(rotation_angle_between(a.orientation, b.orientation)) < 1e-9
    assert np.max(np.abs(a.angular_velocity - b.angular_velocity)) < 1e-8
    assert np.max(np.abs(a.coordinates[2] - b.coordinates[2])) < 1e-9
    assert np.max(np.abs(a.rates[2] - b.rates[2])) < 1e-8
    # C's reaction is its constraint force only, on the tree and on the cut: no torque about
    # the hinge (the spring's torque is not in it), the same force in the plane (where a planar
    # linkage's reactions are unique)
    assert np.max(np.abs(a.torque[:, 2, 1])) < 1e-8
    assert np.max(np.abs(b.torque[:, 2, 1])) < 1e-8
    scale = np.max(np.abs(a.force[:, 2]))
    assert np.max(np.abs(a.force[:, 2, ::2] - b.force[:, 2, ::2])) < 1e-8 * scale


def test_a_drive_on_the_cut_joint_does_the_work_it_adds():
    torque = 3.0
    scene = _four_bar(duration=1.6, A="stiffness: 2.0", B="stiffness: 5.0, rest: 0.1",
                      C=f"torque: {torque}, start: 0.2, end: 1.2", D="stiffness: 1.0")
    assert _cut(scene) == ["C"]
    s = _run(scene, every=0.1).samples
    e = _energy(scene, s)
    at = {round(float(t), 6): n for n, t in enumerate(s.t)}
    i0, i1, i2, i3 = at[0.0], at[0.2], at[1.2], at[1.6]
    work = torque * (s.coordinates[2][i2, 0] - s.coordinates[2][i1, 0])
    scale = np.max(np.abs(e))
    assert abs(work) > 0.01 * scale  # the drive does real work
    assert abs((e[i2] - e[i1]) - work) < 1e-9 * scale
    assert abs(e[i1] - e[i0]) < 1e-9 * scale and abs(e[i3] - e[i2]) < 1e-9 * scale


ROD = ("bodies:\n  rod: {mass: 1.0, inertia: [[0.085, 0, 0], [0, 0.08, 0], [0, 0, 0.006]], "
       "position: [0.3, 0.0, -0.4]}\n")
HINGE = ("{name: h, type: revolute, bodies: %s, point: [0, 0, 0], axis: [0.0, 0.6, 0.8], "
         "stiffness: 3.0, rest: 0.5, damping: 0.2, torque: 0.7, start: 0.3, end: 0.8}")
SLIDE = ("{name: p, type: prismatic, bodies: %s, point: [0.3, 0.0, -0.4], axis: [0.6, 0.0, -0.8],"
         " stiffness: 40.0, rest: 0.05, damping: 0.5, force: 2.0, start: 0.2, end: 0.6}")
TAIL = "forces: [{type: gravity, g: [0, 0, -9.81]}]\ntime: {duration: 1.0}\n"


@pytest.mark.parametrize("order", ["[world, rod]", "[rod, world]"])
@pytest.mark.parametrize("joint", ["hinge", "slide"])
def test_a_loaded_hinge_or_slide_cut_from_a_ball_or_cylinder_moves_as_in_the_tree(joint, order):
    """A ball (hinge) or cylinder (slide) joint in the tree, named so that it stays there, plus a
    loaded hinge or slide on the same axis as the loop's cut: the motion of the hinge or slide
    alone, with its load, in the tree (signs: either order of the bodies)."""
    if joint == "hinge":
        cut = HINGE % order
        holder = "{name: s, type: spherical, bodies: [world, rod], point: [0, 0, 0]}"
        rate = np.array([0.0, 0.6, 0.8]) * (1.5 if order == "[world, rod]" else -1.5)
        alone = ROD + f"joints:\n  - {cut}\ninitial: {{rates: {{h: 1.5}}}}\n" + TAIL
        both = (ROD + f"joints:\n  - {holder}\n  - {cut}\n"
                f"initial: {{rates: {{s: [{', '.join(repr(float(x)) for x in rate)}]}}}}\n" + TAIL)
    else:
        cut = SLIDE % order
        holder = ("{name: c, type: cylindrical, bodies: [world, rod], point: [0.3, 0.0, -0.4], "
                  "axis: [0.6, 0.0, -0.8]}")
        sign = 1.0 if order == "[world, rod]" else -1.0
        alone = ROD + f"joints:\n  - {cut}\ninitial: {{rates: {{p: 0.4}}}}\n" + TAIL
        both = (ROD + f"joints:\n  - {holder}\n  - {cut}\n"
                f"initial: {{rates: {{c: [0.0, {0.4 * sign}]}}}}\n" + TAIL)
    one = parse_system(alone, source="t.yaml", base_dir=SAMPLES)
    two = parse_system(both, source="t.yaml", base_dir=SAMPLES)
    assert _cut(two) == ["h" if joint == "hinge" else "p"]
    a, b = _run(one).samples, _run(two).samples
    assert np.max(np.abs(a.velocity)) > 0.1  # it moves
    assert np.max(np.abs(a.position - b.position)) < 1e-9
    assert np.max(rotation_angle_between(a.orientation, b.orientation)) < 1e-9
    assert np.max(np.abs(a.angular_velocity - b.angular_velocity)) < 1e-8
    assert np.max(np.abs(a.coordinates[0] - b.coordinates[1])) < 1e-9
    assert np.max(np.abs(a.rates[0] - b.rates[1])) < 1e-8


# a planar loop closed by a loaded slide between two bodies: hinge A, hinge B, slide P, hinge D
RRPR = """bodies:
  p: {mass: 1.0, inertia: [[0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.02]], position: [0.0, 0.0, 0.5]}
  q: {mass: 1.5, inertia: [[0.02, 0, 0], [0, 0.3, 0], [0, 0, 0.3]], position: [0.5, 0.0, 1.0]}
  r: {mass: 0.8, inertia: [[0.05, 0, 0], [0, 0.05, 0], [0, 0, 0.01]], position: [1.2, 0.0, 0.5]}
joints:
  - {name: A, type: revolute, bodies: [world, p], point: [0, 0, 0], axis: [0, 1, 0], damping: 0.1}
  - {name: B, type: revolute, bodies: [p, q], point: [0, 0, 1.0], axis: [0, 1, 0],
     stiffness: 2.0, rest: 0.1}
  - {name: P, type: prismatic, bodies: [q, r], point: [1.2, 0, 1.0], axis: [1, 0, 0],
     stiffness: 30.0, rest: 0.02, damping: 0.4, force: 1.5, start: 0.1, end: 0.5}
  - {name: D, type: revolute, bodies: [world, r], point: [1.2, 0, 0], axis: [0, 1, 0],
     torque: -0.5}
initial: {rates: {A: 1.0}, project_initial: true}
forces: [{type: gravity, g: [0, 0, -9.81]}]
time: {duration: 1.0}
"""


@pytest.mark.parametrize("case", ["four_bar", "rrpr", "hinge", "slide"])
def test_compiled_right_hand_side_with_cut_loads_equals_numpy(case):
    if case == "four_bar":
        text = FOUR_BAR.format(A=", stiffness: 4.0", B=", damping: 0.5",
                               C=", stiffness: 5.0, rest: 0.25, damping: 0.3, torque: 1.0, "
                                 "start: 0.1, end: 0.5", D=", torque: 0.2",
                               forces="{type: gravity, g: [0, 0, -9.81]}", duration=1.0)
    elif case == "rrpr":
        text = RRPR
    else:
        cut = (HINGE if case == "hinge" else SLIDE) % "[rod, world]"
        holder = ("{name: s, type: spherical, bodies: [world, rod], point: [0, 0, 0]}"
                  if case == "hinge" else
                  "{name: c, type: cylindrical, bodies: [world, rod], point: [0.3, 0.0, -0.4], "
                  "axis: [0.6, 0.0, -0.8]}")
        name = "s" if case == "hinge" else "c"
        rate = "[0.0, 0.72, 0.96]" if case == "hinge" else "[0.0, 0.4]"  # along the axis
        text = (ROD + f"joints:\n  - {holder}\n  - {cut}\n"
                f"initial: {{rates: {{{name}: {rate}}}}}\n" + TAIL)
    system, y0, _ = prepare(parse_system(text, source="t.yaml", base_dir=SAMPLES))
    assert system.tree.cut_loaded  # the case has a loaded cut joint
    ws = workspace(system.program)
    rng = np.random.default_rng(11)
    for t in (0.15, 0.7):  # inside and outside the drives' windows
        for spread in (0.0, 0.05, 0.05, 0.05):
            y = y0 + spread * rng.standard_normal(y0.size)
            tr.normalize(system.tree, y[:system.nq])
            sol = system.solve(t, y, check=False, full=False)
            want = np.concatenate([tr.qdot(system.tree, y[:system.nq], y[system.nq:]), sol.udot])
            got = np.zeros_like(y)
            assert rhs(system.program, ws, t, y, got, -1) == 0
            scale = max(1.0, float(np.abs(want).max()))
            assert np.abs(got - want).max() <= 1e-11 * scale


@pytest.mark.parametrize(("sample", "cut"), [("four_bar", ["C"]), ("slider_crank", ["C"]),
                                             ("andrews", ["E3", "E4", "E6"])])
def test_the_samples_keep_their_cut_joints(sample, cut):
    """Nothing named or loaded sits on a breadth-first cut in the samples (slider-crank's drive
    and Andrews' drive are on tree joints): the cut, and so every result, is as before."""
    assert _cut(load_system(SAMPLES / f"{sample}.yaml")) == cut


def test_a_named_or_loaded_joint_is_kept_in_the_tree_where_the_loop_allows():
    # a start named on the breadth-first cut C: exchanged for D (the last unnamed, unloaded)
    scene = parse_system(FOUR_BAR.format(A="", B="", C="", D="", forces="", duration=0.1)
                         .replace("rates: {A: 2.0}", "positions: {C: 0.01}\n  rates: {A: 2.0}"),
                         source="t.yaml", base_dir=SAMPLES)
    assert _cut(scene) == ["D"]
    # a named joint may push a loaded one onto the cut; an unloaded one goes first
    assert _cut(_four_bar(C="damping: 0.1", D="damping: 0.1")) == ["B"]
    assert _cut(_four_bar(B="damping: 0.1", C="damping: 0.1", D="damping: 0.1")) == ["C"]
    # every joint of the loop named: the cut one's start cannot be kept
    every = FOUR_BAR.format(A="", B="", C="", D="", forces="", duration=0.1).replace(
        "rates: {A: 2.0}", "rates: {A: 2.0, B: 0.0, C: 0.0, D: 0.0}")
    with pytest.raises(SceneError, match=r"t\.yaml:\d+: initial\.rates\.C: .*closes a loop"):
        build_tree(parse_system(every, source="t.yaml", base_dir=SAMPLES))
