"""Which pieces of a closed mesh are solids, cavities, inverted parts or overlaps.

Decided from nesting depth: winding numbers (Van Oosterom & Strackee solid angles) of a few
vertices of each piece with respect to every other piece. A piece at even depth bounds material
(outward, positive volume), at odd depth a cavity (inward, negative volume).

Two solids can also overlap with no vertex of either inside the other (two bars crossing like a
plus sign): for every two pieces whose bounding boxes share a volume, the centre of that shared
box is probed too. A point inside both solids and in material counted twice (the oriented
windings of all pieces sum to 2 or more: an island in a cavity of a solid sums to 1) is an
overlap, and no touching or merely nearby pair ever gives one (a point on a surface is
inconclusive). The probe finds such
crossings whenever the shared box's centre lies in both, as it does for bars crossing at their
middles; two solids whose shared volume misses that centre are still missed.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from massprops.mesh.geometry import winding_numbers
from massprops.tolerances import WINDING_ATOL

SAMPLE_BUDGET = 1 << 22
"""Point-triangle pairs to spend per piece: each piece gives SAMPLE_BUDGET // m sample vertices,
clipped to 1..MAX_SAMPLES (16 on small meshes, 4 at 1M triangles); pieces whose bounding box
does not hold a sample cost nothing."""

MAX_SAMPLES = 16
"""Sample vertices per piece at most; all eight corners of a box-shaped piece."""

PROBE_BUDGET = SAMPLE_BUDGET
"""Point-triangle pairs to spend on the interior probes of one mesh (pairs with the largest
shared box first)."""

PROBE_THICKNESS = 1e-9
"""A shared box thinner than this fraction of the larger piece's size in some axis is a touch
(round-off of a shared face), not a shared volume: not probed."""

@dataclass(frozen=True, eq=False)
class Windings:
    """Winding numbers of sample vertices w.r.t. the other pieces, as sparse entries.

    sample_piece (q,): the piece of each sample; row, col, w (k,): sample ``row`` has winding
    number ``w`` w.r.t. piece ``col`` (only where the sample lies in col's bounding box).
    probe_pair (p, 2): pieces whose bounding boxes share a volume; probe_row, probe_col,
    probe_w (k,): the centre of pair ``probe_row``'s shared box has winding number ``probe_w``
    w.r.t. piece ``probe_col`` (every piece whose bounding box holds it).
    """

    sample_piece: np.ndarray
    row: np.ndarray
    col: np.ndarray
    w: np.ndarray
    probe_pair: np.ndarray = field(default_factory=lambda: np.empty((0, 2), np.int64))
    probe_row: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))
    probe_col: np.ndarray = field(default_factory=lambda: np.empty(0, np.int64))
    probe_w: np.ndarray = field(default_factory=lambda: np.empty(0))


def sample_windings(vertices: np.ndarray, faces: np.ndarray, tri: np.ndarray,
                    piece: np.ndarray, n_pieces: int) -> Windings:
    """Winding numbers of up to MAX_SAMPLES vertices of each piece w.r.t. each other piece.

    vertices (n, 3) float64, m; faces (m, 3) file vertex indices; tri (m, 3) welded ids (equal
    position, equal id); piece (m,) piece of each triangle, -1 to leave a triangle out.
    """
    keep = np.flatnonzero(piece >= 0)
    keep = keep[np.argsort(piece[keep], kind="stable")]
    tri_bounds = np.concatenate(([0], np.cumsum(np.bincount(piece[keep], minlength=n_pieces))))
    piece_of_id = np.full(int(tri.max(initial=-1)) + 1, -1)
    piece_of_id[tri[keep].ravel()] = np.repeat(piece[keep], 3)
    where = np.full(piece_of_id.size, -1)  # a file vertex of each welded id
    where[tri[keep].ravel()] = faces[keep].ravel()
    ids = np.flatnonzero(piece_of_id >= 0)
    ids = ids[np.argsort(piece_of_id[ids], kind="stable")]
    coords = vertices[where[ids]]  # (u, 3) positions, grouped by piece
    counts = np.bincount(piece_of_id[ids], minlength=n_pieces)
    id_starts = np.concatenate(([0], np.cumsum(counts)[:-1]))
    box_lo = np.minimum.reduceat(coords, id_starts, axis=0)
    box_hi = np.maximum.reduceat(coords, id_starts, axis=0)
    per = int(np.clip(SAMPLE_BUDGET // max(1, keep.size), 1, MAX_SAMPLES))
    picks = [id_starts[c] + np.arange(min(per, counts[c])) * counts[c] // min(per, counts[c])
             for c in range(n_pieces)]
    sample_piece = np.repeat(np.arange(n_pieces), [p.size for p in picks])
    points = coords[np.concatenate(picks)]
    pair, centre = _probe_pairs(box_lo, box_hi, np.diff(tri_bounds))
    row, col, w, p_row, p_col, p_w = [], [], [], [], [], []
    for c in range(n_pieces):
        near = np.flatnonzero(np.all((points >= box_lo[c]) & (points <= box_hi[c]), axis=1)
                              & (sample_piece != c))
        probes = np.flatnonzero(np.all((centre >= box_lo[c]) & (centre <= box_hi[c]), axis=1))
        if near.size or probes.size:
            own = vertices[faces[keep[tri_bounds[c] : tri_bounds[c + 1]]]]
        if near.size:
            row.append(near)
            col.append(np.full(near.size, c))
            w.append(winding_numbers(points[near], own))
        if probes.size:
            p_row.append(probes)
            p_col.append(np.full(probes.size, c))
            p_w.append(winding_numbers(centre[probes], own))
    row_a, col_a, w_a = (np.concatenate(x) if x else np.empty(0, t)
                         for x, t in ((row, np.int64), (col, np.int64), (w, float)))
    p_row_a, p_col_a, p_w_a = (np.concatenate(x) if x else np.empty(0, t)
                               for x, t in ((p_row, np.int64), (p_col, np.int64), (p_w, float)))
    return Windings(sample_piece, row_a, col_a, w_a, pair, p_row_a, p_col_a, p_w_a)


def _probe_pairs(box_lo: np.ndarray, box_hi: np.ndarray, n_tri: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray]:
    """(pairs (p, 2), centres (p, 3)): pieces whose bounding boxes share a volume, and the
    centre of the shared box; the largest shared boxes first, within PROBE_BUDGET."""
    k = box_lo.shape[0]
    span = (box_hi - box_lo).max(axis=1)
    found, centres, volumes = [], [], []
    for i in range(k - 1):  # O(k) memory; a mesh rarely has more than a few thousand pieces
        lo = np.maximum(box_lo[i], box_lo[i + 1 :])
        hi = np.minimum(box_hi[i], box_hi[i + 1 :])
        thick = PROBE_THICKNESS * np.maximum(span[i], span[i + 1 :])
        j = np.flatnonzero(np.all(hi - lo > thick[:, None], axis=1))
        found.append(np.column_stack([np.full(j.size, i), i + 1 + j]))
        centres.append(0.5 * (lo[j] + hi[j]))
        volumes.append(np.prod(hi[j] - lo[j], axis=1))
    if not found:
        return np.empty((0, 2), np.int64), np.empty((0, 3))
    pairs, centre, volume = np.concatenate(found), np.concatenate(centres), np.concatenate(volumes)
    order = np.argsort(-volume, kind="stable")
    cost = np.cumsum(n_tri[pairs[order]].sum(axis=1))
    order = order[cost <= PROBE_BUDGET]
    return pairs[order].astype(np.int64), centre[order]


@dataclass(frozen=True, eq=False)
class Plan:
    """flip (K,): pieces to reverse; whole: every piece, the mesh was inside out; overlaps:
    (outer, inner) pairs, a vertex of inner lies inside outer; loose: cavities partly outside
    every solid; crossings: pairs of solids not in overlaps whose interiors share a point (the
    probe), their surfaces crossing with no vertex of either inside the other."""

    flip: np.ndarray
    whole: bool
    overlaps: list[tuple[int, int]]
    loose: list[int]
    crossings: list[tuple[int, int]] = field(default_factory=list)


def orientation_plan(volumes: np.ndarray, wn: Windings) -> Plan:
    """Decide each piece's orientation from its nesting depth (how many other pieces hold it).

    If every piece disagrees with its depth and the total volume is negative, the whole mesh is
    inside out. Otherwise a negative piece at even depth (inside no solid) is an inverted part
    and is flipped; a positive piece at odd depth is left as is: it overlaps or nests in another
    solid and is counted twice. After the flips, a sample sees winding 0 from the other pieces if
    its own piece is solid, 1 if a cavity; any other sample names an overlap.
    """
    k = volumes.size
    r = np.rint(wn.w)
    r[~(np.abs(wn.w - r) <= WINDING_ATOL)] = 0  # NaN too: a sample on another piece's surface
    holder = np.unique(wn.sample_piece[wn.row[r != 0]] * k + wn.col[r != 0])
    depth = np.bincount(holder // k, minlength=k)
    wrong = (volumes != 0) & ((volumes > 0) != (depth % 2 == 0))
    whole = bool(np.any(wrong) and np.all(wrong[volumes != 0]) and volumes.sum() < 0)
    flip = wrong if whole else wrong & (volumes < 0)
    sign = np.where(flip, -1.0, 1.0)
    rest = np.bincount(wn.row, weights=r * sign[wn.col], minlength=wn.sample_piece.size)
    bad = rest != (volumes * sign < 0)[wn.sample_piece]
    hit = bad[wn.row] & (r != 0)
    pairs = {(int(j), int(i)) for j, i in zip(wn.col[hit], wn.sample_piece[wn.row[hit]])}
    overlaps = sorted(p for p in pairs if p[::-1] not in pairs or p[0] < p[1])
    partnered = set(wn.row[hit].tolist())
    loose = sorted({int(wn.sample_piece[s]) for s in np.flatnonzero(bad) if s not in partnered})
    return Plan(flip, whole, overlaps, loose, _crossings(volumes * sign, sign, wn, overlaps))


def _crossings(oriented: np.ndarray, sign: np.ndarray, wn: Windings,
               overlaps: list[tuple[int, int]]) -> list[tuple[int, int]]:
    """Pairs of solids (positive ``oriented`` volume) whose probe point lies inside both and in
    material counted twice (oriented windings summing to 2 or more; a probe on any surface
    says nothing), not already among ``overlaps``."""
    p = wn.probe_pair.shape[0]
    if not p:
        return []
    r = np.rint(wn.probe_w) * sign[wn.probe_col]
    vague = np.bincount(wn.probe_row, weights=~(np.abs(wn.probe_w - np.rint(wn.probe_w))
                                                <= WINDING_ATOL), minlength=p) > 0
    depth = np.bincount(wn.probe_row, weights=r, minlength=p)
    own = np.zeros((p, 2))
    for side in range(2):
        mine = wn.probe_col == wn.probe_pair[wn.probe_row, side]
        own[wn.probe_row[mine], side] = r[mine]
    hit = ~vague & (depth >= 2) & np.all(own == 1, axis=1) \
        & np.all(oriented[wn.probe_pair] > 0, axis=1)
    known = set(overlaps) | {q[::-1] for q in overlaps}
    return [(int(i), int(j)) for i, j in wn.probe_pair[hit] if (i, j) not in known]
