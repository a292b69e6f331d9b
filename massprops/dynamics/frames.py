"""Frames at the edges of a run: the scene's world/body values <-> the principal-frame state the
integrators step, y = [r, v, q_p, omega'] (13,).

Inside, the rotation lives in the principal frame: q_p (principal -> world) and omega' (principal),
with J' = diag(I1, I2, I3). At the edges: A_body = A_p Rᵀ (R: principal axes as columns, body
frame), omega_body = R omega', omega_world = A_p omega'.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from massprops.dynamics.forces import ForceProgram, energy
from massprops.dynamics.model import Scene
from massprops.rotation import canonical, matrix_to_quat, quat_multiply, quat_to_matrix


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Sampled motion, SI, world frame unless named: t (n,) s; position (n, 3) COM; orientation
    (n, 4) body->world [w, x, y, z]; velocity (n, 3); angular_velocity (n, 3) world;
    angular_velocity_body (n, 3) body frame; angular_momentum (n, 3) world, about the COM,
    kg·m²/s; energy (n,) J or None where the scene makes it meaningless (external work);
    joints: the reaction of each joint (massprops.dynamics.joints.edges.JointLoads), scene
    order (empty for a free body)."""

    t: np.ndarray
    position: np.ndarray
    orientation: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    angular_velocity_body: np.ndarray
    angular_momentum: np.ndarray
    energy: np.ndarray | None = None
    joints: tuple = ()

    def row(self, i: int) -> dict:
        return {"t": float(self.t[i]), "position": self.position[i].tolist(),
                "orientation": self.orientation[i].tolist(), "velocity": self.velocity[i].tolist(),
                "angular_velocity": self.angular_velocity[i].tolist(),
                "angular_velocity_body": self.angular_velocity_body[i].tolist(),
                "joints": [joint.row(i) for joint in self.joints]}


def initial_free_state(scene: Scene) -> np.ndarray:
    """(13,) [r, v, q_p, omega'] at t = 0 from the free body's world/body initial values (joints
    not looked at: `massprops.dynamics.program.initial_principal_state` is the entry)."""
    body, ini = scene.body, scene.initial
    q_r = matrix_to_quat(body.principal_axes)  # principal -> body
    q_p = canonical(quat_multiply(ini.orientation, q_r))
    if ini.angular_velocity_frame == "body":
        w_p = body.principal_axes.T @ ini.angular_velocity
    else:
        w_p = quat_to_matrix(q_p).T @ ini.angular_velocity
    return np.concatenate([ini.position, ini.velocity, q_p, w_p])


def to_world(scene: Scene, t: np.ndarray, y: np.ndarray, program: ForceProgram,
             with_energy: bool) -> Trajectory:
    """Principal-frame states (n, 13) -> a Trajectory in the contract's frames (a program of
    a held body takes its pinned body's states: massprops.dynamics.joints)."""
    if program.joints is not None:
        return program.joints.to_world(t, y, with_energy)
    r_axes = scene.body.principal_axes
    q_p = y[:, 6:10] / np.linalg.norm(y[:, 6:10], axis=1, keepdims=True)
    q_body = canonical(quat_multiply(q_p, matrix_to_quat(r_axes.T)))
    w_p = y[:, 10:13]
    a_p = quat_to_matrix(q_p)
    w_world = np.einsum("nij,nj->ni", a_p, w_p)
    h_world = np.einsum("nij,nj->ni", a_p, program.inertia * w_p)
    return Trajectory(t.copy(), y[:, 0:3].copy(), q_body, y[:, 3:6].copy(), w_world,
                      w_p @ r_axes.T, h_world, energy(y, program) if with_energy else None)
