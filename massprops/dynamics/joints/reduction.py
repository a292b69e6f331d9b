"""A held body as a free body the existing integrators can step: the equivalent pinned body.

A body turning about a fixed point P moves exactly like a free body whose centre of mass is P,
whose inertia is J_P (the inertia about P, parallel-axis theorem), acted on by the same forces at
the same body points, and whose "centre of mass" P never moves: the joint's reaction force
cancels the total force at every instant. So the scene is rewritten once:
- body: mass m, inertia J_P diagonalised in its own principal frame E (for a hinge: E has its z
  axis along the hinge and the isotropic inertia I_axis E, I_axis = e·J_P e, so that Euler's
  equations reduce to I_axis θ̈ = n·e and ω' stays on z exactly), "centre of mass" P;
- forces: gravity becomes the constant world force m g at the centre of mass (a lever about P),
  linear drag a pure damper at the centre of mass, a hinge's damping an angular drag, its drive
  a body torque about the axis;
- the JOINT row, last in the force table, sets the total force to zero (the reaction takes it)
  and, for a hinge, the torque across the axis to zero.
Every integrator then steps y = [P (fixed), 0, q_E, ω'_E] with its usual kernels; frames at the
edges (edges.py) turn that back into the body's own state, reactions and diagnostics.
"""

from __future__ import annotations

import dataclasses
import math
import weakref
from typing import cast

import numpy as np

from massprops.dynamics.exact import SYMMETRY_RTOL
from massprops.dynamics.forces import JOINT, NPAR, ForceProgram, compile_free_forces
from massprops.dynamics.joints.edges import held_diagnostics, held_trajectory
from massprops.dynamics.joints.hold import Hold, hold_of
from massprops.dynamics.joints.scene import bind_scene
from massprops.dynamics.model import (
    Drag,
    Gravity,
    InitialState,
    PointForce,
    RigidBody,
    Scene,
    Spring,
    Torque,
)
from massprops.inertia import parallel_axis, principal_axes
from massprops.rotation import canonical, matrix_to_quat, quat_multiply, quat_to_matrix

__all__ = ["JointModel", "compile_held", "model_of"]


@dataclasses.dataclass(frozen=True, eq=False)
class JointModel:
    """A held scene and its equivalent pinned body.

    scene : the held scene (initial state on the joints). hold : what the joints leave free.
    pinned : the equivalent body (principal frame E, "centre of mass" at the held point).
    inertia_point : (3, 3) kg·m², J_P about the held point in E axes (diagonal for a spherical
        joint). lever : (3,) m, the centre of mass from the held point, E axes.
    physical : the body's own force program (its forces plus the joints' drive and damping, no
        reaction), for the energy and the conservation tests. free_scene : the body without
        joints (frames at the edges). loads : (codes, params, windows) of the pinned body's
        forces without the JOINT row: what the joints' reactions balance.
    closed_form : a heavy symmetric top (`exact` solves it). conserved : ((name, (3,) unit
        vector, frame "world" or "pinned"), ...): the angular momenta about the held point the
        scene conserves. y0 : (13,) the pinned body's initial state.
    """

    scene: Scene
    hold: Hold
    pinned: RigidBody
    inertia_point: np.ndarray
    lever: np.ndarray
    physical: ForceProgram
    free_scene: Scene
    base: ForceProgram
    closed_form: bool
    conserved: tuple[tuple[str, np.ndarray, str], ...]
    y0: np.ndarray

    def to_world(self, t: np.ndarray, y: np.ndarray, with_energy: bool):
        """The pinned body's states (n, 13) as the held body's Trajectory, reactions included."""
        return held_trajectory(self, t, y, with_energy)

    def diagnostics(self, y: np.ndarray, traj) -> dict:
        """constraint_drift and the conserved momenta's drifts (see edges.held_diagnostics)."""
        return held_diagnostics(self, y, traj)


_MODELS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def model_of(scene: Scene) -> JointModel:
    """The `JointModel` of a held scene (computed once per Scene object)."""
    model = _MODELS.get(scene)
    if model is None:
        model = _MODELS[scene] = _build(scene)
    return model


def compile_held(scene: Scene) -> ForceProgram:
    """The force program of the scene's equivalent pinned body, with its JOINT row last."""
    model = model_of(scene)
    base = model.base
    row = np.zeros(NPAR)
    row[0] = 1.0 if model.hold.kind == "revolute" else 0.0
    row[1] = 1.0 if model.closed_form else 0.0
    return dataclasses.replace(
        base, codes=np.append(base.codes, JOINT), params=np.vstack([base.params, row]),
        windows=np.vstack([base.windows, [-math.inf, math.inf]]), joints=model)


# --- building the model --------------------------------------------------------------------------
def _build(scene: Scene) -> JointModel:
    scene = bind_scene(scene)  # a Scene built in code is checked here (a parsed one already was)
    body = scene.body
    hold = hold_of(scene.joints, body)
    hold = dataclasses.replace(hold, world_axis=_world_axis(scene, hold))
    com = np.asarray(body.center_of_mass, np.float64)
    j_point = parallel_axis(body.inertia_body, body.mass, hold.point - com)
    if hold.kind == "spherical":
        moments, axes = principal_axes(j_point)
    else:
        axis = cast(np.ndarray, hold.axis)  # a hinge's
        axes = _frame_with_z(axis)
        i_axis = float(axis @ j_point @ axis)
        moments = np.full(3, i_axis)
    moments = np.array(moments, dtype=np.float64)
    moments.setflags(write=False)
    pinned = RigidBody(body.mass, moments, axes, np.asarray(hold.point, np.float64), body.size)
    inertia_point = axes.T @ j_point @ axes
    lever = axes.T @ (com - hold.point)
    physical_scene = dataclasses.replace(scene, forces=scene.forces + _joint_terms(hold),
                                         joints=())
    pinned_scene = _pinned_scene(scene, hold, pinned)
    program = compile_free_forces(pinned_scene)
    closed = _is_lagrange_top(scene, hold, moments, lever)
    y0 = _initial_state(scene, hold, pinned)
    return JointModel(
        scene=scene, hold=hold, pinned=pinned, inertia_point=inertia_point, lever=lever,
        physical=compile_free_forces(physical_scene),
        free_scene=dataclasses.replace(scene, joints=()),
        base=program, closed_form=closed,
        conserved=_conserved(scene, hold, moments, lever, program), y0=y0)


def _world_axis(scene: Scene, hold: Hold) -> np.ndarray | None:
    if hold.kind != "revolute" or hold.world_axis is not None:
        return hold.world_axis
    turned = quat_to_matrix(scene.initial.orientation) @ hold.axis
    return turned / np.linalg.norm(turned)


def _frame_with_z(axis: np.ndarray) -> np.ndarray:
    """A proper rotation (columns) whose third column is the unit ``axis``."""
    helper = np.eye(3)[int(np.argmin(np.abs(axis)))]
    x = np.cross(helper, axis)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(axis, x), axis])


def _joint_terms(hold: Hold) -> tuple:
    """The hinge's own damping and drive as force terms of the body."""
    terms: list = []
    if hold.damping:
        terms.append(Drag(angular=hold.damping))
    if hold.torque:
        vec = np.array(hold.torque * cast(np.ndarray, hold.axis))  # only a hinge is driven
        vec.setflags(write=False)
        terms.append(Torque(vec, "body", hold.start, hold.end))
    return tuple(terms)


def _pinned_scene(scene: Scene, hold: Hold, pinned: RigidBody) -> Scene:
    """The scene of the equivalent pinned body: its forces at the body's own points."""
    body = scene.body
    com = np.array(body.center_of_mass, np.float64)
    com.setflags(write=False)
    forces: list = []
    for term in scene.forces + _joint_terms(hold):
        if isinstance(term, Gravity):
            weight = np.array(body.mass * np.asarray(term.g))
            weight.setflags(write=False)
            forces.append(PointForce(weight, "world", com))
        elif isinstance(term, PointForce | Spring) and term.point is None:
            forces.append(dataclasses.replace(term, point=com))
        elif isinstance(term, Drag):
            if term.angular:
                forces.append(Drag(angular=term.angular))
            if term.linear:  # -c v at the centre of mass: a damper with no spring
                forces.append(Spring(np.zeros(3), 0.0, com, 0.0, term.linear))
        else:
            forces.append(term)
    ini = scene.initial
    initial = InitialState(position=np.asarray(hold.anchor, np.float64), velocity=np.zeros(3),
                           orientation=ini.orientation, angular_velocity=ini.angular_velocity,
                           angular_velocity_frame=ini.angular_velocity_frame)
    return dataclasses.replace(scene, body=pinned, initial=initial, forces=tuple(forces),
                               joints=(), notes=())


def _initial_state(scene: Scene, hold: Hold, pinned: RigidBody) -> np.ndarray:
    """(13,) [P world, 0, q_E, ω'_E]; for a hinge ω'_E = (0, 0, θ̇) exactly."""
    ini = scene.initial
    q_e = canonical(quat_multiply(ini.orientation, matrix_to_quat(pinned.principal_axes)))
    to_world = quat_to_matrix(ini.orientation)
    w_world = to_world @ ini.angular_velocity if ini.angular_velocity_frame == "body" \
        else np.asarray(ini.angular_velocity, np.float64)
    if hold.kind == "revolute":
        w_e = np.array([0.0, 0.0, float(w_world @ cast(np.ndarray, hold.world_axis))])
    else:
        w_e = quat_to_matrix(q_e).T @ w_world
    return np.concatenate([hold.anchor, np.zeros(3), q_e, w_e])


def _symmetric_axis(moments: np.ndarray) -> int | None:
    """Index of the distinct moment of a body symmetric within SYMMETRY_RTOL, else None."""
    tol = SYMMETRY_RTOL * float(moments[2])
    if moments[1] - moments[0] <= tol and moments[2] - moments[1] > tol:
        return 2
    if moments[2] - moments[1] <= tol and moments[1] - moments[0] > tol:
        return 0
    return None


def _only_gravity(scene: Scene) -> np.ndarray | None:
    """The total field (m/s², world) when gravity is the only force, else None."""
    if not scene.forces or not all(isinstance(f, Gravity) for f in scene.forces):
        return None
    g = np.sum([np.asarray(cast(Gravity, f).g) for f in scene.forces], axis=0)
    return g if np.any(g != 0) else None


def _is_lagrange_top(scene, hold, moments, lever) -> bool:
    """A heavy symmetric top: a fixed point, gravity alone, the inertia about the point
    symmetric about the line to the centre of mass (both within SYMMETRY_RTOL)."""
    if hold.kind != "spherical" or _only_gravity(scene) is None:
        return False
    axis = _symmetric_axis(moments)
    length = float(np.linalg.norm(lever))
    if axis is None or length == 0.0:
        return False
    across = math.hypot(*[lever[i] for i in range(3) if i != axis])
    return across <= SYMMETRY_RTOL * length


def _conserved(scene, hold, moments, lever, program) -> tuple:
    """The angular momenta about the held point this scene conserves (see JointModel)."""
    out: list = []
    g = _only_gravity(scene)
    if hold.kind == "spherical":
        if not program.has_torque:
            return (("angular_momentum", np.zeros(3), "all"),)
        if g is not None:
            out.append(("vertical_angular_momentum", -g / np.linalg.norm(g), "world"))
            axis = _symmetric_axis(moments)
            if axis is not None and _is_lagrange_top(scene, hold, moments, lever):
                e3 = np.zeros(3)
                e3[axis] = 1.0
                out.append(("axial_angular_momentum", e3, "pinned"))
        return tuple(out)
    # a hinge: the momentum about its axis, when nothing turns the body about it
    if hold.damping or hold.torque:
        return ()
    if not scene.forces or g is not None and (
            abs(abs(float(g @ hold.world_axis)) - float(np.linalg.norm(g)))
            <= SYMMETRY_RTOL * float(np.linalg.norm(g)) or math.hypot(lever[0], lever[1])
            <= SYMMETRY_RTOL * float(np.linalg.norm(lever))):
        out.append(("axial_angular_momentum", np.array([0.0, 0.0, 1.0]), "pinned"))
    return tuple(out)
