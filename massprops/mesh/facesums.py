"""The blocked pass over a mesh's faces: tetrahedron totals about an origin, with fast or
double-double determinants, and what the error bounds need to know about their rounding.

Internal to ``massprops.mesh.integral`` (which documents the method); split out to keep each
module to one job. Per face (a, b, c) and origin o, primes meaning "minus o": d = det(a', b', c'),
s = a' + b' + c'; the totals are Σd, Σd s_i, Σd f_i, Σd q_ij (see ``FaceSums``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from massprops.errors import MeshFormatError, setting_ref
from massprops.mesh.topology import is_soup
from massprops.mesh.value import Mesh

U = 2.0**-53
"""Unit round-off of float64."""

BLOCK = 4096
"""Faces per block: a block's ~20 work rows stay in a core's L2 cache, and each row total is
one numpy pairwise sum, whose rounding depth ``sum_depth`` counts."""

UNDERFLOW = 1e-300
"""Per-face allowance for gradual underflow in the products, far below any resolvable volume."""


class FaceSums(NamedTuple):
    """Totals over the faces, unit density, about the origin: det Σd, abs_det Σ|d|, first (3,)
    Σ d s_i, diag (3,) Σ d f_i with f_i = (a'_i² + b'_i² + c'_i² + s_i²)/2, off (3,) Σ d q for
    (xy, yz, zx) with q_ij = a'_i a'_j + b'_i b'_j + c'_i c'_j + s_i s_j, perm (3,) the
    determinant-error weights (see ``det_error``), area (3,) Σ|n_i| with |n| twice the
    triangle's area (zeros unless asked), lowest/highest (3,) the extremes of the rounded v - o,
    count of faces, and which path made them."""

    det: float
    abs_det: float
    first: np.ndarray
    diag: np.ndarray
    off: np.ndarray
    perm: np.ndarray
    area: np.ndarray
    lowest: np.ndarray
    highest: np.ndarray
    count: int  # type: ignore[assignment]  # a field named like tuple.count, on purpose
    accurate: bool


def reach_of(sums: FaceSums) -> np.ndarray:
    """(3,) bound of |v_i - o_i| and of its rounded value; 4u covers the roundings."""
    return np.maximum(-sums.lowest, sums.highest) * (1 + 4 * U)


def face_sums(mesh: Mesh, origin: np.ndarray, *, accurate: bool, area: bool) -> FaceSums:
    """One pass over the faces of ``mesh`` (indices already checked: 0 <= i < n_vertices).

    origin : (3,) m. accurate : double-double determinants. area : also total |n_i|.
    Work rows: 0 d, 1 |d|, 2-4 d s, 5-7 d f, 8-10 d q, 11-13 perm, 14-16 |n| (if ``area``).
    Block buffers are reused, so memory stays O(BLOCK).
    """
    m = mesh.faces.shape[0]
    k = min(BLOCK, m)
    gather = _gatherer(mesh)
    stored = np.empty((3, 3, k))        # [a, b, c] x [x, y, z] x face, as stored
    primes = np.empty((4, 4, k))        # [a', b', c', s] x [x, y, z, x again] x face
    edges = np.empty((2, 5, k))         # [b - a, c - a] x [x, y, z, x, y] x face
    work = np.empty((4, 3, k))
    rows = np.empty((17 if area else 14, k))
    shift = origin[None, :, None]
    totals, extremes = [], []
    with np.errstate(over="ignore", invalid="ignore"):
        for start in range(0, m, k):
            n = min(k, m - start)
            v, x, r = stored[..., :n], primes[..., :n], rows[:, :n]
            gather(start, n, v)
            np.subtract(v, shift, out=x[:3, :3])
            if accurate:
                # the rounding errors of v - o, exactly (Knuth's two-sum, s = v - o known)
                z = x[:3, :3] - v
                _accurate_dets(x[:3, :3], (v - (x[:3, :3] - z)) - (shift + z), r, area)
            else:
                _fast_dets(v, x, edges[..., :n], work[..., :n], r, area)
            extremes.append(np.concatenate([x[:3, :3].min(axis=2).min(axis=0),
                                            x[:3, :3].max(axis=2).max(axis=0)]))
            _moment_rows(x, work[..., :n], r)
            totals.append(r.sum(axis=1))
    t = np.array([math.fsum(col) for col in np.array(totals).T])
    ext = np.array(extremes)
    if not (np.isfinite(t).all() and np.isfinite(ext).all()):
        if not np.isfinite(mesh.vertices).all():
            raise MeshFormatError(f"{mesh.name}: expected finite vertex coordinates, got NaN or "
                                  "infinity; fix or re-export the file")
        # the input's scale (integral.check_coordinate_scale refuses it first, with its limit)
        raise MeshFormatError(f"{mesh.name}: coordinates too large for float64 mass "
                              "properties: the integral's products passed 1.8e308; rescale the "
                              f"mesh ({setting_ref('unit')})")
    return FaceSums(t[0], t[1], t[2:5], t[5:8], t[8:11], t[11:14],
                    t[14:17] if area else np.zeros(3), ext[:, :3].min(axis=0),
                    ext[:, 3:].max(axis=0), m, accurate)


def _gatherer(mesh: Mesh) -> Callable[[int, int, np.ndarray], None]:
    """gather(start, n, out): out (3, 3, n) = the stored [a, b, c] x [x, y, z] of faces
    start..start+n. STL soups (faces = arange): a transposed copy of the vertices' rows. Welded
    meshes (vertices <= faces, indices jump around): one transposed copy of the vertices, then
    1-D takes of 8-byte items. Other unwelded meshes: row takes, then a transposed copy.
    The caller checked the indices, so mode="clip" skips numpy's buffered bounds check."""
    vertices, faces = mesh.vertices, mesh.faces
    if is_soup(faces, vertices.shape[0]):
        corners = vertices.reshape(-1, 3, 3)

        def gather(start: int, n: int, out: np.ndarray) -> None:
            out[...] = corners[start:start + n].transpose(1, 2, 0)
    elif vertices.shape[0] <= faces.shape[0]:
        columns, index = np.ascontiguousarray(vertices.T), np.ascontiguousarray(faces.T)

        def gather(start: int, n: int, out: np.ndarray) -> None:
            for j in range(3):
                np.take(columns, index[j, start:start + n], axis=1, out=out[j], mode="clip")
    else:
        rows = np.empty((min(BLOCK, faces.shape[0]), 3, 3))

        def gather(start: int, n: int, out: np.ndarray) -> None:
            np.take(vertices, faces[start:start + n], axis=0, out=rows[:n], mode="clip")
            out[...] = rows[:n].transpose(1, 2, 0)
    return gather


def _fast_dets(v: np.ndarray, x: np.ndarray, e: np.ndarray, w: np.ndarray, r: np.ndarray,
               area: bool) -> None:
    """d = a'·((b - a) × (c - a)) into r[0], |d| into r[1], perm_i = |e1_j e2_k| + |e1_k e2_j|
    into r[11:14], |n| into r[14:17]. Edges come from the stored vertices v: exact to u|e|."""
    np.subtract(v[1:3], v[0:1], out=e[:, :3])
    e[:, 3:] = e[:, :2]
    plus, minus, normal = w[0], w[1], w[2]
    np.multiply(e[0, 1:4], e[1, 2:5], out=plus)      # e1_j e2_k for (i, j, k) cyclic
    np.multiply(e[0, 2:5], e[1, 1:4], out=minus)     # e1_k e2_j
    np.subtract(plus, minus, out=normal)
    if area:
        np.abs(normal, out=r[14:17])
    np.abs(plus, out=plus)
    np.abs(minus, out=minus)
    np.add(plus, minus, out=r[11:14])
    np.multiply(x[0, :3], normal, out=normal)
    np.add.reduce(normal, axis=0, out=r[0])
    np.abs(r[0], out=r[1])


def _moment_rows(x: np.ndarray, w: np.ndarray, r: np.ndarray) -> None:
    """Rows 2-10 from d (row 0) and a', b', c' (x[0:3]); leaves s in x[3]."""
    d = r[0]
    np.add(x[0, :3], x[1, :3], out=w[0])             # a + b
    np.add(w[0], x[2, :3], out=x[3, :3])             # s
    x[:, 3] = x[:, 0]
    np.multiply(x[1, :3], w[0], out=w[1])            # f = a² + b (a + b) + c s
    np.multiply(x[0, :3], x[0, :3], out=w[0])
    np.multiply(x[2, :3], x[3, :3], out=w[2])
    np.add.reduce(w[:3], axis=0, out=r[5:8])
    np.multiply(x[:, :3], x[:, 1:4], out=w)          # a_i a_j, b_i b_j, c_i c_j, s_i s_j
    np.add.reduce(w, axis=0, out=r[8:11])
    np.multiply(x[3, :3], d, out=r[2:5])
    np.multiply(r[5:11], d, out=r[5:11])


_SPLITTER = 134217729.0  # 2**27 + 1, Dekker's splitting constant


def _split(v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    c = _SPLITTER * v
    high = c - (c - v)
    return high, v - high


def _two_prod(p: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(fl(p q), its exact rounding error): Dekker's product (numpy has no fma)."""
    prod = p * q
    ph, pl = _split(p)
    qh, ql = _split(q)
    return prod, ((ph * qh - prod) + ph * ql + pl * qh) + pl * ql


def _two_sum(p: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(fl(p + q), its exact rounding error): Knuth's sum."""
    s = p + q
    z = s - p
    return s, (p - (s - z)) + (q - z)


def _accurate_dets(primes: np.ndarray, low: np.ndarray, r: np.ndarray, area: bool) -> None:
    """d = det(a, b, c) in double-double into r[0], |d| into r[1], P into r[11].

    primes : (3, 3, n) rounded a', b', c' (vertex x coordinate x face); low : their exact
    rounding errors, so a' = primes[0] + low[0] exactly. With P = Σ_i |a'_i| (|b'_j c'_k| +
    |b'_k c'_j|): each n_i = (b' × c')_i is h_i + l_i to 3u² of its products, a'_i h_i is split
    exactly, the small terms and the first-order terms of ``low`` (each <= u P) are summed in
    float, the second-order ones (<= 3u² P) dropped. So |d̂ - d| <= u|d| + 40 u² P; the bound
    in ``det_error`` uses 64 u² P.
    """
    a, b, c = primes
    j, k = [1, 2, 0], [2, 0, 1]
    p1, e1 = _two_prod(b[j], c[k])
    p2, e2 = _two_prod(b[k], c[j])
    high, t = _two_sum(p1, -p2)
    g, rest = _two_prod(a, high)
    small = (rest + a * ((e1 - e2) + t)).sum(axis=0)
    small += (low[0] * high + low[1] * (c[j] * a[k] - c[k] * a[j])
              + low[2] * (a[j] * b[k] - a[k] * b[j])).sum(axis=0)
    s1, f1 = _two_sum(g[0], g[1])
    s2, f2 = _two_sum(s1, g[2])
    np.add(s2, (f1 + f2) + small, out=r[0])
    np.abs(r[0], out=r[1])
    np.sum(np.abs(a) * (np.abs(p1) + np.abs(p2)), axis=0, out=r[11])
    r[12:14] = 0.0
    if area:
        np.abs(high, out=r[14:17])


def det_error(sums: FaceSums, reach: np.ndarray) -> float:
    """Bound of Σ_f |d̂_f - d_f|. Fast path: each of the 6 monomials a'_i e1_j e2_k carries <= 8
    roundings (a'_i, two edges, product, difference, times a'_i, two additions), |a'_i| <= reach_i,
    and γ_10 also absorbs the rounding of the perm totals. Accurate path: ``_accurate_dets``."""
    if sums.accurate:
        bound = gamma(2) * sums.abs_det + 64 * U**2 * float(sums.perm[0])
    else:
        bound = gamma(10) * float(reach @ sums.perm)
    return bound + sums.count * UNDERFLOW


def gamma(k: int) -> float:
    """γ_k = k u / (1 - k u): the relative error bound of k nested roundings."""
    return k * U / (1.0 - k * U)


def pairwise_depth(n: int) -> int:
    """Nested roundings in numpy's pairwise sum of n terms (numpy/_core/src/umath/
    loops_utils.h.src): below 8 terms sequential; up to 128, 8 accumulators, a 3-level combine
    and the leftovers added in turn; above, two halves whose sizes are multiples of 8."""
    if n < 8:
        return max(n - 1, 0)
    if n <= 128:
        return n // 8 - 1 + 3 + n % 8
    half = n // 2 - (n // 2) % 8
    return 1 + max(pairwise_depth(half), pairwise_depth(n - half))


BLOCK_SUM_DEPTH = 29
"""max(pairwise_depth(n) for n <= BLOCK), checked by the tests."""


def sum_depth(count: int) -> int:
    """Roundings nested in one total over ``count`` faces: the reduction's accumulator and the
    pairwise sum of a block, plus math.fsum (correctly rounded) when there are several blocks."""
    if count <= BLOCK:
        return 1 + max(pairwise_depth(count), pairwise_depth(count - 1))
    return 2 + BLOCK_SUM_DEPTH
