"""Universal and cylindrical joints as cut joints (closing a loop), against the same joints in
the tree. A ball joint in the tree plus a cut joint at the same point leaves exactly the motion
of the cut joint alone: if the cut's constraint rows were wrong (a wrong axis, a sign, a missing
row), the projection would hold the body somewhere else or let it move where it may not."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from massprops.dynamics.systems.run import simulate_system
from massprops.dynamics.systems.scene import parse_system
from massprops.rotation import (
    matrix_to_quat,
    quat_from_axis_angle,
    quat_to_matrix,
    rotation_angle_between,
)

SAMPLES = Path(__file__).resolve().parent.parent / "sample_scenes"
TAIL = "forces: [{type: gravity, g: [0, 0, -9.81]}]\ntime: {duration: 1.0}\n"


def _run(text: str):
    scene = parse_system(text, source="t.yaml", base_dir=SAMPLES)
    return simulate_system(scene, rtol=1e-11, every=0.1, estimate=False)


def _vec(v) -> str:
    return "[" + ", ".join(repr(float(x)) for x in v) + "]"


def _rod(rotation: np.ndarray, com: np.ndarray) -> str:
    # a rod 1 m long along its own z, unsymmetric so every turn shows in the motion
    return ("bodies:\n  rod: {mass: 1.0, inertia: [[0.085, 0, 0], [0, 0.08, 0], [0, 0, 0.006]], "
            f"position: {_vec(com)}, orientation: {_vec(matrix_to_quat(rotation))}}}\n")


def _same_motion(a, b) -> None:
    sa, sb = a.samples, b.samples
    assert np.max(np.abs(sa.position - sb.position)) < 1e-9
    assert np.max(rotation_angle_between(sa.orientation[:, 0], sb.orientation[:, 0])) < 1e-9
    assert np.max(np.abs(sa.angular_velocity - sb.angular_velocity)) < 1e-8


def test_universal_cut_joint_on_a_ball_joint_moves_as_the_universal_joint():
    tilt = quat_to_matrix(quat_from_axis_angle(np.array([1.0, 1.0, 0.0]) / np.sqrt(2), 0.6))
    body = _rod(tilt, tilt @ np.array([0.0, 0.0, -0.5]))
    a0, a1 = np.array([1.0, 0, 0]), np.array([0.0, 0.8, 0.6])  # perpendicular in the assembly
    universal = ("  - {name: u, type: universal, bodies: [world, rod], point: [0, 0, 0], "
                 f"axes: [{_vec(a0)}, {_vec(a1)}]}}\n")
    alone = _run(body + "joints:\n" + universal + "initial: {rates: {u: [1.5, 2.0]}}\n" + TAIL)
    omega = 1.5 * a0 + 2.0 * a1  # the universal joint's rates as an angular velocity
    both = _run(body + "joints:\n  - {name: s, type: spherical, bodies: [world, rod], "
                "point: [0, 0, 0]}\n" + universal
                + f"initial: {{rates: {{s: {_vec(omega)}}}}}\n" + TAIL)
    d = both.diagnostics
    assert d["degrees_of_freedom"] == 2 and d["redundant_constraints"] == 3
    assert d["constraint_residual"]["position"] < 1e-12
    assert np.max(np.abs(alone.samples.velocity)) > 0.5  # it does move
    _same_motion(both, alone)
    # the two joints together carry what the universal joint carries alone
    total = both.samples.force[:, 0] + both.samples.force[:, 1]
    assert np.max(np.abs(total - alone.samples.force[:, 0])) < 1e-7


def test_cylindrical_cut_joint_on_a_ball_joint_moves_as_a_hinge():
    axis = np.array([0.0, 0.6, 0.8])
    body = _rod(np.eye(3), np.array([0.4, 0.0, -0.3]))
    hinge = _run(body + "joints:\n  - {name: h, type: revolute, bodies: [world, rod], "
                 f"point: [0, 0, 0], axis: {_vec(axis)}}}\n"
                 "initial: {rates: {h: 2.0}}\n" + TAIL)
    both = _run(body + "joints:\n  - {name: s, type: spherical, bodies: [world, rod], "
                "point: [0, 0, 0]}\n  - {name: c, type: cylindrical, bodies: [world, rod], "
                f"point: [0, 0, 0], axis: {_vec(axis)}}}\n"
                f"initial: {{rates: {{s: {_vec(2.0 * axis)}}}}}\n" + TAIL)
    d = both.diagnostics
    # ball (3 rows) + cylinder (4 rows) on 6 freedoms leave the hinge's 1; 2 rows are redundant
    assert d["degrees_of_freedom"] == 1 and d["redundant_constraints"] == 2
    _same_motion(both, hinge)
    # the cut joint's coordinates: the turn about and the shift along its axis (none)
    coords = both.samples.coordinates[1]
    assert np.allclose(coords[:, 0], hinge.samples.coordinates[0][:, 0], atol=1e-9)
    assert np.max(np.abs(coords[:, 1])) < 1e-12
    total = both.samples.torque[:, 0] + both.samples.torque[:, 1]
    assert np.max(np.abs(total - hinge.samples.torque[:, 0])) < 1e-7


def _split_coupler(text: str, weld: str) -> str:
    """The four-bar sample with its coupler cut in two equal halves welded back together by
    ``weld`` (a fixed joint, written without a point): the same mechanism, one body more, and a
    loop that now runs through a weld."""
    import yaml

    data = yaml.safe_load(text)
    coupler = data["bodies"].pop("coupler")
    b = np.array(next(j["point"] for j in data["joints"] if j["name"] == "B"))
    c = np.array(next(j["point"] for j in data["joints"] if j["name"] == "C"))
    half = 0.5 * coupler["mass"]
    r = (c - b) / 4  # each half's centre from the coupler's
    own = 0.5 * np.array(coupler["inertia"]) - half * (r @ r * np.eye(3) - np.outer(r, r))
    for name, centre in (("coupler1", b + r), ("coupler2", c - r)):
        data["bodies"][name] = {"mass": half, "inertia": own.tolist(),
                                "position": centre.tolist()}
    for joint in data["joints"]:
        joint["bodies"] = [{"coupler": "coupler1" if joint["name"] == "B" else "coupler2"}
                           .get(x, x) for x in joint["bodies"]]
    data["joints"].append(yaml.safe_load(weld))
    data["time"] = {"duration": 1.0}
    return yaml.safe_dump(data)


def test_a_weld_without_a_point_inside_a_loop_is_the_body_it_welds():
    """A fixed joint may omit its point (any point serves a weld). Inside a loop, whichever
    joint the tree cuts, the welded halves must move as the one coupler they make (a cut weld
    without a point once failed with a TypeError)."""
    import yaml

    text = (SAMPLES / "four_bar.yaml").read_text()
    data = yaml.safe_load(text)
    data["time"] = {"duration": 1.0}
    one = _run(yaml.safe_dump(data))
    for weld in ("{name: W, type: fixed, bodies: [coupler1, coupler2]}",
                 "{name: W, type: fixed, bodies: [coupler2, coupler1]}"):
        two = _run(_split_coupler(text, weld))
        assert two.diagnostics["degrees_of_freedom"] == 1
        for k in range(3):  # the joints A, B, C of both runs (the scene's order)
            assert np.max(np.abs(two.samples.coordinates[k] - one.samples.coordinates[k])) \
                < 1e-8
