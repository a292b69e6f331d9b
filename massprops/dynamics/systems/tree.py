"""The spanning tree in minimal joint coordinates: kinematics, CRBA mass matrix, RNEA bias.

Spatial vectors are world-frame, about the world origin O (Featherstone's notation): a motion
V = (ω, v_O), v_O the velocity of the body point at O; a force f = (n_O, f). With every
quantity in one fixed frame no transforms between bodies are needed: a child's velocity is
V_c = V_p + S u_j, its acceleration A_c = A_p + S u̇_j + Ṡ u_j, and a composite inertia is the
plain sum of its bodies' inertias. Body i's spatial inertia about O is
[[J_w - m c̃c̃, m c̃], [-m c̃, m E]] with J_w = R J Rᵀ and c its centre of mass.

Joint coordinates. A tree joint's frame is the world frame at t = 0 carried by the parent,
E = R_p R_p0ᵀ. The child is at R_c = E Q(q) R_c0, its joint point at p = c_p + R_p s_p + E d(q):
revolute Q = Rot(a, q); prismatic d = q a; cylindrical [turn, shift]; universal
Q = Rot(a0, q0) Rot(a1, q1); spherical Q a unit quaternion [w, x, y, z] (4 coordinates), its
rates u the relative angular velocity in the frame E Q that turns with the child (3),
Q̇ = ½ Q ⊗ (0, u); free (a floating base on the world): [x (3), Q (4)], c = c0 + x, R = Q R0,
rates [v_c (3) world, u (3)] with ω = Q u, Q̇ = ½ Q ⊗ (0, u).
Costs: one pass over the bodies per kinematics and RNEA call (O(n)), CRBA O(n · depth).

Why the rates of a ball or a free body turn with it: their equations are then Euler's, whose
angular velocity evolves apart from the orientation (for a free body, with no torque that
depends on it). With world-side rates the orientation's error turns ω's body components by
δθ × ω at every step; near a free body's unstable axis that one change took the tumbling
sample (separatrix.yaml, 10 s, rtol 1e-11) from 7e-10 rad to 2.5e-4 rad of the closed form
(the same DOP853 on both in scipy: 1.9e-10 against 1.0e-3 rad). Ṡ u is unchanged by the
choice: columns fixed in the child move as V_c ×, and (S u) × (S u) = 0 leaves V_p ×m S u.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import cast

import numpy as np

from massprops.dynamics.systems.model import WORLD

NQ = {"revolute": 1, "prismatic": 1, "cylindrical": 2, "universal": 2, "spherical": 4,
      "fixed": 0, "free": 7}
NV = {"revolute": 1, "prismatic": 1, "cylindrical": 2, "universal": 2, "spherical": 3,
      "fixed": 0, "free": 6}


@dataclass(frozen=True, eq=False)
class TreeJoint:
    """One tree joint: ``parent`` (WORLD or a body index) -> ``child``; ``axes`` (k, 3) in the
    joint frame (world at t = 0); ``s_parent`` the joint point in the parent's body frame (world
    at t = 0 for the world), ``s_child`` in the child's; ``rot_parent0`` R_p0; ``iq``, ``iu``
    offsets into q and u; ``source`` the scene joint's index (None: an added free joint);
    ``reversed``: the scene's first body is the tree's child (coordinates change sign)."""

    kind: str
    parent: int
    child: int
    axes: np.ndarray
    s_parent: np.ndarray
    s_child: np.ndarray
    rot_parent0: np.ndarray
    iq: int
    iu: int
    source: int | None
    reversed: bool = False

    @property
    def nq(self) -> int:
        return NQ[self.kind]

    @property
    def nv(self) -> int:
        return NV[self.kind]


EYE3 = np.eye(3)
EYE3.setflags(write=False)  # shared: a 300-body forest's outputs called np.eye half a million times


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """a × b of two 3-vectors (np.cross costs ~30 µs of axis handling per call)."""
    a0, a1, a2 = a[0], a[1], a[2]
    b0, b1, b2 = b[0], b[1], b[2]
    return np.array([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def rot(axis: np.ndarray, angle: float) -> np.ndarray:
    """Rotation matrix about the unit ``axis`` by ``angle`` rad (Rodrigues)."""
    k = skew(axis)
    return EYE3 + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


def quat_matrix(q: np.ndarray) -> np.ndarray:
    """3x3 rotation of a unit quaternion [w, x, y, z] (normalised here)."""
    w, x, y, z = q / np.sqrt(q @ q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def quat_rate(q: np.ndarray, w: np.ndarray) -> np.ndarray:
    """q̇ = ½ q ⊗ (0, w): w the angular velocity in the frame q maps from (the moving side)."""
    return 0.5 * np.array([-w @ q[1:], q[0] * w[0] + q[2] * w[2] - q[3] * w[1],
                           q[0] * w[1] + q[3] * w[0] - q[1] * w[2],
                           q[0] * w[2] + q[1] * w[1] - q[2] * w[0]])


def quat_turn(q: np.ndarray, rotvec: np.ndarray) -> np.ndarray:
    """q ⊗ exp(rotvec), normalised: q turned by the moving-side rotation vector ``rotvec``."""
    angle = float(np.sqrt(rotvec @ rotvec))
    if angle == 0.0:
        return q
    h = 0.5 * angle
    p = np.concatenate([[np.cos(h)], np.sin(h) * rotvec / angle])
    out = np.array([q[0] * p[0] - q[1:] @ p[1:],
                    *(q[0] * p[1:] + p[0] * q[1:] + cross(q[1:], p[1:]))])
    return out / np.sqrt(out @ out)


def cross_motion(v: np.ndarray, m: np.ndarray) -> np.ndarray:
    """v ×m m for spatial motions (ω, v_O)."""
    return np.concatenate([cross(v[:3], m[:3]), cross(v[3:], m[:3]) + cross(v[:3], m[3:])])


def cross_force(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """v ×f f for a spatial motion v and force f = (n_O, f)."""
    return np.concatenate([cross(v[:3], f[:3]) + cross(v[3:], f[3:]), cross(v[:3], f[3:])])


def spatial_inertia(mass: float, inertia_world: np.ndarray, com: np.ndarray) -> np.ndarray:
    """(6, 6) about the world origin, world axes."""
    c = skew(com)
    out = np.empty((6, 6))
    out[:3, :3] = inertia_world - mass * (c @ c)
    out[:3, 3:] = mass * c
    out[3:, :3] = -mass * c
    out[3:, 3:] = mass * EYE3
    return out


@dataclass(eq=False)
class Kinematics:
    """Per body: rotation (n, 3, 3) body -> world, com (n, 3), V (n, 6), A (n, 6) (with the
    accelerations given, else u̇ = 0), inertia (n, 6, 6) about O, bias (n, 6) the velocity
    product term of its joint (A = A_parent + bias + S u̇); per tree joint: S (6, nv) and the
    joint point p (3,) world. O, the point positions are measured from, is ``ref`` (3,) of
    the system's frame (`reference_point`): a world point w is at w − ref."""

    rotation: np.ndarray
    com: np.ndarray
    V: np.ndarray
    A: np.ndarray
    inertia: np.ndarray
    S: list
    point: list
    bias: np.ndarray | None = None
    ref: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))


def _joint_motion(j: TreeJoint, qj: np.ndarray, carry: np.ndarray):
    """(Q (3, 3), d (3,), axes for S as list of (kind, world vector)) of a joint at ``qj``."""
    kind, a = j.kind, j.axes
    if kind == "revolute":
        return rot(a[0], qj[0]), np.zeros(3), [("r", carry @ a[0])]
    if kind == "prismatic":
        return np.eye(3), qj[0] * a[0], [("t", carry @ a[0])]
    if kind == "cylindrical":
        w = carry @ a[0]
        return rot(a[0], qj[0]), qj[1] * a[0], [("r", w), ("t", w)]
    if kind == "universal":
        r0 = rot(a[0], qj[0])
        return r0 @ rot(a[1], qj[1]), np.zeros(3), [("r", carry @ a[0]), ("r", carry @ r0 @ a[1])]
    if kind == "spherical":  # its rates turn with the child (`joint_rates`)
        qm = quat_matrix(qj)
        moving = carry @ qm
        return qm, np.zeros(3), [("r", moving[:, k]) for k in range(3)]
    return np.eye(3), np.zeros(3), []  # fixed


def reference_point(tree, q: np.ndarray) -> np.ndarray:
    """(3,) m: the point this state's spatial vectors are about, in the system's frame: the
    first floating base's displacement x (its centre of mass then sits at its start c0), else
    the frame's origin. Each evaluation is about a point fixed in the world at that instant,
    so the equations hold as about any; a floating system pushed far by its forces keeps its
    inertias and velocities about a point among its bodies, not (d / size)² × eps off."""
    for j in tree.joints:
        if j.kind == "free":
            return np.array(q[j.iq:j.iq + 3], dtype=float)
    return np.zeros(3)


def kinematics(tree, q: np.ndarray, u: np.ndarray, udot: np.ndarray | None = None) -> Kinematics:
    """Poses, spatial velocities and accelerations of every body (one pass, tree order), about
    `reference_point`."""
    n = len(tree.bodies)
    ref = reference_point(tree, q)
    rotation, com = np.empty((n, 3, 3)), np.empty((n, 3))
    V, A, inertia = np.zeros((n, 6)), np.zeros((n, 6)), np.empty((n, 6, 6))
    biases = np.zeros((n, 6))
    S, points = [], []
    for j in tree.joints:
        body = tree.bodies[j.child]
        qj, uj = q[j.iq:j.iq + j.nq], u[j.iu:j.iu + j.nv]
        if j.parent == WORLD:  # the world's origin, seen from the reference point
            rp, cp, vp, ap = EYE3, -ref, np.zeros(6), np.zeros(6)
        else:
            rp, cp, vp, ap = rotation[j.parent], com[j.parent], V[j.parent], A[j.parent]
        if j.kind == "free":
            qm = quat_matrix(qj[3:7])
            r = qm @ body.rotation0
            c = body.com0 + (qj[0:3] - ref)
            s = np.zeros((6, 6))
            s[3:, 0:3] = EYE3
            s[0:3, 3:6] = qm  # ω = Q u[3:6]: rates that turn with the body
            s[3:, 3:6] = skew(c) @ qm
            p = c
            bias = np.concatenate([np.zeros(3), cross(uj[0:3], qm @ uj[3:6])])
        else:
            carry = rp @ j.rot_parent0.T
            qmat, d, cols = _joint_motion(j, qj, carry)
            r = carry @ qmat @ body.rotation0
            p = cp + rp @ j.s_parent + carry @ d
            c = p - r @ j.s_child
            s = np.empty((6, len(cols)))
            for k, (what, w) in enumerate(cols):
                s[:, k] = np.concatenate([w, cross(p, w)]) if what == "r" else \
                    np.concatenate([np.zeros(3), w])
            su = s @ uj if len(cols) else np.zeros(6)
            bias = cross_motion(vp, su)
            if j.kind == "universal":
                bias += cross_motion(s[:, 0] * uj[0], s[:, 1] * uj[1])
        rotation[j.child], com[j.child] = r, c
        V[j.child] = vp + (s @ uj if s.shape[1] else 0.0)
        A[j.child] = ap + bias + (s @ udot[j.iu:j.iu + j.nv] if udot is not None and s.shape[1]
                                  else 0.0)
        inertia[j.child] = spatial_inertia(body.mass, r @ body.inertia @ r.T, c)
        biases[j.child] = bias
        S.append(s)
        points.append(p)
    return Kinematics(rotation, com, V, A, inertia, S, points, biases, ref)


def with_accelerations(tree, kin: Kinematics, udot: np.ndarray) -> Kinematics:
    """``kin`` (made at u̇ = 0) with every body's A at the accelerations ``udot``: the same sums
    as `kinematics` with ``udot`` (the same numbers), without recomputing poses, velocities and
    inertias (a third of a sample's outputs on a large system)."""
    A, bias = np.zeros_like(kin.A), cast(np.ndarray, kin.bias)  # `kinematics` filled it
    for n, j in enumerate(tree.joints):
        ap = np.zeros(6) if j.parent == WORLD else A[j.parent]
        s = kin.S[n]
        A[j.child] = ap + bias[j.child] + (s @ udot[j.iu:j.iu + j.nv] if s.shape[1]
                                               else 0.0)
    return dataclasses.replace(kin, A=A)


def mass_matrix(tree, kin: Kinematics) -> np.ndarray:
    """(nv, nv) joint-space mass matrix by the composite-rigid-body algorithm."""
    comp = kin.inertia.copy()
    for j in reversed(tree.joints):
        if j.parent != WORLD:
            comp[j.parent] += comp[j.child]
    m = np.zeros((tree.nv, tree.nv))
    for k, j in enumerate(tree.joints):
        if j.nv == 0:
            continue
        f = comp[j.child] @ kin.S[k]
        m[j.iu:j.iu + j.nv, j.iu:j.iu + j.nv] = kin.S[k].T @ f
        up = tree.parent_joint[j.parent] if j.parent != WORLD else None
        while up is not None:
            anc = tree.joints[up]
            if anc.nv:
                block = kin.S[up].T @ f
                m[anc.iu:anc.iu + anc.nv, j.iu:j.iu + j.nv] = block
                m[j.iu:j.iu + j.nv, anc.iu:anc.iu + anc.nv] = block.T
            up = tree.parent_joint[anc.parent] if anc.parent != WORLD else None
    return m


def joint_rates(j: TreeJoint, qj: np.ndarray, uj: np.ndarray) -> np.ndarray:
    """A spherical tree joint's rates ``uj`` (its moving frame E Q, `tree`) as the scene gives
    them: the second body's angular velocity relative to the first in the joint frame carried
    by the first (the contract's). Ran from the scene's second body (``reversed``), the tree's
    moving frame is that carried frame already: only the sign turns. The same map takes a
    generalised force on the joint (Sᵀ f, a torque) to the scene's joint frame."""
    if j.reversed:
        return -uj
    return quat_matrix(qj) @ uj


def body_forces(tree, kin: Kinematics, fext: np.ndarray) -> np.ndarray:
    """(n, 6) the net spatial force each body needs, I A + V ×f I V, minus what acts on it
    (``fext`` (n, 6) about O): the notes' g^(c)_i = M_i ḣ_i + b_i - g_i, world, about O."""
    out = np.empty_like(fext)
    for i in range(len(tree.bodies)):
        out[i] = kin.inertia[i] @ kin.A[i] + cross_force(kin.V[i], kin.inertia[i] @ kin.V[i]) \
            - fext[i]
    return out


def transmitted(tree, net: np.ndarray) -> np.ndarray:
    """(n_joints, 6): the spatial force each tree joint passes from its parent to its child's
    subtree, the per-body ``net`` forces summed from the leaves in."""
    acc = net.copy()
    for j in reversed(tree.joints):
        if j.parent != WORLD:
            acc[j.parent] += acc[j.child]
    return np.array([acc[j.child] for j in tree.joints])


def generalized(tree, kin: Kinematics, f: np.ndarray) -> np.ndarray:
    """(nv,) Sᵀ f per joint of the transmitted forces ``f`` (n_joints, 6)."""
    tau = np.zeros(tree.nv)
    for k, j in enumerate(tree.joints):
        if j.nv:
            tau[j.iu:j.iu + j.nv] = kin.S[k].T @ f[k]
    return tau


def jacobians(tree, kin: Kinematics) -> np.ndarray:
    """(n, 6, nv): V_i = J_i u for every body."""
    jac = np.zeros((len(tree.bodies), 6, tree.nv))
    for k, j in enumerate(tree.joints):
        if j.parent != WORLD:
            jac[j.child] = jac[j.parent]
        if j.nv:
            jac[j.child][:, j.iu:j.iu + j.nv] = kin.S[k]
    return jac


def qdot(tree, q: np.ndarray, u: np.ndarray) -> np.ndarray:
    """q̇ from the rates (quaternion coordinates: ½ Q ⊗ (0, u))."""
    out = np.empty(tree.nq)
    for j in tree.joints:
        qj, uj = q[j.iq:j.iq + j.nq], u[j.iu:j.iu + j.nv]
        if j.kind == "spherical":
            out[j.iq:j.iq + 4] = quat_rate(qj, uj)
        elif j.kind == "free":
            out[j.iq:j.iq + 3] = uj[0:3]
            out[j.iq + 3:j.iq + 7] = quat_rate(qj[3:7], uj[3:6])
        else:
            out[j.iq:j.iq + j.nq] = uj
    return out


def advance(tree, q: np.ndarray, delta: np.ndarray) -> np.ndarray:
    """q moved by a tangent ``delta`` (nv,): coordinates add, quaternions turn by exp(δ) on
    their moving side (Q ⊗ exp(δ), as their rates)."""
    out = q.copy()
    for j in tree.joints:
        d = delta[j.iu:j.iu + j.nv]
        if j.kind == "spherical":
            out[j.iq:j.iq + 4] = quat_turn(q[j.iq:j.iq + 4], d)
        elif j.kind == "free":
            out[j.iq:j.iq + 3] += d[0:3]
            out[j.iq + 3:j.iq + 7] = quat_turn(q[j.iq + 3:j.iq + 7], d[3:6])
        else:
            out[j.iq:j.iq + j.nq] += d
    return out


def normalize(tree, q: np.ndarray) -> None:
    """Renormalise every quaternion coordinate of q in place."""
    for j in tree.joints:
        o = j.iq + (3 if j.kind == "free" else 0)
        if j.kind in ("spherical", "free"):
            q[o:o + 4] /= np.sqrt(q[o:o + 4] @ q[o:o + 4])
