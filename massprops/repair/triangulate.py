"""Triangulating one hole's rim without new vertices: ear clipping of its outline seen in a
best-fit plane when that outline is simple, else the minimum-area triangulation of the rim in
space (dynamic programming, small rims only). Plane geometry helpers for `massprops.repair.holes`.

A rim is (k, 3) points in cap order: the cap's triangles run the rim this way round, so their
right-hand normal follows the surface's orientation. Triangles are (t, 3) indices into the rim,
each listing its corners in rim order, so every rim edge is used once by the cap as i -> i+1.
"""

from __future__ import annotations

import numpy as np

from massprops.tolerances import RIM_NORMAL_RTOL

MAX_DP_POINTS = 200
"""Largest rim the minimum-area dynamic programme takes: O(k³) work (~0.2 s at 200 points) and
O(k²) memory. A rim whose outline crosses itself in every plane and is larger than this is
refused (no cap we could defend)."""


def plane_frame(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(centre (3,), unit normal (3,), in-plane axes (2, 3)) of the best-fit plane of a closed
    polygon: the normal of its vector area (Newell's method, right-handed with the point order),
    or the direction of least spread when the vector area vanishes (a figure of eight)."""
    centre = points.mean(axis=0)
    p = points - centre
    area = np.cross(p, np.roll(p, -1, axis=0)).sum(axis=0)
    norm = np.linalg.norm(area)
    scale = float((np.linalg.norm(p, axis=1) ** 2).sum())
    if norm > RIM_NORMAL_RTOL * scale:
        normal = area / norm
    else:
        normal = np.linalg.eigh(p.T @ p)[1][:, 0]
    helper = np.eye(3)[int(np.argmin(np.abs(normal)))]
    e1 = np.cross(normal, helper)
    e1 /= np.linalg.norm(e1)
    return centre, normal, np.stack([e1, np.cross(normal, e1)])


def is_simple(xy: np.ndarray) -> bool:
    """A closed polygon (k, 2) whose edges meet only at shared corners of neighbouring edges,
    no two vertices equal (points touching a non-neighbouring edge count as crossing)."""
    k = xy.shape[0]
    if k < 3:
        return False
    if np.unique(xy, axis=0).shape[0] < k:
        return False
    a, b = xy, np.roll(xy, -1, axis=0)
    idx = np.arange(k)
    for lo in range(0, k, 256):
        i = idx[lo:lo + 256, None]
        near = (idx[None, :] == i) | (idx[None, :] == (i + 1) % k) | ((idx[None, :] + 1) % k == i)
        hit = _segments_meet(a[lo:lo + 256, None], b[lo:lo + 256, None], a[None], b[None])
        if np.any(hit & ~near):
            return False
    return True


def _orient(p: np.ndarray, q: np.ndarray, r: np.ndarray) -> np.ndarray:
    return ((q[..., 0] - p[..., 0]) * (r[..., 1] - p[..., 1])
            - (q[..., 1] - p[..., 1]) * (r[..., 0] - p[..., 0]))


def _segments_meet(p1, p2, q1, q2) -> np.ndarray:
    """Closed segments p1p2 and q1q2 share a point (touching counts)."""
    d1, d2 = _orient(q1, q2, p1), _orient(q1, q2, p2)
    d3, d4 = _orient(p1, p2, q1), _orient(p1, p2, q2)
    crossing = (d1 * d2 < 0) & (d3 * d4 < 0)

    def on(p, q, r, d):  # r on segment pq, given orient(p, q, r) = d
        lo, hi = np.minimum(p, q), np.maximum(p, q)
        return (d == 0) & np.all((r >= lo) & (r <= hi), axis=-1)

    return (crossing | on(q1, q2, p1, d1) | on(q1, q2, p2, d2) | on(p1, p2, q1, d3)
            | on(p1, p2, q2, d4))


def ear_clip(xy: np.ndarray) -> np.ndarray | None:
    """Triangles (k-2, 3) of a simple counter-clockwise polygon (k, 2) by ear clipping: cut off,
    again and again, a convex corner whose triangle holds no other remaining vertex. None if no
    ear is found (the outline was not simple after all)."""
    left = list(range(xy.shape[0]))
    out: list[tuple[int, ...]] = []
    while len(left) > 3:
        n = len(left)
        idx = np.array(left)
        prev, nxt = np.roll(idx, 1), np.roll(idx, -1)
        convex = _orient(xy[prev], xy[idx], xy[nxt]) > 0
        found = False
        for j in np.flatnonzero(convex):
            a, b, c = xy[prev[j]], xy[idx[j]], xy[nxt[j]]
            others = np.delete(idx, [(j - 1) % n, j, (j + 1) % n])
            pts = xy[others]
            inside = ((_orient(a, b, pts) >= 0) & (_orient(b, c, pts) >= 0)
                      & (_orient(c, a, pts) >= 0))
            if not np.any(inside):
                out.append((prev[j], idx[j], nxt[j]))
                left.pop(j)
                found = True
                break
        if not found:
            return None
    out.append(tuple(left))
    tri = np.array(out, dtype=np.int64)
    return _in_rim_order(tri)


def min_area(points: np.ndarray) -> np.ndarray:
    """Triangles (k-2, 3) of the rim (k, 3) of least total area among all triangulations of the
    polygon without new vertices (dynamic programming over sub-polygons i..j)."""
    k = points.shape[0]
    cost = np.zeros((k, k))
    pick = np.zeros((k, k), dtype=np.int64)
    for length in range(2, k):
        for i in range(0, k - length):
            j = i + length
            m = np.arange(i + 1, j)
            area = np.linalg.norm(np.cross(points[m] - points[i], points[j] - points[i]), axis=1)
            total = cost[i, m] + cost[m, j] + area / 2
            best = int(np.argmin(total))
            cost[i, j], pick[i, j] = total[best], m[best]
    out, stack = [], [(0, k - 1)]
    while stack:
        i, j = stack.pop()
        if j - i < 2:
            continue
        m = pick[i, j]
        out.append((i, m, j))
        stack += [(i, m), (m, j)]
    return np.array(out, dtype=np.int64)


def _in_rim_order(tri: np.ndarray) -> np.ndarray:
    """Each triangle's corners rotated so that they appear in increasing rim order after a
    cyclic shift (orientation kept)."""
    first = np.argmin(tri, axis=1)
    rows = np.arange(tri.shape[0])[:, None]
    return tri[rows, (first[:, None] + np.arange(3)) % 3]


def hull_area(xy: np.ndarray) -> float:
    """Area of the convex hull of points (k, 2), m² (Andrew's monotone chain)."""
    pts = np.unique(xy, axis=0)
    if pts.shape[0] < 3:
        return 0.0

    def half(points: np.ndarray) -> list:
        chain: list = []
        for p in points:
            while len(chain) >= 2 and _orient(chain[-2], chain[-1], p) <= 0:
                chain.pop()
            chain.append(p)
        return chain

    ring = np.array(half(pts)[:-1] + half(pts[::-1])[:-1])
    x, y = ring[:, 0], ring[:, 1]
    return float(abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))) / 2)
