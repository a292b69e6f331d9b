"""Signed volumes, area vectors, exact flatness and winding numbers of triangle surfaces: the
geometric facts the health check and the repairs read off a mesh. numpy only, no loop per face."""

from __future__ import annotations

from typing import cast

import numpy as np

from massprops.parallel import in_halves
from massprops.tolerances import EPS, ON_SURFACE_RTOL

_CHUNK = 1 << 15  # rows per block of chunked passes: temporaries stay in cache, not in new pages


def signed_volumes6(vertices: np.ndarray, faces: np.ndarray | None, origin: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Per triangle: 6 × the signed volume of the tetrahedron (origin, triangle), m³ (m,) float64,
    and whether its area is exactly zero (m,) bool. ``faces`` None means the soup layout (see
    `is_soup`). Taken about a point near the mesh, so round-off scales with the mesh's size."""
    m = vertices.shape[0] // 3 if faces is None else faces.shape[0]
    det = np.empty(m)
    flat = np.empty(m, bool)
    step = _CHUNK // 2  # many operations per block: a block and its temporaries stay in L2
    v9 = vertices.reshape(-1, 9) if faces is None else None

    def fill(start: int, stop: int) -> None:
        for lo in range(start, stop, step):
            hi = min(lo + step, stop)
            if v9 is not None:
                c = v9[lo:hi].T.copy()  # (9, c): contiguous rows
            else:
                rows = cast(np.ndarray, faces)[lo:hi]  # v9 is None only when faces is given
                c = np.take(vertices, rows, axis=0).reshape(-1, 9).T.copy()
            x0, y0, z0, x1, y1, z1, x2, y2, z2 = c
            x1 -= x0
            y1 -= y0
            z1 -= z0
            x2 -= x0
            y2 -= y0
            z2 -= z0
            x0 -= origin[0]
            y0 -= origin[1]
            z0 -= origin[2]
            nx, ny, nz = y1 * z2, z1 * x2, x1 * y2  # n = (p1 - p0) × (p2 - p0), written out
            nx -= z1 * y2
            ny -= x1 * z2
            nz -= y1 * x2
            d = det[lo:hi]
            np.multiply(x0, nx, out=d)
            d += y0 * ny
            d += z0 * nz
            f = flat[lo:hi]
            np.equal(nx, 0, out=f)
            f &= ny == 0
            f &= nz == 0

    in_halves(fill, m, step)
    return det, flat


def area_vector_sums(vertices: np.ndarray, faces: np.ndarray) -> tuple[np.ndarray, float]:
    """Σ of the triangles' area vectors (3,) m² (zero for a closed surface) and Σ of their areas."""
    total, area = np.zeros(3), 0.0
    for lo in range(0, faces.shape[0], _CHUNK):
        f = faces[lo : lo + _CHUNK]
        p0 = np.take(vertices, f[:, 0], axis=0)
        n = np.cross(np.take(vertices, f[:, 1], axis=0) - p0,
                     np.take(vertices, f[:, 2], axis=0) - p0)
        total += n.sum(axis=0) / 2
        area += float(np.linalg.norm(n, axis=1).sum()) / 2
    return total, area


def exactly_flat(vertices: np.ndarray, faces: np.ndarray) -> np.ndarray:
    """(t,) bool: whether each triangle (``faces`` (t, 3) indices into ``vertices``) has exactly
    zero area, its corners coinciding or on one line, decided for the stored float64 values.

    A float cross product can round a collinear triangle to a tiny non-zero normal and a thin one
    to zero, so only a filter runs in floats: a triangle whose computed normal is above a bound of
    that rounding is not flat; the few below it are decided in exact rational arithmetic (every
    float is a rational).
    """
    p0 = np.take(vertices, faces[:, 0], axis=0)
    e1 = np.take(vertices, faces[:, 1], axis=0) - p0
    e2 = np.take(vertices, faces[:, 2], axis=0) - p0
    normal = np.abs(np.cross(e1, e2))
    # |computed - exact| per component <= (3u + O(u²)) (|a b| + |c d|) with the edges' own
    # rounding (u each) included; 8u leaves a margin, and the exact test below settles the rest.
    yzx, zxy = [1, 2, 0], [2, 0, 1]
    scale = np.abs(e1[:, yzx] * e2[:, zxy]) + np.abs(e1[:, zxy] * e2[:, yzx])
    maybe = np.flatnonzero(np.all(normal <= 8 * EPS * scale, axis=1))
    out = np.zeros(faces.shape[0], bool)
    from fractions import Fraction  # only meshes open at first get here: keep start-up lean

    for f in maybe:
        a, b, c = ([Fraction(x) for x in vertices[i]] for i in faces[f])
        u, w = [q - p for p, q in zip(a, b)], [q - p for p, q in zip(a, c)]
        out[f] = (u[1] * w[2] == u[2] * w[1] and u[2] * w[0] == u[0] * w[2]
                  and u[0] * w[1] == u[1] * w[0])
    return out


def winding_numbers(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(q,) winding number of each point (q, 3) w.r.t. triangles (t, 3, 3): Σ signed solid angle
    / 4π, Van Oosterom & Strackee (1983). 1 inside a closed outward surface, 0 outside, -1 inside
    an inward one; not an integer for an open surface. NaN for a point on one of the triangles
    (to ``ON_SURFACE_RTOL`` relative), where the solid angle jumps by 4π and the sign of a zero
    decides."""
    q = points.shape[0]
    w = np.zeros(q)
    on = np.zeros(q, bool)
    p = [points[:, k : k + 1] for k in range(3)]  # (q, 1) columns broadcast against (1, c)
    step = max(1, _CHUNK // 2 // max(q, 1))
    t9 = triangles.reshape(-1, 9)
    for lo in range(0, t9.shape[0], step):
        c = t9[lo : lo + step].T
        ax, ay, az, bx, by, bz, cx, cy, cz = (c[k] - p[k % 3] for k in range(9))  # (q, c) each
        la = np.sqrt(ax * ax + ay * ay + az * az)
        lb = np.sqrt(bx * bx + by * by + bz * bz)
        lc = np.sqrt(cx * cx + cy * cy + cz * cz)
        num = ax * (by * cz - bz * cy) + ay * (bz * cx - bx * cz) + az * (bx * cy - by * cx)
        den = (la * lb * lc + (ax * bx + ay * by + az * bz) * lc
               + (ax * cx + ay * cy + az * cz) * lb + (bx * cx + by * cy + bz * cz) * la)
        scale = ON_SURFACE_RTOL * la * lb * lc  # in the plane and not outside the triangle
        on |= np.any((np.abs(num) <= scale) & (den <= scale), axis=1)
        w += np.arctan2(num, den).sum(axis=1)
    w /= 2 * np.pi
    w[on] = np.nan
    return w
