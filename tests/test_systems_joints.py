"""Systems with spherical, free, universal and redundant joints against independent truth: the
one-body closed forms (Lagrange top, torque-free body), conservation, and reactions that do no
work along a joint's free axes."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from massprops.dynamics.scene import load_scene
from massprops.dynamics.simulate import simulate
from massprops.dynamics.systems.run import simulate_system
from massprops.dynamics.systems.scene import parse_system
from massprops.rotation import quat_to_matrix, rotation_angle_between

SAMPLES = Path(__file__).resolve().parent.parent / "sample_scenes"
ROD = "{mass: 1.0, inertia: [[0.0834, 0, 0], [0, 0.0834, 0], [0, 0, 0.001]], "


def _system(text: str, every: float, rtol: float = 1e-11):
    scene = parse_system(text, source="t.yaml", base_dir=SAMPLES)
    return simulate_system(scene, rtol=rtol, every=every, estimate=False)


def _vec(v) -> str:
    return "[" + ", ".join(repr(float(x)) for x in v) + "]"


def _one_body(name: str, duration: float, every: float):
    scene = load_scene(SAMPLES / name)
    scene = dataclasses.replace(scene, time=dataclasses.replace(scene.time, duration=duration))
    return scene, simulate(scene, every=every)  # auto: the closed form, no compiler needed


def test_heavy_top_on_a_spherical_joint_equals_lagrange_closed_form():
    scene, ref = _one_body("heavy_top.yaml", 0.5, 0.1)
    q = scene.initial.orientation
    a = quat_to_matrix(q)
    body = scene.body
    com = a @ (body.center_of_mass - np.array([0.0, 0.0, -1.0]))
    rate = a @ np.array([0.0, 0.0, 30.0])
    text = (f"bodies:\n  top: {{mesh: ../sample_meshes/prism.obj, density: 1.0, position: "
            f"{_vec(com)}, orientation: {_vec(q)}}}\n"
            "joints:\n  - {name: tip, type: spherical, bodies: [world, top], point: [0, 0, 0]}\n"
            f"initial: {{rates: {{tip: {_vec(rate)}}}}}\n"
            "forces: [{type: gravity, g: [0, 0, -9.81]}]\ntime: {duration: 0.5}\n")
    s = _system(text, every=0.1).samples
    traj = ref.trajectory
    assert np.max(np.abs(s.position[:, 0] - traj.position)) < 1e-8
    assert np.max(rotation_angle_between(s.orientation[:, 0], traj.orientation)) < 1e-8
    assert np.max(np.abs(s.angular_velocity[:, 0] - traj.angular_velocity)) < 1e-7 * 30
    force = traj.joints[0].force_world
    assert np.max(np.abs(s.force[:, 0] - force)) < 1e-6 * np.max(np.abs(force))
    # the tip's coordinates: a unit quaternion, its rates the angular velocity (world frame)
    assert np.allclose(np.linalg.norm(s.coordinates[0], axis=1), 1.0, atol=1e-14)
    assert np.allclose(s.rates[0], s.angular_velocity[:, 0], atol=1e-12)


def test_spherical_rates_in_the_joint_frame_either_way_round():
    """A spherical joint's rates are the second body's angular velocity relative to the first,
    in the joint frame the first carries (the contract), whichever way the tree runs it, from a
    named start pose on: the top declared [world, top] and [top, world] moves alike, and its
    reported rates are E_aᵀ (ω_b − ω_a) with E_a = R_a R_a0ᵀ (the world's: E = I)."""
    turn = np.array([0.9, 0.3, -0.2, 0.25])
    turn /= np.linalg.norm(turn)
    w = np.array([0.4, -1.5, 6.0])  # world, at t = 0
    top = ("bodies:\n  top: {mesh: ../sample_meshes/prism.obj, density: 1.0, "
           "position: [0, 0, 1.2]}\n")
    tail = "forces: [{type: gravity, g: [0, 0, -9.81]}]\ntime: {duration: 0.5}\n"
    start = quat_to_matrix(turn)
    ahead = _system(top + "joints:\n  - {name: tip, type: spherical, bodies: [world, top], "
                    f"point: [0, 0, 0]}}\ninitial: {{positions: {{tip: {_vec(turn)}}}, "
                    f"rates: {{tip: {_vec(w)}}}}}\n" + tail, every=0.1).samples
    # reversed: the world turns by turnᵀ relative to the top, at −(Rᵀ w) in the top's frame
    back = _system(top + "joints:\n  - {name: tip, type: spherical, bodies: [top, world], "
                   f"point: [0, 0, 0]}}\ninitial: {{positions: {{tip: "
                   f"{_vec(turn * [1, -1, -1, -1])}}}, rates: {{tip: {_vec(-start.T @ w)}}}}}\n"
                   + tail, every=0.1).samples
    assert np.allclose(ahead.angular_velocity[0, 0], w, atol=1e-14)
    assert np.allclose(back.angular_velocity[0, 0], w, atol=1e-14)
    assert np.max(rotation_angle_between(ahead.orientation[:, 0], back.orientation[:, 0])) < 1e-9
    assert np.max(np.abs(ahead.angular_velocity - back.angular_velocity)) < 1e-8
    assert np.allclose(ahead.rates[0], ahead.angular_velocity[:, 0], atol=1e-12)
    carried = np.array([quat_to_matrix(q) for q in back.orientation[:, 0]])  # R_a0 = I
    want = -np.einsum("nji,nj->ni", carried, back.angular_velocity[:, 0])
    assert np.allclose(back.rates[0], want, atol=1e-12)
    assert np.allclose(back.coordinates[0][0], turn * [1, -1, -1, -1], atol=1e-15)


def test_tumbling_near_the_unstable_axis_keeps_its_phase():
    """separatrix.yaml's body spun 1e-3 off its intermediate axis, as a floating system: the
    ball's and the free joint's rates turn with the body (`tree`), so orientation errors do not
    feed its angular velocity; with world-side rates the same run at rtol 1e-9 was 1.7e-2 rad
    off the closed form at 10 s, now ~1e-8."""
    scene, ref = _one_body("separatrix.yaml", 10.0, 1.0)
    w = scene.initial.angular_velocity
    if scene.initial.angular_velocity_frame == "body":
        w = quat_to_matrix(scene.initial.orientation) @ w
    body = scene.body
    inertia = "[" + ", ".join(_vec(row) for row in body.inertia_body) + "]"
    text = (f"bodies:\n  b: {{mass: {body.mass!r}, inertia: {inertia}, position: [0, 0, 0], "
            f"orientation: {_vec(scene.initial.orientation)}}}\n"
            f"initial: {{bodies: {{b: {{angular_velocity: {_vec(w)}}}}}}}\n"
            "time: {duration: 10.0}\n")
    s = _system(text,
                every=1.0, rtol=1e-9).samples
    assert np.max(rotation_angle_between(s.orientation[:, 0], ref.trajectory.orientation)) < 1e-7


def test_floating_body_equals_torque_free_closed_form():
    scene, ref = _one_body("dzhanibekov.yaml", 2.0, 0.25)
    w = np.array([-3.2, 9.0, 2.8])
    text = ("bodies:\n  t: {mesh: ../sample_meshes/tetrahedron.obj, density: 1.0, "
            "position: [0, 0, 0]}\n"
            f"initial: {{bodies: {{t: {{velocity: [0.1, 0, 0], angular_velocity: {_vec(w)}}}}}}}\n"
            "time: {duration: 2.0}\n")
    # the flip near the intermediate axis amplifies step errors: a tight tolerance
    s = _system(text, every=0.25, rtol=1e-13).samples
    traj = ref.trajectory
    assert np.max(rotation_angle_between(s.orientation[:, 0], traj.orientation)) < 1e-8
    assert np.max(np.abs(s.angular_velocity[:, 0] - traj.angular_velocity)) < 1e-8 * 10
    assert np.allclose(s.position[:, 0, 0], 0.1 * s.t, atol=1e-12)  # free drift, no force


def test_universal_joint_reaction_does_no_work_on_its_axes():
    text = (f"bodies:\n  rod: {ROD}position: [0, 0, -0.5]}}\n"
            "joints:\n  - {name: u, type: universal, bodies: [world, rod], point: [0, 0, 0], "
            "axes: [[1, 0, 0], [0, 1, 0]]}\n"
            "initial: {positions: {u: [0.5, 0.3]}, rates: {u: [0.0, 2.0]}}\n"
            "forces: [{type: gravity, g: [0, 0, -9.81]}]\ntime: {duration: 1.0}\n")
    result = _system(text, every=0.05)
    s = result.samples
    assert result.diagnostics["energy_rel_drift"] < 1e-9
    assert result.diagnostics["degrees_of_freedom"] == 2
    q0 = s.coordinates[0][:, 0]
    for k in range(len(s.t)):
        a0 = np.array([1.0, 0, 0])  # fixed in the world
        a1 = quat_to_matrix(s.orientation[k, 0]) @ np.array([0, 1.0, 0])  # carried by the rod
        assert abs(s.torque[k, 0] @ a0) < 1e-9 and abs(s.torque[k, 0] @ a1) < 1e-9
        # the second axis is the first's turn of y by q0 (the cross's middle piece)
        expected = np.array([0.0, np.cos(q0[k]), np.sin(q0[k])])
        assert np.allclose(a1, expected, atol=1e-10)


def test_redundant_spherical_joint_on_a_hinge():
    """A hinge plus a ball joint at the same point: 3 redundant rows, 1 degree of freedom, the
    motion of the hinge alone, the reactions' sum that of the hinge alone."""
    hinge = (f"bodies:\n  rod: {ROD}position: [0, 0, -0.5]}}\n"
             "joints:\n  - {name: h, type: revolute, bodies: [world, rod], point: [0, 0, 0], "
             "axis: [0, 1, 0]}\n")
    tail = ("initial: {positions: {h: 1.0}}\nforces: [{type: gravity, g: [0, 0, -9.81]}]\n"
            "time: {duration: 1.0}\n")
    alone = _system(hinge + tail, every=0.1)
    both = _system(hinge + "  - {name: b, type: spherical, bodies: [world, rod], "
                   "point: [0, 0, 0]}\n" + tail, every=0.1)
    d = both.diagnostics
    assert d["degrees_of_freedom"] == 1 and d["redundant_constraints"] == 3
    assert np.max(np.abs(both.samples.position - alone.samples.position)) < 1e-10
    total = both.samples.force[:, 0] + both.samples.force[:, 1]
    assert np.max(np.abs(total - alone.samples.force[:, 0])) < 1e-8
    assert d["constraint_residual"]["position"] < 1e-13


def test_locked_mechanism_stays_put_and_says_so():
    text = (f"bodies:\n  rod: {ROD}position: [0.5, 0, 0]}}\n"
            "joints:\n  - {name: h, type: revolute, bodies: [world, rod], point: [0, 0, 0], "
            "axis: [0, 1, 0]}\n"
            "  - {name: tie, type: distance, bodies: [world, rod], points: [[1, 0, 1], "
            "[1, 0, 0]]}\n"
            "forces: [{type: gravity, g: [0, 0, -9.81]}]\ntime: {duration: 1.0}\n")
    result = _system(text, every=0.25)
    assert result.diagnostics["degrees_of_freedom"] == 0
    assert any("locked" in note for note in result.notes)
    s = result.samples
    assert np.all(np.isfinite(s.force)) and np.max(np.abs(s.velocity)) < 1e-12
    # statics: the tie carries the rod's weight about the hinge: m g (l/2) / l = m g / 2, up
    assert np.allclose(s.force[:, 1], [0, 0, 9.81 / 2], atol=1e-9)


def test_mesh_parts_in_one_assembly_equal_explicit_bodies():
    from massprops.dynamics.systems.scene import load_system

    meshes = load_system(SAMPLES / "mesh_pendulum.yaml")
    m = 1000 * 0.04 * 0.04 * 1.0
    across, along = m * (0.04**2 + 1.0) / 12, m * 2 * 0.04**2 / 12
    body = f"{{mass: {m!r}, inertia: [[{across!r}, 0, 0], [0, {across!r}, 0], [0, 0, {along!r}]]"
    text = (SAMPLES / "mesh_pendulum.yaml").read_text()
    text = text.replace("{mesh: parts/upper_link.obj, density: 1000}",
                        body + ", position: [0, 0, -0.5]}")
    text = text.replace("{mesh: parts/lower_link.obj, density: 1000}",
                        body + ", position: [0, 0, -1.5]}")
    explicit = parse_system(text, source="t.yaml", base_dir=SAMPLES)
    for b_mesh, b_explicit in zip(meshes.bodies, explicit.bodies):
        assert np.allclose(b_mesh.com0, b_explicit.com0, atol=1e-15)
        assert abs(b_mesh.mass - b_explicit.mass) < 1e-12 * m
    a = simulate_system(meshes, rtol=1e-10, every=0.5, estimate=False).samples
    b = simulate_system(explicit, rtol=1e-10, every=0.5, estimate=False).samples
    assert np.max(np.abs(a.position - b.position)) < 1e-9
    assert np.max(np.abs(a.force - b.force)) < 1e-8 * m * 9.81


def test_plot_draws_planar_and_spatial_mechanisms(tmp_path):
    import pytest

    pytest.importorskip("matplotlib")
    from massprops.dynamics.systems.plots import plot_system

    planar = (f"bodies:\n  rod: {ROD}position: [0, 0, -0.5]}}\n"
              "joints:\n  - {name: h, type: revolute, bodies: [world, rod], point: [0, 0, 0], "
              "axis: [0, 1, 0]}\ninitial: {positions: {h: 1.0}}\n"
              "forces: [{type: gravity, g: [0, 0, -9.81]}]\ntime: {duration: 0.5}\n")
    spatial = planar.replace("type: revolute", "type: spherical").replace(
        "positions: {h: 1.0}", "rates: {h: [0.0, 2.0, 1.0]}").replace(", axis: [0, 1, 0]", "")
    for name, text in (("planar.png", planar), ("spatial.png", spatial)):
        result = _system(text, every=0.05, rtol=1e-8)
        plot_system(result, tmp_path / name)
        assert (tmp_path / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("start, rtol", [(0.0, 1e-4), (0.0, 1e-9), (0.5, 1e-12), (0.9, 1e-10)])
def test_singular_pose_is_reported_not_run_through(start, rtol):
    """A parallelogram four-bar goes flat (all four joints on a line) when its crank has turned
    to 60° from the x axis: the loop's constraints lose rank there, and the run stops saying so,
    naming the cut joint and the time, instead of choosing a branch silently (or returning NaN).
    Coarse steps jump across the pose, fine ones land beside it (1e-8 of rank loss, where the
    rank test alone saw nothing): both report the pose's own time."""
    from massprops.errors import ComputationError

    h = 0.8660254037844386
    light = "[[0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.1]]"
    heavy = "[[0.7, 0, 0], [0, 0.7, 0], [0, 0, 0.1]]"
    text = f"""bodies:
  crank: {{mass: 1.0, inertia: {light}, position: [0.25, 0, {h / 2!r}]}}
  coupler: {{mass: 2.0, inertia: {heavy}, position: [1.5, 0, {h!r}]}}
  rocker: {{mass: 1.0, inertia: {light}, position: [2.25, 0, {h / 2!r}]}}
joints:
  - {{name: A, type: revolute, bodies: [world, crank], point: [0, 0, 0], axis: [0, 1, 0]}}
  - {{name: B, type: revolute, bodies: [crank, coupler], point: [0.5, 0, {h!r}], axis: [0, 1, 0]}}
  - {{name: C, type: revolute, bodies: [coupler, rocker], point: [2.5, 0, {h!r}], axis: [0, 1, 0]}}
  - {{name: D, type: revolute, bodies: [world, rocker], point: [2, 0, 0], axis: [0, 1, 0]}}
initial: {{positions: {{A: {start!r}}}, rates: {{A: 2.0}}, project_initial: true}}
time: {{duration: 2.0}}
"""
    with pytest.raises(ComputationError) as info:
        _system(text, every=0.1, rtol=rtol)
    message = str(info.value)
    assert "singular pose" in message and "joint(s) C" in message and "\n" not in message
    # the crank turns at a constant 2 rad/s (no loads), right-handed about +y from 60° above
    # the x axis (plus ``start``): B = (0.5, 0, h) reaches the x axis, every joint on one line,
    # after turning 60° - start
    t_flat = (np.pi / 3 - start) / 2.0
    t = float(message.split("singular pose t = ")[1].split(" s")[0])
    assert abs(t - t_flat) < 1e-5
