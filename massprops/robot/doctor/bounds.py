"""The link geometry's extent, in the link frame (metres): the points whose convex hull
contains every geometry of the link, that hull, and an ellipsoid containing it.

Points: a mesh's own vertices (scaled and posed); a primitive's circumscribing polytope (a
sphere's subdivided icosahedron, a circle's 48-gon, each pushed out until its faces clear the
curved surface), so the hull of the points contains the solid exactly, never less. The
ellipsoid is the minimum-volume one around the points (Khachiyan's iteration, a few hundred
steps, on at most `ELLIPSOID_POINTS` of them), then grown until every point is inside: any
ellipsoid that contains the geometry makes `validity`'s realizability test a valid necessary
condition; a tighter one makes it sharper.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Bounds", "bounds_of", "primitive_points"]


@dataclass(frozen=True, eq=False)
class Bounds:
    """points : (k, 3) m, the hull's vertices. normals, offsets : the hull's facets, n·x <= o
    (unit outward n). centre : (3,) m and shape : (3, 3) m², the ellipsoid
    {x : (x - centre)ᵀ shape⁻¹ (x - centre) <= 1}. size : m, the diagonal of the points' box."""

    points: np.ndarray
    normals: np.ndarray
    offsets: np.ndarray
    centre: np.ndarray
    shape: np.ndarray
    size: float

    def outside(self, point: np.ndarray) -> float:
        """m: how far ``point`` lies outside the hull (<= 0 inside; the largest facet excess)."""
        return float(np.max(self.normals @ np.asarray(point, dtype=np.float64) - self.offsets))


def _sphere_points() -> np.ndarray:
    """Unit sphere: an icosahedron subdivided twice (162 points), pushed out so that its hull
    contains the unit ball (divided by the smallest facet distance)."""
    t = (1 + math.sqrt(5)) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    pts = np.array(v, dtype=np.float64)
    pts /= np.linalg.norm(pts, axis=1, keepdims=True)
    from scipy.spatial import ConvexHull  # only the doctor's bounds use Qhull

    for _ in range(2):
        faces = ConvexHull(pts).simplices
        mids = np.concatenate([(pts[faces[:, i]] + pts[faces[:, (i + 1) % 3]]) / 2
                               for i in range(3)])
        mids /= np.linalg.norm(mids, axis=1, keepdims=True)
        pts = np.unique(np.round(np.concatenate([pts, mids]), 12), axis=0)
    pts /= np.linalg.norm(pts, axis=1, keepdims=True)
    reach = float(np.min(-ConvexHull(pts).equations[:, 3]))
    return pts / reach


_SPHERE = None
_CIRCLE = 48


def _ball() -> np.ndarray:
    global _SPHERE
    if _SPHERE is None:
        _SPHERE = _sphere_points()
    return _SPHERE


def _disc(radius: float, z: float) -> np.ndarray:
    a = 2 * math.pi * np.arange(_CIRCLE) / _CIRCLE
    r = radius / math.cos(math.pi / _CIRCLE)  # the polygon's edges clear the circle
    return np.column_stack([r * np.cos(a), r * np.sin(a), np.full(_CIRCLE, z)])


def primitive_points(kind: str, dims: tuple[float, ...]) -> np.ndarray:
    """(k, 3) m: points whose hull contains the primitive (`primitives` dims, own frame, its
    centre of mass at the origin)."""
    if kind == "box":
        h = np.asarray(dims) / 2
        return np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]) * h
    if kind == "sphere":
        return _ball() * dims[0]
    if kind == "ellipsoid":
        return _ball() * np.asarray(dims)  # an affine image keeps containment
    radius, length = dims
    if kind == "cylinder":
        return np.concatenate([_disc(radius, -length / 2), _disc(radius, length / 2)])
    if kind == "capsule":
        return np.concatenate([_ball() * radius + [0, 0, -length / 2],
                               _ball() * radius + [0, 0, length / 2]])
    if kind == "cone":  # centre of mass length/4 above the base
        return np.concatenate([_disc(radius, -length / 4), [[0.0, 0.0, 0.75 * length]]])
    raise ValueError(f"no bounding points for a {kind!r}")


def bounds_of(points: np.ndarray) -> Bounds | None:
    """The hull and ellipsoid of ``points`` (k, 3) m; None when they span no volume."""
    from scipy.spatial import ConvexHull  # only the doctor's bounds use Qhull

    p = np.asarray(points, dtype=np.float64)
    try:
        hull = ConvexHull(p)
    except Exception:  # Qhull's error for flat or degenerate point sets
        return None
    p = p[hull.vertices]
    centre, shape = _ellipsoid(p)
    if not (np.isfinite(shape).all() and np.linalg.eigvalsh(shape)[0] > 0):
        return None  # no volume to speak of: nothing to judge against
    size = float(np.linalg.norm(p.max(axis=0) - p.min(axis=0)))
    return Bounds(p, hull.equations[:, :3], -hull.equations[:, 3], centre, shape, size)


ELLIPSOID_POINTS = 2000
"""Khachiyan's iteration runs on at most this many of the hull's vertices (every k-th): its cost
is steps × points, and the ellipsoid is grown afterwards to hold every vertex, so a subsample
only makes it a little looser (the test stays valid, a little less sharp)."""


def _ellipsoid(all_points: np.ndarray, steps: int = 400) -> tuple[np.ndarray, np.ndarray]:
    """Khachiyan's minimum-volume enclosing ellipsoid, then grown to contain every point; on
    every k-th point, or on all of them when that subsample spans no volume (a regular mesh
    whose hull vertices come in rings)."""
    sub = all_points[::-(-len(all_points) // ELLIPSOID_POINTS)]
    spread = np.linalg.eigvalsh(np.cov(sub.T)) if len(sub) > 3 else np.zeros(3)
    if not spread[0] > 1e-12 * spread[2]:
        sub = all_points
    return _khachiyan(sub, all_points, steps)


def _khachiyan(p: np.ndarray, all_points: np.ndarray, steps: int):
    n = len(p)
    q = np.column_stack([p, np.ones(n)]).T
    u = np.full(n, 1.0 / n)
    for _ in range(steps):
        x = q @ (u[:, None] * q.T)
        m = np.einsum("ij,ji->i", q.T, np.linalg.solve(x, q))
        j = int(np.argmax(m))
        step = (m[j] - 4.0) / (4.0 * (m[j] - 1.0))
        if step < 1e-6:
            break
        u *= 1 - step
        u[j] += step
    centre = u @ p
    d = p - centre
    shape = 3.0 * ((d.T * u) @ d)
    d = all_points - centre
    reach = float(np.max(np.einsum("ij,ij->i", d, np.linalg.solve(shape, d.T).T)))
    return centre, shape * reach
