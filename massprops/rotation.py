"""Unit quaternions and rotation matrices, scalar-first, body -> world, stated once.

Conventions (the contract's):
- a quaternion is ``q = [w, x, y, z]`` (scalar first), unit norm;
- it rotates body -> world: ``v_world = A(q) @ v_body`` with ``A = quat_to_matrix(q)``;
- the composition ``quat_multiply(p, q)`` is the Hamilton product, so
  ``A(p ⊗ q) = A(p) @ A(q)``: apply q first, then p;
- q and -q are the same rotation; ``canonical`` picks the one with w >= 0 (output convention).

Every function is vectorised over leading axes: quaternions are ``(..., 4)``, vectors ``(..., 3)``,
matrices ``(..., 3, 3)``, angles ``(...)``; leading axes broadcast. All arrays are float64.
"""

from __future__ import annotations

import numpy as np

from massprops.errors import UsageError

__all__ = [
    "canonical",
    "matrix_to_quat",
    "quat_conjugate",
    "quat_from_axis_angle",
    "quat_from_rotvec",
    "quat_multiply",
    "quat_normalize",
    "quat_rotate",
    "quat_to_matrix",
    "quat_to_rotvec",
    "rotation_angle_between",
]

_SMALL_ANGLE = 1e-4
"""Below this rotation angle (rad) the exp map uses the series sin(θ/2)/θ = 1/2 - θ²/48: the next
term, θ⁴/3840, is 3e-20 there, far below round-off, while the closed form is still exact above."""


def _as_array(a, name: str, trailing: tuple[int, ...]) -> np.ndarray:
    """``a`` as a float64 array whose last axes are ``trailing``, or a UsageError saying so."""
    arr = np.asarray(a, dtype=np.float64)
    n = len(trailing)
    if arr.ndim < n or arr.shape[arr.ndim - n:] != trailing:
        dims = ", ".join(str(d) for d in trailing)
        raise UsageError(
            f"expected {name} of shape (..., {dims}), got {arr.shape}; "
            f"pass an array whose last axis has length {trailing[-1]}")
    return arr


def quat_multiply(p, q) -> np.ndarray:
    """Hamilton product p ⊗ q.

    p, q : (..., 4) float, [w, x, y, z]; leading axes broadcast.
    Returns (..., 4) float: the rotation "q first, then p" (A(p ⊗ q) = A(p) A(q)). Not normalised.
    """
    p = _as_array(p, "p", (4,))
    q = _as_array(q, "q", (4,))
    pw, px, py, pz = np.moveaxis(p, -1, 0)
    qw, qx, qy, qz = np.moveaxis(q, -1, 0)
    return np.stack([
        pw * qw - px * qx - py * qy - pz * qz,
        pw * qx + px * qw + py * qz - pz * qy,
        pw * qy - px * qz + py * qw + pz * qx,
        pw * qz + px * qy - py * qx + pz * qw,
    ], axis=-1)


def quat_conjugate(q) -> np.ndarray:
    """q* = [w, -x, -y, -z]: the inverse rotation for a unit q. q : (..., 4) -> (..., 4)."""
    q = _as_array(q, "q", (4,))
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def quat_normalize(q) -> np.ndarray:
    """q / |q|. q : (..., 4) float, every norm finite and non-zero (else UsageError)."""
    q = _as_array(q, "q", (4,))
    norm = np.linalg.norm(q, axis=-1, keepdims=True)
    if not (np.all(norm > 0) and np.all(np.isfinite(norm))):
        raise UsageError(
            "expected quaternions with a finite non-zero norm, got one of norm "
            f"{float(np.min(norm)) if np.any(norm == 0) else float(np.max(norm))}; "
            "a rotation needs a non-zero [w, x, y, z], e.g. [1, 0, 0, 0] for none")
    return q / norm


def canonical(q) -> np.ndarray:
    """The representative of ±q with w >= 0 (the output convention).

    q : (..., 4) float. Where w == 0 exactly, the sign makes the first non-zero of x, y, z
    positive, so the choice is deterministic. Returns (..., 4), a copy.
    """
    q = _as_array(q, "q", (4,))
    lead = q[..., 0]
    for k in (1, 2, 3):  # tie-break where all components before k are zero
        undecided = lead == 0
        lead = np.where(undecided, q[..., k], lead)
    # + 0.0 turns the -0.0 of a flipped zero component into 0.0 (it would print as "-0.0").
    return np.where((lead < 0)[..., None], -q, q) + 0.0


def quat_to_matrix(q) -> np.ndarray:
    """The rotation matrix A(q), body -> world (v_world = A v_body).

    q : (..., 4) float, non-zero; a non-unit q is treated as q/|q| (the formula is homogeneous).
    Returns (..., 3, 3) float, proper orthogonal.
    """
    q = _as_array(q, "q", (4,))
    n2 = np.sum(q * q, axis=-1)
    if not np.all(n2 > 0):
        raise UsageError("expected non-zero quaternions, got [0, 0, 0, 0]; "
                         "use [1, 0, 0, 0] for the identity rotation")
    s = 2.0 / n2
    w, x, y, z = np.moveaxis(q, -1, 0)
    xx, yy, zz = s * x * x, s * y * y, s * z * z
    xy, xz, yz = s * x * y, s * x * z, s * y * z
    wx, wy, wz = s * w * x, s * w * y, s * w * z
    rows = [
        [1.0 - yy - zz, xy - wz, xz + wy],
        [xy + wz, 1.0 - xx - zz, yz - wx],
        [xz - wy, yz + wx, 1.0 - xx - yy],
    ]
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def matrix_to_quat(matrix) -> np.ndarray:
    """The unit quaternion of a rotation matrix, canonical (w >= 0).

    matrix : (..., 3, 3) float, a rotation (body -> world). Shepperd's method with Markley's
    branch choice: of the four expressions 4w², 4x², 4y², 4z² (from the trace and the diagonal)
    the largest is used as the pivot, so the square root and the division are well conditioned
    for every rotation, including 180° turns. A slightly non-orthogonal input gives the
    normalised quaternion of a nearby rotation. Returns (..., 4) float.
    """
    r = _as_array(matrix, "matrix", (3, 3))
    r00, r11, r22 = r[..., 0, 0], r[..., 1, 1], r[..., 2, 2]
    trace = r00 + r11 + r22
    # Each candidate row is 4·(pivot component)·q; the pivot row has the largest pivot.
    candidates = np.stack([
        np.stack([1.0 + trace, r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0],
                  r[..., 1, 0] - r[..., 0, 1]], axis=-1),
        np.stack([r[..., 2, 1] - r[..., 1, 2], 1.0 + 2.0 * r00 - trace,
                  r[..., 0, 1] + r[..., 1, 0], r[..., 0, 2] + r[..., 2, 0]], axis=-1),
        np.stack([r[..., 0, 2] - r[..., 2, 0], r[..., 0, 1] + r[..., 1, 0],
                  1.0 + 2.0 * r11 - trace, r[..., 1, 2] + r[..., 2, 1]], axis=-1),
        np.stack([r[..., 1, 0] - r[..., 0, 1], r[..., 0, 2] + r[..., 2, 0],
                  r[..., 1, 2] + r[..., 2, 1], 1.0 + 2.0 * r22 - trace], axis=-1),
    ], axis=-2)
    pivots = np.stack([trace, r00, r11, r22], axis=-1)
    best = np.argmax(pivots, axis=-1)
    q = np.take_along_axis(candidates, best[..., None, None], axis=-2)[..., 0, :]
    return canonical(quat_normalize(q))


def quat_rotate(q, v) -> np.ndarray:
    """A(q) v: the vector v (..., 3) rotated by q (..., 4), body -> world. Returns (..., 3)."""
    return np.einsum("...ij,...j->...i", quat_to_matrix(q), _as_array(v, "v", (3,)))


def quat_from_rotvec(rotvec) -> np.ndarray:
    """The exponential map: the unit quaternion turning by |r| rad about r/|r| (right hand).

    rotvec : (..., 3) float, rad. Accurate to round-off for every angle, including tiny ones
    (the vector part is r·sin(θ/2)/θ, evaluated by its series below ``_SMALL_ANGLE``).
    Returns (..., 4) float, unit, w >= 0 for angles up to π.
    """
    r = _as_array(rotvec, "rotvec", (3,))
    theta = np.linalg.norm(r, axis=-1)
    small = theta < _SMALL_ANGLE
    safe = np.where(small, 1.0, theta)
    half_sinc = np.where(small, 0.5 - theta * theta / 48.0, np.sin(0.5 * safe) / safe)
    return np.concatenate([np.cos(0.5 * theta)[..., None], r * half_sinc[..., None]], axis=-1)


def quat_from_axis_angle(axis, angle) -> np.ndarray:
    """The unit quaternion turning by ``angle`` (rad, right hand) about ``axis``.

    axis : (..., 3) float, non-zero (normalised here); angle : (...) float, rad.
    Returns (..., 4) float.
    """
    a = _as_array(axis, "axis", (3,))
    norm = np.linalg.norm(a, axis=-1, keepdims=True)
    if not np.all(norm > 0):
        raise UsageError("expected a non-zero rotation axis, got [0, 0, 0]; "
                         "give the axis direction, e.g. [0, 0, 1]")
    half = 0.5 * np.asarray(angle, dtype=np.float64)[..., None]
    return np.concatenate([np.cos(half), np.sin(half) * (a / norm)], axis=-1)


def quat_to_rotvec(q) -> np.ndarray:
    """The logarithm map: the rotation vector (axis · angle, angle in [0, π]) of q.

    q : (..., 4) float, non-zero (normalised here). Uses θ = 2·atan2(|v|, |w|), accurate for tiny
    and for near-π angles alike. Returns (..., 3) float, rad.
    """
    q = canonical(quat_normalize(q))
    w = q[..., 0]
    v = q[..., 1:]
    s = np.linalg.norm(v, axis=-1)
    # θ/s -> 2/w as s -> 0; atan2 keeps its relative accuracy for tiny s, so only s == 0 is
    # special (and there w = 1).
    has_axis = s > 0
    factor = np.where(has_axis, 2.0 * np.arctan2(s, w) / np.where(has_axis, s, 1.0),
                      2.0 / np.where(has_axis, 1.0, w))
    return v * factor[..., None]


def rotation_angle_between(q1, q2) -> np.ndarray:
    """The angle (rad, in [0, π]) of the rotation taking orientation q1 to q2.

    q1, q2 : (..., 4) float, unit; leading axes broadcast. Computed as
    2·atan2(|vec(q1* ⊗ q2)|, |w(q1* ⊗ q2)|), accurate from 1e-16 rad up to π (unlike arccos of a
    dot product, which loses half the digits for small angles). Returns (...) float.
    """
    d = quat_multiply(quat_conjugate(q1), q2)
    return 2.0 * np.arctan2(np.linalg.norm(d[..., 1:], axis=-1), np.abs(d[..., 0]))
