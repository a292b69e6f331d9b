"""The Newton-Euler right-hand side of one rigid body in plain numpy, as a scipy user would write
it. Imports numpy only, so a stand-alone scipy process can use it without loading massprops.

State y : (13,) float64 in the principal frame, like massprops' kernels: [r (3) m, v (3) m/s,
world, of the centre of mass; q (4) principal -> world, [w, x, y, z]; omega' (3) rad/s, principal
frame]. Equations: m r̈ = f (world); J' ω̇' + ω' × J' ω' = n' (J' = diag(moments));
q̇ = ½ q ⊗ (0, ω'). The rotation matrix is the unit-quaternion formula: scipy's integrators know
nothing of |q| = 1 and nothing here renormalises q.
"""

from __future__ import annotations

import numpy as np


def quat_matrix(q) -> np.ndarray:
    """(3, 3) rotation matrix of the quaternion q (4,) [w, x, y, z] (taken as unit)."""
    q0, q1, q2, q3 = q
    return np.array([
        [1 - 2 * (q2 * q2 + q3 * q3), 2 * (q1 * q2 - q0 * q3), 2 * (q1 * q3 + q0 * q2)],
        [2 * (q1 * q2 + q0 * q3), 1 - 2 * (q1 * q1 + q3 * q3), 2 * (q2 * q3 - q0 * q1)],
        [2 * (q1 * q3 - q0 * q2), 2 * (q2 * q3 + q0 * q1), 1 - 2 * (q1 * q1 + q2 * q2)]])


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a × b of two (3,) vectors (np.cross costs ~10 µs per call on 3-vectors: written out)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


class NumpyRhs:
    """ẏ(t, y) for constant force terms already in the frames the equations use.

    mass : kg. moments : (3,) kg·m², principal. force : (3,) N, world, constant (gravity m·g and
    world forces). torque : (3,) N·m, principal, constant (body torques and the moments of body
    forces). torque_world : (3,) N·m, world. body_force : (3,) N, principal. world_forces,
    world_arms : (k, 3) world forces applied off the COM and their lever arms (m, principal)
    (the forces are in ``force`` too; only their moments are added here). springs : list of
    (anchor (3,) m world, arm (3,) m principal, stiffness N/m, rest_length m, damping N·s/m).
    drag_linear : N·s/m. drag_angular : N·m·s.
    """

    def __init__(self, mass, moments, force, torque, torque_world=(0, 0, 0),
                 body_force=(0, 0, 0), world_forces=(), world_arms=(), springs=(),
                 drag_linear=0.0, drag_angular=0.0):
        self.mass = float(mass)
        self.moments = [float(i) for i in moments]
        self.force = np.asarray(force, dtype=float)
        self.torque = np.asarray(torque, dtype=float)
        self.torque_world = np.asarray(torque_world, dtype=float)
        self.body_force = np.asarray(body_force, dtype=float)
        self.world_forces = np.asarray(world_forces, dtype=float).reshape(-1, 3)
        self.world_arms = np.asarray(world_arms, dtype=float).reshape(-1, 3)
        self.springs = [(np.asarray(a, dtype=float), np.asarray(s, dtype=float), float(k),
                         float(rest), float(c), bool(np.any(s)))
                        for a, s, k, rest, c in springs]
        self.drag_linear, self.drag_angular = float(drag_linear), float(drag_angular)
        self.has_body_force = bool(np.any(self.body_force))
        self.has_torque_world = bool(np.any(self.torque_world))
        self.needs_matrix = bool(len(self.world_forces) or self.springs or self.has_body_force
                                 or self.has_torque_world)

    def as_dict(self) -> dict:
        """JSON-ready constructor arguments (a stand-alone process rebuilds the model from it)."""
        return {"mass": self.mass, "moments": self.moments, "force": self.force.tolist(),
                "torque": self.torque.tolist(), "torque_world": self.torque_world.tolist(),
                "body_force": self.body_force.tolist(),
                "world_forces": self.world_forces.tolist(),
                "world_arms": self.world_arms.tolist(),
                "springs": [[a.tolist(), s.tolist(), k, rest, c]
                            for a, s, k, rest, c, _ in self.springs],
                "drag_linear": self.drag_linear, "drag_angular": self.drag_angular}

    def __call__(self, t: float, y: np.ndarray) -> np.ndarray:
        r, v, w = y[0:3], y[3:6], y[10:13]
        q0, q1, q2, q3, w0, w1, w2 = y[6:13].tolist()  # scalars: numpy scalar maths is slower
        f = self.force - self.drag_linear * v if self.drag_linear else self.force
        n = self.torque - self.drag_angular * w if self.drag_angular else self.torque
        if self.needs_matrix:
            a = quat_matrix((q0, q1, q2, q3))
            if self.has_body_force:
                f = f + a @ self.body_force
            if self.has_torque_world:
                n = n + a.T @ self.torque_world
            for f_w, arm in zip(self.world_forces, self.world_arms):
                n = n + cross(arm, a.T @ f_w)
            for anchor, arm, k, rest, c, has_arm in self.springs:
                f_s = spring_force(r, v, w, a, anchor, arm, k, rest, c)
                f = f + f_s
                if has_arm:
                    n = n + cross(arm, a.T @ f_s)
        qdot = [-0.5 * (q1 * w0 + q2 * w1 + q3 * w2), 0.5 * (q0 * w0 + q2 * w2 - q3 * w1),
                0.5 * (q0 * w1 + q3 * w0 - q1 * w2), 0.5 * (q0 * w2 + q1 * w1 - q2 * w0)]
        i0, i1, i2 = self.moments
        n0, n1, n2 = n.tolist()
        wdot = [(n0 - (i2 - i1) * w1 * w2) / i0, (n1 - (i0 - i2) * w2 * w0) / i1,
                (n2 - (i1 - i0) * w0 * w1) / i2]
        return np.concatenate([v, f / self.mass, qdot, wdot])


def spring_force(r, v, w, a, anchor, arm, k, rest, c) -> np.ndarray:
    """World force (3,) N of a spring-damper from ``anchor`` to the body point at ``arm``:
    rest 0: -k d - c ḋ (isotropic); else -(k (L - rest) + c L̇) d/L."""
    d = r + a @ arm - anchor
    d_dot = v + a @ cross(w, arm)
    if rest == 0.0:
        return -k * d - c * d_dot
    length = np.sqrt(d @ d)
    if length == 0.0:
        return np.zeros(3)
    u = d / length
    return -(k * (length - rest) + c * (u @ d_dot)) * u
