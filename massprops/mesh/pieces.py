"""Which triangles meet at each edge, and the pieces a surface falls into when it is cut at every
edge that is not shared by exactly two triangles running opposite ways (the repairs' own view of
a mesh's topology; `massprops.mesh.health` decides and explains, this module serves the repairs)."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from massprops.mesh.geometry import signed_volumes6
from massprops.mesh.topology import connected_components
from massprops.mesh.value import Mesh
from massprops.mesh.weld import weld


@dataclass(frozen=True, eq=False)
class EdgeUses:
    """Every use of an undirected edge by a triangle, grouped by edge.

    face (3t,) int64 : the triangle (row of ``Mesh.faces``) of each use, uses of one edge adjacent.
    forward (3t,) bool : the triangle runs the edge from its smaller id to its larger.
    corner (3t,) int64 : 0, 1, 2: the use is the triangle's edge from corner k to corner k + 1.
    start (e,) int64, count (e,) int64 : where each edge's uses begin, and how many there are.
    u, v (e,) int64 : the welded ids of each edge's ends, u < v.
    """

    face: np.ndarray
    forward: np.ndarray
    corner: np.ndarray
    start: np.ndarray
    count: np.ndarray
    u: np.ndarray
    v: np.ndarray

    @cached_property
    def manifold(self) -> np.ndarray:
        """(e,) bool: used by exactly two triangles, once each way."""
        two = self.count == 2
        at = self.start[two]
        out = np.zeros(self.count.size, bool)
        out[two] = self.forward[at] != self.forward[at + 1]
        return out


@dataclass(frozen=True, eq=False)
class Welded:
    """A mesh's triangles on welded ids: tri (m, 3) ids, valid (m,) three distinct ids, reps (u,)
    a vertex row per id (see `massprops.mesh.weld.weld`)."""

    mesh: Mesh
    tri: np.ndarray
    valid: np.ndarray
    reps: np.ndarray

    @classmethod
    def of(cls, mesh: Mesh) -> Welded:
        inv, reps = weld(mesh.vertices)
        tri = inv.astype(np.int64)[mesh.faces]
        valid = (tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 2] != tri[:, 0])
        return cls(mesh, tri, valid, reps)

    @cached_property
    def positions(self) -> np.ndarray:
        """(u, 3) float64 m: the position of each welded id."""
        return self.mesh.vertices[self.reps]

    @cached_property
    def edges(self) -> EdgeUses:
        rows = np.flatnonzero(self.valid)
        a = self.tri[rows]
        b = a[:, [1, 2, 0]]
        low, high = np.minimum(a, b).astype(np.uint64), np.maximum(a, b).astype(np.uint64)
        key = (low << np.uint64(32)) | high
        order = np.argsort(key.ravel(), kind="stable")
        key = key.ravel()[order]
        new = np.concatenate(([True], key[1:] != key[:-1])) if key.size else np.zeros(0, bool)
        start = np.flatnonzero(new)
        count = np.diff(np.append(start, key.size))
        ends = key[start]
        return EdgeUses(np.repeat(rows, 3)[order], (a < b).ravel()[order],
                        np.tile(np.arange(3), rows.size)[order], start, count,
                        (ends >> np.uint64(32)).astype(np.int64),
                        (ends & np.uint64(0xFFFFFFFF)).astype(np.int64))


@dataclass(frozen=True, eq=False)
class Pieces:
    """The surface cut at every edge that is not manifold (see `EdgeUses.manifold`), so that
    solids touching along an edge or at a vertex come apart.

    label (m,) int64 : piece of each triangle, numbered by first triangle; -1 for triangles with
        a repeated vertex (no area, no piece). count : number of pieces.
    closed (k,) bool : every edge of the piece is manifold: a closed 2-manifold by itself.
    boundary, crowded, disagreeing (k,) int64 : the piece's edges used once, by more than two
        triangles, or twice the same way (why it is not closed).
    volumes (k,) float64 m³ : signed volume of each piece as wound.
    """

    label: np.ndarray
    count: int
    closed: np.ndarray
    boundary: np.ndarray
    crowded: np.ndarray
    disagreeing: np.ndarray
    volumes: np.ndarray

    def rows(self, k: int) -> np.ndarray:
        """The triangles (rows of ``Mesh.faces``) of piece k."""
        return np.flatnonzero(self.label == k)

    def why_open(self, k: int) -> str:
        """Why piece k is not a closed 2-manifold by itself, in words."""
        parts = []
        if self.boundary[k]:
            parts.append(f"{self.boundary[k]} boundary edges")
        if self.crowded[k]:
            parts.append(f"{self.crowded[k]} edges shared by more than two faces")
        if self.disagreeing[k]:
            parts.append(f"{self.disagreeing[k]} edges whose faces disagree on winding")
        return ", ".join(parts)


def split_pieces(w: Welded) -> Pieces:
    """The pieces of a welded mesh; see `Pieces`."""
    m = w.tri.shape[0]
    e = w.edges
    ok = e.manifold
    at = e.start[ok]
    label = connected_components(m, e.face[at], e.face[at + 1]).astype(np.int64)
    label[~w.valid] = -1
    roots, first = np.unique(label[w.valid], return_index=True)
    rank = np.empty(roots.size, np.int64)
    rank[np.argsort(first)] = np.arange(roots.size)
    out = np.full(m, -1, np.int64)
    out[w.valid] = rank[np.searchsorted(roots, label[w.valid])]
    k = roots.size
    # a piece is closed when each edge it uses is used by ITS triangles once each way (solids
    # touching along an edge share it, four uses in all, two per piece)
    edge_of_use = np.repeat(np.arange(e.count.size), e.count)
    group = edge_of_use * k + out[e.face]
    order = np.argsort(group, kind="stable")
    g = group[order]
    new = np.concatenate(([True], g[1:] != g[:-1]))
    starts = np.flatnonzero(new)
    uses = np.diff(np.append(starts, g.size))
    forward = np.add.reduceat(e.forward[order].astype(np.int64), starts)
    piece = g[starts] % k
    kind = np.select([uses == 1, uses > 2, forward != 1], [1, 2, 3], 0)
    counts = {code: np.bincount(piece[kind == code], minlength=k) for code in (1, 2, 3)}
    rows = np.flatnonzero(w.valid)
    origin = w.mesh.vertices[w.mesh.faces[rows[0]], :][0] if rows.size else np.zeros(3)
    det6, _ = signed_volumes6(w.mesh.vertices, w.mesh.faces[rows], origin)
    volumes = np.bincount(out[rows], weights=det6, minlength=k) / 6
    bad = counts[1] + counts[2] + counts[3]
    return Pieces(out, k, bad == 0, counts[1], counts[2], counts[3], volumes)
