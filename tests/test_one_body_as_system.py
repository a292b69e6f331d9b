"""A one-body scene run as a system of one body (`systems.one_body.as_system`) moves as the
one-body engine moves it, and as closed forms say.

Both engines run DOP853 at rtol 1e-11; each run's ``error_estimate`` is honest (a companion at
rtol / 20, `dynamics.accuracy`), so two faithful runs differ by at most the sum of their errors:
that sum, in each engine's own metric turned back into m, rad, m/s and rad/s, times SAFETY, is
every tolerance here. A wrong translation (a point in the wrong frame, an angular velocity not
turned to the world) misses by far more.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from massprops.dynamics.accuracy import Scales, state_error
from massprops.dynamics.scene import load_scene, parse_scene
from massprops.dynamics.simulate import simulate
from massprops.dynamics.systems.model import WORLD
from massprops.dynamics.systems.one_body import BODY, as_system
from massprops.dynamics.systems.run import simulate_system
from massprops.rotation import quat_to_matrix, rotation_angle_between

ROOT = Path(__file__).resolve().parent.parent
SCENES = ROOT / "sample_scenes"
MESHES = ROOT / "sample_meshes"
RTOL = 1e-11
EPS = float(np.finfo(float).eps)

SAFETY = 4.0
"""How far beyond the sum of the two runs' estimates a difference may go: the estimates are
honest to ~5 % (accuracy.py), and the two engines' metrics scale velocities by the largest
component (systems) or norm (one body), up to √3 apart."""

REACTION_SAFETY = 10.0
"""A reaction is m a - Σ f of the state: relative errors in ω enter twice (centripetal m ω² l)
and the orientation error turns the weight, so its relative error is a few times the state's."""

SAMPLES = {
    # name: shortened duration (s); every sample scene with `body:`
    "compound_pendulum": 2.0,  # a revolute joint: swings from upright through the bottom
    "far": 1.0,
    "heavy_top_damped": 0.005,  # 4.6e6/s damping: dop853 takes ~4600 steps
    "heavy_top_stiff": 0.1,
    "huge": 7200.0,  # the thruster's hour and as long after it
    "long_run": 5.0,  # asks splitting: no system form, both run dop853 (as every scene here)
    "needle": 0.5,
    "short_window": 1.0,
    "unstable": 0.2,
    "tiny": 0.5,  # drag
    # closed-form scenes (auto picks exact), stepped here all the same: the spherical joint's
    # only samples, and a mesh whose principal axes and COM are off the mesh frame's
    "heavy_top": 1.0,
    "gyroscope": 0.3,
    "dzhanibekov": 4.0,
    "disk": 0.2,
    "separatrix": 5.0,
}


def _shortened(scene, duration: float):
    return dataclasses.replace(scene, time=dataclasses.replace(scene.time, duration=duration))


def _scene(text: str, duration: float):
    return parse_scene(text.replace("DURATION", repr(duration)), source="scene.yaml",
                       base_dir=MESHES)


def _both(scene, samples: int = 10):
    """(one-body result, system result) of ``scene`` sampled ``samples`` times."""
    every = scene.time.duration / samples
    one = simulate(scene, integrator="dop853", rtol=RTOL, every=every)
    system = simulate_system(as_system(scene), integrator="dop853", rtol=RTOL, every=every)
    return one, system


def _agree(scene, one, system) -> dict:
    """Assert the sampled body states agree within SAFETY × the runs' errors; return the worst
    difference of each part relative to its tolerance (for the report)."""
    tr, s = one.trajectory, system.samples
    assert np.array_equal(tr.t, s.t)
    e1, e2 = one.diagnostics["error_estimate"], system.diagnostics["error_estimate"]
    assert e1 is not None and e2 is not None
    duration = scene.time.duration
    one_scale = Scales.of(scene.body.size, tr, duration)
    size2 = as_system(scene).size  # the system's metric: position / the system's size
    v2 = max(float(np.abs(s.velocity).max()), size2 / duration)
    w2 = max(float(np.abs(s.angular_velocity).max()), 1.0 / duration)
    reach = float(np.abs(tr.position).max()) + scene.body.size
    tolerances = {  # m, rad, m/s, rad/s; plus the round-off of the numbers themselves
        "position": SAFETY * (e1 * one_scale.size + e2 * size2) + 64 * EPS * reach,
        "orientation": SAFETY * (e1 + e2) + 64 * EPS,
        "velocity": SAFETY * (e1 * one_scale.velocity + e2 * v2) + 64 * EPS * v2,
        "angular_velocity": SAFETY * (e1 * one_scale.angular_velocity + e2 * w2) + 64 * EPS * w2,
    }
    diffs = {
        "position": np.linalg.norm(tr.position - s.position[:, 0], axis=1).max(),
        "orientation": rotation_angle_between(tr.orientation, s.orientation[:, 0]).max(),
        "velocity": np.linalg.norm(tr.velocity - s.velocity[:, 0], axis=1).max(),
        "angular_velocity": np.linalg.norm(tr.angular_velocity - s.angular_velocity[:, 0],
                                           axis=1).max(),
    }
    ratios = {k: float(diffs[k] / tolerances[k]) for k in diffs}
    assert max(ratios.values()) <= 1.0, (ratios, diffs, e1, e2)
    return ratios


def _reactions_agree(scene, one, system, joints=None) -> None:
    """Each joint's reaction on the body: the one-body engine's force (at the joint's point) and
    torque (about it; None for a spherical joint) against the system's, which are on the joint's
    second body (the body) at the joint's point, world frame; and the body-frame forms."""
    tr, s = one.trajectory, system.samples
    e = one.diagnostics["error_estimate"] + system.diagnostics["error_estimate"]
    weight = scene.body.mass * 9.81
    rot = quat_to_matrix(s.orientation[:, 0])  # body -> world, from the system run
    for k in joints if joints is not None else range(len(scene.joints)):
        loads = tr.joints[k]
        scale = float(np.abs(loads.force_world).max()) + weight
        tol = REACTION_SAFETY * e * scale + 1e3 * EPS * scale
        assert np.abs(loads.force_world - s.force[:, k]).max() <= tol
        body_frame = np.einsum("nji,nj->ni", rot, s.force[:, k])
        assert np.abs(loads.force_body - body_frame).max() <= tol
        torque_scale = scale * as_system(scene).size
        if loads.torque_world is None:  # a spherical joint passes no torque about its point
            assert np.abs(s.torque[:, k]).max() <= 1e3 * EPS * torque_scale
        else:
            assert np.abs(loads.torque_world - s.torque[:, k]).max() <= \
                REACTION_SAFETY * e * torque_scale + 1e3 * EPS * torque_scale


# --- every sample scene -------------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(SAMPLES))
def test_sample_scene_runs_alike(name):
    scene = _shortened(load_scene(SCENES / f"{name}.yaml"), SAMPLES[name])
    one, system = _both(scene)
    _agree(scene, one, system)
    if scene.joints:
        _reactions_agree(scene, one, system)


# --- scenes that use every translated key ---------------------------------------------------------
LOADED_MESH = """
body: {mesh: tetrahedron.obj, density: 1.0}
initial:
  position: [0.3, -0.2, 0.1]
  orientation: [0.8, 0.2, -0.4, 0.4]
  velocity: [0.1, 0.4, -0.3]
  angular_velocity: [0.7, -1.1, 2.3]
  angular_velocity_frame: body
forces:
  - {type: gravity, g: [0.5, 0, -9.81]}
  - {type: force, vector: [0, 3, 1], frame: world, point: [1, 0, 0], start: 0.1, end: 0.4}
  - {type: force, vector: [1, -2, 0], frame: body, point: [0, 2, 0]}
  - {type: force, vector: [0, 0, 4], frame: body}
  - {type: torque, vector: [0.2, 0, -0.5], frame: body, start: 0.3}
  - {type: torque, vector: [0, 0.3, 0], frame: world, end: 0.7}
  - {type: spring, anchor: [0, 0, 2], point: [0, 0, 3], stiffness: 30, rest_length: 0.5,
     damping: 0.4}
  - {type: spring, anchor: [1, 1, 0], stiffness: 5, damping: 0.2}
time: {duration: DURATION}
"""
"""The tetrahedron's COM (1/4, 1/2, 3/4) and principal axes are off its mesh frame: every point
and every body-frame vector has to be converted to be right."""

DRIVEN_HINGE = """
body: {mesh: tetrahedron.obj, density: 1.0}
joints:
  - {type: revolute, point: [0, 0, 0], axis: [0, 1, 1], anchor: [0, 0, 1], damping: 0.05,
     torque: 0.4, start: 0.2, end: 0.6}
initial:
  orientation: [0.9, 0.3, 0.1, -0.2]
  angular_velocity: [0, 1.5, 1.5]
  angular_velocity_frame: body
forces:
  - {type: gravity, g: [0, 0, -9.81]}
time: {duration: DURATION}
"""
"""A hinge through a vertex, its world axis where the orientation turns the body axis (no
world_axis given), spinning about it from the start (a body-frame rate), damped and driven."""

TWO_POINT_HINGE = """
body: {mesh: tetrahedron.obj, density: 1.0}
joints:
  - {type: spherical, point: [0, 0, 0], anchor: [0, 0, 0]}
  - {type: spherical, point: [1, 0, 0], anchor: [1, 0, 0]}
initial:
  angular_velocity: [2.0, 0, 0]
forces:
  - {type: gravity, g: [2.0, 0.3, -9.81]}
time: {duration: DURATION}
"""
"""Two spherical joints at distinct points: the one-body hinge; the systems engine cuts the
second and finds its axial row redundant (rank). Gravity has a part along the hinge (x): an
axial load for the bearings to share."""

CUSTOM = {"loaded_mesh": (LOADED_MESH, 1.0), "driven_hinge": (DRIVEN_HINGE, 1.0),
          "two_point_hinge": (TWO_POINT_HINGE, 1.0)}


@pytest.mark.parametrize("name", sorted(CUSTOM))
def test_every_key_runs_alike(name):
    text, duration = CUSTOM[name]
    scene = _scene(text, duration)
    one, system = _both(scene, samples=20)
    _agree(scene, one, system)
    if scene.joints:
        _reactions_agree(scene, one, system)


def test_two_point_hinge_splits_the_load_as_one_body_does():
    """The one-body hinge of two spherical joints puts the whole axial load on the first and
    none on the second (a locating and a floating bearing); the system's minimum-norm multipliers
    of its cut (second) joint give the same split, each joint's own force agreeing."""
    scene = _scene(TWO_POINT_HINGE, 0.5)
    one, system = _both(scene)
    axis = np.array([1.0, 0.0, 0.0])  # the hinge line, world (its anchors)
    weight = scene.body.mass * 9.81
    # the COM turns about the fixed line: no acceleration along it, so the bearings hold -m g_x
    assert np.abs(system.samples.force[:, 0] @ axis + scene.body.mass * 2.0).max() \
        <= 1e-9 * weight
    assert np.abs(system.samples.force[:, 1] @ axis).max() <= 1e-9 * weight
    assert system.diagnostics["redundant_constraints"] == 1
    _reactions_agree(scene, one, system, joints=[0, 1])


# --- closed forms ---------------------------------------------------------------------------------
FREE_MESH = """
body: {mesh: tetrahedron.obj, density: 1.0}
initial:
  position: [2.0, -1.0, 0.5]
  orientation: [0.5, 0.5, -0.5, 0.5]
  velocity: [0.3, -0.7, 1.1]
  angular_velocity: [-3.2, 9.0, 2.8]
  angular_velocity_frame: body
time: {duration: DURATION}
"""


def test_free_body_keeps_its_momenta_and_energy():
    """With no force the centre of mass moves uniformly (to round-off), and the angular
    momentum about it, R J Rᵀ ω (world), and the kinetic energy stay constant (to the run's
    error); the initial ω given in body axes must be turned to the world's to start right."""
    duration = 2.0
    scene = _scene(FREE_MESH, duration)
    system = simulate_system(as_system(scene), integrator="dop853", rtol=RTOL, every=0.1)
    s = system.samples
    v0 = np.array([0.3, -0.7, 1.1])
    p0 = np.array([2.0, -1.0, 0.5])
    assert np.abs(s.velocity[:, 0] - v0).max() <= 8 * EPS * np.linalg.norm(v0)
    expected = p0 + s.t[:, None] * v0
    assert np.abs(s.position[:, 0] - expected).max() <= 64 * EPS * np.abs(expected).max()

    j_com = np.array([[39, 2, 3], [2, 30, 6], [3, 6, 15]]) / 80  # the tetrahedron, by hand
    rot = quat_to_matrix(s.orientation[:, 0])
    j_world = rot @ j_com @ rot.transpose(0, 2, 1)
    h = np.einsum("nij,nj->ni", j_world, s.angular_velocity[:, 0])
    energy = 0.5 * np.einsum("ni,ni->n", s.angular_velocity[:, 0], h)
    w0_body = np.array([-3.2, 9.0, 2.8])
    h0 = quat_to_matrix([0.5, 0.5, -0.5, 0.5]) @ j_com @ w0_body
    e = system.diagnostics["error_estimate"]
    w_scale = float(np.abs(s.angular_velocity).max())
    j_norm = float(np.linalg.eigvalsh(j_com).max())
    # δω ≤ e w_scale and δangle ≤ e (the metric), so |δ(R J Rᵀ ω)| ≤ |J| (δω + 2 |ω| δangle)
    # and |δE| ≤ |ω| |δH|
    h_tol = SAFETY * e * 3 * j_norm * w_scale
    assert np.abs(h - h0).max() <= h_tol
    assert np.abs(energy - 0.5 * w0_body @ j_com @ w0_body).max() <= h_tol * w_scale


ROD_PENDULUM = """
body: {mass: 2.0, inertia: [[0.16673333333333333, 0, 0], [0, 0.16673333333333333, 0],
                            [0, 0, 1.3333333333333333e-4]]}
joints:
  - {type: revolute, point: [0, 0, 0.5], axis: [1, 0, 0], anchor: [0, 0, 1]}
initial:
  orientation: [0.955336489125606, 0.29552020666133955, 0, 0]
forces:
  - {type: gravity, g: [0, 0, -9.81]}
time: {duration: DURATION}
"""
"""A 1 m rod hung from its end, released from rest 0.6 rad from the bottom (a turn about x)."""


def test_pendulum_pivot_reaction_and_energy():
    """Released from rest, the rod's centre of mass starts on its circle with no centripetal
    part: α = -m g l sin θ0 / I_P about x, a_c = α x × r, so the hinge pushes F = m a_c - m g;
    the energy is conserved through the swing."""
    scene = _scene(ROD_PENDULUM, 1.0)
    one, system = _both(scene)
    m, g, arm, theta0 = 2.0, 9.81, 0.5, 0.6
    i_pivot = 0.16673333333333333 + m * arm * arm
    r = arm * np.array([0.0, math.sin(theta0), -math.cos(theta0)])  # pivot -> COM, world
    alpha = -m * g * arm * math.sin(theta0) / i_pivot
    force = m * alpha * np.cross([1.0, 0, 0], r) - m * np.array([0, 0, -g])
    assert np.abs(system.samples.force[0, 0] - force).max() <= 1e-12 * m * g
    assert np.abs(one.trajectory.joints[0].force_world[0] - force).max() <= 1e-12 * m * g
    assert system.diagnostics["energy_rel_drift"] <= 1e-9
    _agree(scene, one, system)
    _reactions_agree(scene, one, system)


# --- the translation itself and what it refuses -------------------------------------------------
def test_translation_of_the_body_and_its_start():
    """The body: its mass, the inertia about the COM in the mesh axes (the tetrahedron's closed
    form, exactly symmetric), placed at the scene's COM and orientation; a free body's start as
    world velocities; a hinge's start as its rate about the world axis."""
    scene = _scene(FREE_MESH, 1.0)
    system = as_system(scene)
    (body,) = system.bodies
    assert body.name == BODY and body.mass == pytest.approx(1.0, rel=1e-14)
    assert np.array_equal(body.inertia, body.inertia.T)
    j_com = np.array([[39, 2, 3], [2, 30, 6], [3, 6, 15]]) / 80
    assert np.abs(body.inertia - j_com).max() <= 1e-14
    assert np.array_equal(body.com0, [2.0, -1.0, 0.5])
    rot0 = quat_to_matrix([0.5, 0.5, -0.5, 0.5])
    assert np.allclose(body.rotation0, rot0, rtol=0, atol=1e-15)
    v, w = system.initial.velocities[BODY]
    assert np.array_equal(v, [0.3, -0.7, 1.1])
    assert np.allclose(w, rot0 @ [-3.2, 9.0, 2.8], rtol=0, atol=1e-14)
    assert system.initial.project is False and not system.joints

    hinge = as_system(_scene(DRIVEN_HINGE, 1.0))
    (joint,) = hinge.joints
    assert (joint.name, joint.kind, joint.a, joint.b) == ("j0", "revolute", WORLD, 0)
    assert np.array_equal(joint.point, [0, 0, 1])
    assert (joint.damping, joint.drive, joint.start, joint.end) == (0.05, 0.4, 0.2, 0.6)
    turned = quat_to_matrix(np.array([0.9, 0.3, 0.1, -0.2]) / math.sqrt(1.15)) @ \
        (np.array([0, 1, 1]) / math.sqrt(2))
    assert np.allclose(joint.axes[0], turned, rtol=0, atol=1e-15)
    assert hinge.initial.rates == {"j0": pytest.approx((1.5 * math.sqrt(2),), rel=1e-14)}
    assert hinge.initial.velocities == {}


def test_every_kind_of_force_and_joint_has_a_translation():
    """`as_system` translates each force and joint kind a one-body scene can name; its last
    branch takes the last kind (drag, revolute). A kind added to the scene must be translated
    there, and listed here."""
    from massprops.dynamics.joints.scene import JOINT_TYPES
    from massprops.dynamics.scene import FORCE_TYPES

    assert set(FORCE_TYPES) == {"gravity", "force", "torque", "spring", "drag"}
    assert set(JOINT_TYPES) == {"spherical", "revolute"}
    text = LOADED_MESH.replace("time:", "  - {type: drag, linear: 0.3, angular: 0.1}\ntime:")
    system = as_system(_scene(text, 1.0))
    assert (len(system.forces), len(system.springs), len(system.drags)) == (5, 2, 1)
    assert np.allclose(system.gravity, [0.5, 0, -9.81], rtol=0, atol=0)
    (drag,) = system.drags
    assert (drag.body, drag.linear, drag.angular) == (0, 0.3, 0.1)
    hinge = as_system(_scene(DRIVEN_HINGE, 1.0)).joints
    assert [j.kind for j in hinge] == ["revolute"]
    balls = as_system(_scene(TWO_POINT_HINGE, 1.0)).joints
    assert [j.kind for j in balls] == ["spherical", "spherical"]


def test_radau_takes_a_stiff_spinning_top_in_whole_steps():
    """heavy_top_damped.yaml: a 1e8 N/m spring and a 1e7 N·s/m damper hold a top spinning at
    200 rad/s. The spring's Jacobian turns with the body within a step, so Newton with J at the
    step's start does not converge; with the stage Jacobians J(y + Z_s) every step does
    (without them the system took four pieces a step, and 42,000 of 80,000 pieces were tried in
    vain). The run agrees with dop853 stepping at the stiff rate's stability limit (another
    step loop, thousands of steps) within both runs' estimates."""
    from massprops.dynamics.program import compile_forces
    from massprops.dynamics.simulate import default_step

    scene = _shortened(load_scene(SCENES / "heavy_top_damped.yaml"), 0.05)
    every = scene.time.duration / 10
    implicit = simulate(scene, integrator="implicit", every=every)
    explicit = simulate(scene, integrator="dop853", rtol=RTOL, every=every)
    h = default_step(scene, compile_forces(scene), stiff=True)  # the scene's
    steps = math.ceil(scene.time.duration / h * (1 - 1e-12))  # nominal steps, none cut
    assert implicit.rejected == 0 and implicit.steps == steps
    assert explicit.steps > 20 * steps  # dop853 is held at the stiff rate's limit
    scales = Scales.of(scene.body.size, explicit.trajectory, scene.time.duration)
    estimates = implicit.diagnostics["error_estimate"] + explicit.diagnostics["error_estimate"]
    assert state_error(implicit.trajectory, explicit.trajectory, scales) <= SAFETY * estimates
