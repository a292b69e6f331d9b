"""Which pieces of a closed mesh are solids, cavities, inverted parts or overlaps.

Decided from nesting depth: winding numbers (Van Oosterom & Strackee solid angles) of a few
vertices of each piece with respect to every other piece. A piece at even depth bounds material
(outward, positive volume), at odd depth a cavity (inward, negative volume).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from massprops.surface import winding_numbers

SAMPLE_BUDGET = 1 << 22
"""Point-triangle pairs to spend per piece: each piece gives SAMPLE_BUDGET // m sample vertices,
clipped to 1..MAX_SAMPLES (16 on small meshes, 4 at 1M triangles); pieces whose bounding box
does not hold a sample cost nothing."""

MAX_SAMPLES = 16
"""Sample vertices per piece at most; all eight corners of a box-shaped piece."""

WINDING_ATOL = 0.25
"""A winding number further than this from an integer belongs to a point on (or next to)
another piece's surface: inconclusive, ignored. Round-off is ~1e-12; a point on a face gives
±0.5 and one on an edge or corner less."""


@dataclass(frozen=True, eq=False)
class Windings:
    """Winding numbers of sample vertices w.r.t. the other pieces, as sparse entries.

    sample_piece (q,): the piece of each sample; row, col, w (k,): sample ``row`` has winding
    number ``w`` w.r.t. piece ``col`` (only where the sample lies in col's bounding box).
    """

    sample_piece: np.ndarray
    row: np.ndarray
    col: np.ndarray
    w: np.ndarray


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
    row, col, w = [], [], []
    for c in range(n_pieces):
        near = np.flatnonzero(np.all((points >= box_lo[c]) & (points <= box_hi[c]), axis=1)
                              & (sample_piece != c))
        if near.size:
            own = vertices[faces[keep[tri_bounds[c] : tri_bounds[c + 1]]]]
            row.append(near)
            col.append(np.full(near.size, c))
            w.append(winding_numbers(points[near], own))
    return Windings(sample_piece, *(np.concatenate(x) if x else np.empty(0, t)
                                    for x, t in ((row, np.int64), (col, np.int64), (w, float))))


@dataclass(frozen=True, eq=False)
class Plan:
    """flip (K,): pieces to reverse; whole: every piece, the mesh was inside out; overlaps:
    (outer, inner) pairs, a vertex of inner lies inside outer; loose: cavities partly outside
    every solid."""

    flip: np.ndarray
    whole: bool
    overlaps: list[tuple[int, int]]
    loose: list[int]


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
    return Plan(flip, whole, overlaps, loose)
