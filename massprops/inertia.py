"""Inertia tensors: principal axes, change of axes, change of reference point.

Conventions (stated once in DESIGN.md): J = -∫ s̃ s̃ dm, so J_xx = ∫(y² + z²) dm and
J_xy = -∫ x y dm; tensors are (3, 3) float64 in kg·m². Principal moments are ascending and the
principal axes are the COLUMNS of a proper rotation R (det R = +1) with J = R diag(moments) Rᵀ.
"""

from __future__ import annotations

import numpy as np

from massprops.errors import UnphysicalInertiaError
from massprops.tolerances import AXIS_SIGN_TIE_ATOL, DEGENERATE_MOMENT_RTOL

__all__ = ["principal_axes", "rotate_inertia", "parallel_axis", "parallel_axis_to_com"]


def principal_axes(inertia: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Principal moments and axes of a symmetric inertia tensor.

    inertia : (3, 3) float, kg·m², any reference point, any axes (symmetrised before use).
    Returns (moments, R): moments (3,) float64 ascending, kg·m²; R (3, 3) float64 whose columns
    are the principal axes in the tensor's axes, det R = +1, J = R diag(moments) Rᵀ.

    Signs: each of the first two columns has its component of largest magnitude positive
    (components within ``AXIS_SIGN_TIE_ATOL`` of the largest count as tied and the first of them
    decides); the third column is col0 × col1.

    Coinciding moments (within ``DEGENERATE_MOMENT_RTOL`` of the largest): all three → R = I.
    Two → the distinct axis u is kept and the pair's plane gets a fixed basis: project the
    tensor's axes e_x, e_y, e_z onto the plane and normalise the longest projection (ties within
    ``AXIS_SIGN_TIE_ATOL``: the lowest index) to b1; b2 = u × b1. The pair is ordered by the
    index of each vector's largest component (b1 first if equal), signed by the rule above, and
    the frame is completed by col2 = col0 × col1. A tensor axis lying in the plane is therefore
    chosen as it is: a cylinder along z gets the mesh's own x and y axes, and the seed's cuboid
    (moments 8, 13, 13) gets [[.866, -.5, 0], [.5, .866, 0], [0, 0, 1]].
    """
    j = _symmetric_tensor(inertia, "inertia")
    moments, vectors = np.linalg.eigh(j)
    scale = float(np.max(np.abs(moments)))
    close = np.diff(moments) <= DEGENERATE_MOMENT_RTOL * scale
    if close.all():
        return moments, np.eye(3)
    if close[0]:        # moments 0 and 1 coincide: the distinct axis is the last
        first, second = _plane_basis(vectors[:, 2])
    elif close[1]:      # moments 1 and 2 coincide: the distinct axis is the first
        first, second = _orient(vectors[:, 0]), _plane_basis(vectors[:, 0])[0]
    else:
        first, second = _orient(vectors[:, 0]), _orient(vectors[:, 1])
    return moments, _proper_rotation(first, second)


def rotate_inertia(inertia: np.ndarray, rotation: np.ndarray) -> np.ndarray:
    """The same tensor expressed in other axes: J_a = A J_b Aᵀ where v_a = A v_b.

    inertia : (3, 3) float, kg·m², in frame b. rotation : (3, 3) float, the rotation A taking
    frame-b coordinates to frame-a coordinates. Returns (3, 3) float64 in frame a, same
    reference point, exactly symmetric.
    """
    j = _symmetric_tensor(inertia, "inertia")
    a = _matrix(rotation, "rotation")
    out = a @ j @ a.T
    return 0.5 * (out + out.T)


def parallel_axis(inertia_com: np.ndarray, mass: float, offset: np.ndarray) -> np.ndarray:
    """Inertia about the point at ``offset`` from the centre of mass (parallel-axis theorem).

    inertia_com : (3, 3) float, kg·m², about the COM. mass : kg. offset : (3,) float, m, the
    point minus the COM, in the tensor's axes. Returns (3, 3) float64 about that point:
    J_p = J_com + m (|d|² I - d dᵀ).
    """
    return _symmetric_tensor(inertia_com, "inertia_com") + _point_inertia(mass, offset)


def parallel_axis_to_com(inertia_point: np.ndarray, mass: float, offset: np.ndarray) -> np.ndarray:
    """Inertia about the centre of mass from the inertia about a point (the inverse shift).

    inertia_point : (3, 3) float, kg·m², about the point at ``offset`` (m, point minus COM) from
    the COM. Returns (3, 3) float64 about the COM: J_com = J_p - m (|d|² I - d dᵀ).
    """
    return _symmetric_tensor(inertia_point, "inertia_point") - _point_inertia(mass, offset)


def _point_inertia(mass: float, offset: np.ndarray) -> np.ndarray:
    """m (|d|² I - d dᵀ); the diagonal is m (d_j² + d_k²), never |d|² - d_i², so a long
    offset along one axis does not wipe out the small moment about that axis."""
    d = np.asarray(offset, dtype=np.float64)
    if d.shape != (3,):
        raise ValueError(f"offset: expected a 3-vector, got shape {d.shape}")
    squares = d * d
    out = -float(mass) * np.outer(d, d)
    out[np.diag_indices(3)] = float(mass) * (squares[[1, 2, 0]] + squares[[2, 0, 1]])
    return out


def _plane_basis(normal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Ordered, signed orthonormal basis of the plane ⟂ ``normal`` (unit), by the rule in
    ``principal_axes``: b1 projects the coordinate axis with the smallest |normal_k|."""
    mags = np.abs(normal)
    k = int(np.argmax(mags <= mags.min() + AXIS_SIGN_TIE_ATOL))
    b1 = -normal[k] * normal
    b1[k] += 1.0
    b1 /= np.linalg.norm(b1)
    b2 = np.cross(normal, b1)
    if _dominant(b2) < _dominant(b1):
        b1, b2 = b2, b1
    return _orient(b1), _orient(b2)


def _dominant(axis: np.ndarray) -> int:
    """Index of the largest-magnitude component; the first of those within
    ``AXIS_SIGN_TIE_ATOL`` of the largest, so round-off cannot change the answer."""
    mags = np.abs(axis)
    return int(np.argmax(mags >= mags.max() - AXIS_SIGN_TIE_ATOL))


def _orient(axis: np.ndarray) -> np.ndarray:
    """The axis signed so that its dominant component is positive."""
    return axis if axis[_dominant(axis)] > 0 else -axis


def _proper_rotation(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """Columns first, second, first × second, made orthonormal to round-off by one
    Newton–Schulz step R (3I - RᵀR) / 2 (eigh leaves ~1e-15 of non-orthogonality; this step
    brings it to a few 1e-16 and moves no axis by more than that)."""
    r = np.column_stack([first, second, np.cross(first, second)])
    return r @ (3.0 * np.eye(3) - r.T @ r) * 0.5


def _matrix(value: np.ndarray, name: str) -> np.ndarray:
    m = np.asarray(value, dtype=np.float64)
    if m.shape != (3, 3):
        raise UnphysicalInertiaError(f"{name}: expected a 3x3 matrix, got shape {m.shape}")
    if not np.isfinite(m).all():
        raise UnphysicalInertiaError(f"{name}: expected finite numbers, got {m.tolist()}")
    return m


def _symmetric_tensor(value: np.ndarray, name: str) -> np.ndarray:
    """(3, 3) float64, finite, symmetrised (the mean of J and Jᵀ; callers that must refuse an
    asymmetric tensor check that themselves, as RigidBody.from_inertia does)."""
    m = _matrix(value, name)
    return 0.5 * (m + m.T)
