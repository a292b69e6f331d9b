"""Frames at the edges of a held body's run: the pinned body's states back to the body's own
(centre of mass, principal frame), the joints' reactions, and the held body's diagnostics.

Reactions are physical quantities, from Newton and Euler applied to the body at each sample:
- force: the joint's force on the body, F = m a_com - Σ f_applied, with
  a_com = ω̇ × c + ω × (ω × c) (c the centre of mass from the held point) and ω̇ from Euler's
  equation about the held point, J_P ω̇ + ω × J_P ω = n_P (for a hinge only its axial part:
  I_axis θ̈ = n·e). It acts at the joint's point.
- torque (hinge only): the couple the hinge exerts across its axis, about its point,
  τ = J_P ω̇ + ω × J_P ω - n_P, perpendicular to the axis by construction (the drive and the
  damping about the axis are applied loads, not reactions).
- two spherical joints making a hinge share that wrench: the second (floating) one takes the
  force whose moment about the first is τ, F2 = (τ × d) / |d|², d from the first point to the
  second, with no axial part; the first takes the rest, F1 = F - F2.
World and body frames: F_body = A_bodyᵀ F_world (v_world = A_body v_body).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from massprops.dynamics.forces import force_torque
from massprops.dynamics.frames import to_world
from massprops.rotation import matrix_to_quat, quat_multiply, quat_to_matrix

__all__ = ["JointLoads", "held_diagnostics", "held_trajectory", "joint_loads"]


@dataclass(frozen=True, eq=False)
class JointLoads:
    """The reaction one joint applies to the body at the samples: ``kind`` ("spherical" or
    "revolute"); force_world, force_body (n, 3) N, acting at the joint's point; torque_world,
    torque_body (n, 3) N·m about that point, perpendicular to the hinge axis (None for a
    spherical joint, which transmits no torque)."""

    kind: str
    force_world: np.ndarray
    force_body: np.ndarray
    torque_world: np.ndarray | None = None
    torque_body: np.ndarray | None = None

    def row(self, i: int) -> dict:
        """The contract's ``final.joints`` entry at sample ``i``."""
        def vec(a):
            return None if a is None else a[i].tolist()

        return {"type": self.kind, "force_world": vec(self.force_world),
                "force_body": vec(self.force_body), "torque_world": vec(self.torque_world),
                "torque_body": vec(self.torque_body)}


def _applied(states: np.ndarray, times: np.ndarray, windows: np.ndarray, codes: np.ndarray,
             params: np.ndarray) -> np.ndarray:
    """(n, 6): `forces.force_torque` of the pinned body's loads at each state (n, 13), with the
    terms active at each time: (total force, world, N; torque about the held point, E frame).
    numpy over all samples at once, one call per pattern of active terms (the force law is
    written elementwise): a held body's reactions need no compiler."""
    active = (windows[:, 0] <= times[:, None]) & (times[:, None] < windows[:, 1])  # (n, k)
    patterns, which = np.unique(active, axis=0, return_inverse=True)
    out = np.empty((states.shape[0], 6))
    for j, pattern in enumerate(patterns):
        rows = np.flatnonzero(which.reshape(-1) == j)
        loads = force_torque(states[rows].T, 6, pattern, codes, params)
        for c in range(6):
            out[rows, c] = loads[c]
    return out


def _unit_quats(y: np.ndarray) -> np.ndarray:
    q = y[:, 6:10]
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def body_states(model, y: np.ndarray) -> np.ndarray:
    """(n, 13) [r, v, q_p, ω'] of the body itself (its centre of mass, its principal frame)
    from the pinned body's states y (n, 13)."""
    a_e = quat_to_matrix(_unit_quats(y))
    w = y[:, 10:13]
    c = model.lever
    r = y[:, 0:3] + a_e @ c
    v = y[:, 3:6] + np.einsum("nij,nj->ni", a_e, np.cross(w, c))
    body_axes = model.scene.body.principal_axes
    pinned_axes = model.pinned.principal_axes
    q_p = quat_multiply(_unit_quats(y), matrix_to_quat(pinned_axes.T @ body_axes))
    w_p = w @ (body_axes.T @ pinned_axes).T
    return np.hstack([r, v, q_p, w_p])


def held_trajectory(model, t: np.ndarray, y: np.ndarray, with_energy: bool):
    """The Trajectory of the held body (its own frames, its own energy) with the reactions."""
    traj = to_world(model.free_scene, t, body_states(model, y), model.physical, with_energy)
    return dataclasses.replace(traj, joints=joint_loads(model, t, y))


def _rates(model, t: np.ndarray, y: np.ndarray):
    """(applied force world (n, 3), torque about the point n_P (n, 3) E, ω̇' (n, 3) E,
    gyroscopic ω' × J_P ω' (n, 3) E) at the samples."""
    base = model.base
    out = _applied(y, np.asarray(t, np.float64), base.windows, base.codes, base.params)
    force, torque = out[:, 0:3], out[:, 3:6]
    j = model.inertia_point
    w = y[:, 10:13]
    gyro = np.cross(w, w @ j.T)
    if model.hold.kind == "spherical":
        wdot = (torque - gyro) / np.diag(j)
    else:
        wdot = np.zeros_like(w)
        wdot[:, 2] = torque[:, 2] / j[2, 2]
    return force, torque, wdot, gyro


def joint_loads(model, t: np.ndarray, y: np.ndarray) -> tuple[JointLoads, ...]:
    """The reaction of each joint (scene order) at the samples (t (n,), pinned states y)."""
    force, torque, wdot, gyro = _rates(model, t, y)
    c = model.lever
    w = y[:, 10:13]
    a_e = quat_to_matrix(_unit_quats(y))
    acc = np.cross(wdot, c) + np.cross(w, np.cross(w, c))
    reaction_e = model.scene.body.mass * acc - np.einsum("nji,nj->ni", a_e, force)
    to_body = model.pinned.principal_axes  # v_body = R_E v_E
    hold = model.hold

    def loads(kind, f_e, tau_e=None) -> JointLoads:
        world = np.einsum("nij,nj->ni", a_e, f_e)
        if tau_e is None:
            return JointLoads(kind, world, f_e @ to_body.T)
        return JointLoads(kind, world, f_e @ to_body.T,
                          np.einsum("nij,nj->ni", a_e, tau_e), tau_e @ to_body.T)

    if hold.kind == "spherical":
        return (loads("spherical", reaction_e),)
    couple = wdot @ model.inertia_point.T + gyro - torque
    couple[:, 2] = 0.0  # across the axis by construction; its axial part is round-off
    if hold.second_point is None:
        return (loads("revolute", reaction_e, couple),)
    d = to_body.T @ (hold.second_point - hold.point)
    second = np.cross(couple, d) / float(d @ d)
    return (loads("spherical", reaction_e - second), loads("spherical", second))


def held_diagnostics(model, y: np.ndarray, traj) -> dict:
    """constraint_drift: the largest distance (m) of a joint's point from its anchor, or angle
    (rad) of a hinge axis from its world axis, over the output samples (round-off: the motion
    holds the joints exactly). The drifts, relative to |H_P(0)|, of the angular momenta about
    the held point that the scene conserves (null when it does not):
    angular_momentum_rel_drift (the whole vector: a torque-free spherical joint),
    vertical_angular_momentum_rel_drift (gravity alone, a spherical joint),
    axial_angular_momentum_rel_drift (a heavy symmetric top's axis; a hinge nothing turns)."""
    out = {"constraint_drift": _constraint_drift(model, traj), "angular_momentum_rel_drift": None,
           "vertical_angular_momentum_rel_drift": None,
           "axial_angular_momentum_rel_drift": None}
    h_e = y[:, 10:13] @ model.inertia_point.T  # H_P, E frame
    a_e = quat_to_matrix(_unit_quats(y))
    h_world = np.einsum("nij,nj->ni", a_e, h_e)
    scale = float(np.linalg.norm(h_world[0])) or 1.0
    for name, vector, frame in model.conserved:
        if frame == "all":
            drift = np.linalg.norm(h_world - h_world[0], axis=1)
        else:
            comp = h_world @ vector if frame == "world" else h_e @ vector
            drift = np.abs(comp - comp[0])
        out[f"{name}_rel_drift"] = float(np.max(drift)) / scale
    return out


def _constraint_drift(model, traj) -> float:
    a_body = quat_to_matrix(traj.orientation)
    com = np.asarray(model.scene.body.center_of_mass, np.float64)
    worst = 0.0
    for joint in model.scene.joints:
        point = com if joint.point is None else np.asarray(joint.point, np.float64)
        where = traj.position + a_body @ (point - com)
        worst = max(worst, float(np.max(np.linalg.norm(where - joint.anchor, axis=1))))
    hold = model.hold
    if hold.kind == "revolute":
        turned = a_body @ hold.axis
        across = np.linalg.norm(np.cross(turned, hold.world_axis), axis=1)
        worst = max(worst, float(np.max(np.arctan2(across, turned @ hold.world_axis))))
    return worst
