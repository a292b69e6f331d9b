"""Vectorised kernels on welded triangle surfaces: edge use counts, connected components,
consistent winding. numpy only, no loop per face.

Triangles given to these kernels are (t, 3) integer arrays of welded ids (see
`massprops.mesh.weld`, which uses this module's `connected_components`, never the reverse).
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from massprops.errors import MeshFormatError
from massprops.parallel import in_halves, sort_in_two

_CHUNK = 1 << 15  # rows per block of chunked passes: temporaries stay in cache, not in new pages
_LOW, _HIGH = (0, 1) if sys.byteorder == "little" else (1, 0)  # uint32 words of a uint64


def id_dtype(n: int) -> type:
    """Narrowest index type for ids below n: int32 halves memory traffic against int64."""
    return np.int32 if n < 2**31 else np.int64


# --- edges ------------------------------------------------------------------------------------
def _edge_keys(tri: np.ndarray, shift: int) -> np.ndarray:
    """(3t,) uint64 key per directed edge a→b, triangle by triangle (edge k of triangle f at
    3f + k): min << shift+1 | max << 1 | (a > b)."""
    t = tri.shape[0]
    keys = np.empty((t, 3), np.uint64)
    s1, one = np.uint64(shift + 1), np.uint64(1)

    def fill(start: int, stop: int) -> None:
        for lo in range(start, stop, _CHUNK):
            a = tri[lo : min(lo + _CHUNK, stop)].astype(np.uint64)
            b = a[:, [1, 2, 0]]
            out = np.minimum(a, b) << s1
            out |= np.maximum(a, b) << one
            out |= a > b
            keys[lo : lo + a.shape[0]] = out

    in_halves(fill, t, _CHUNK)
    return keys.reshape(-1)


def _key_shift(n_ids: int) -> int:
    shift = max(1, (n_ids - 1).bit_length())
    if 2 * shift + 1 > 64:
        raise MeshFormatError(f"{n_ids} distinct vertices: more than the 2**31 massprops handles")
    return shift


@dataclass(frozen=True, eq=False)
class Edges:
    """The undirected edges of a triangle set and how often each direction is used.

    u, v : (e,) int, welded ids, u < v.
    forward, backward : (e,) int64 uses as u→v and as v→u; None when every edge is used exactly
        once each way (a closed, consistently wound 2-manifold: the common case, kept cheap).
    """

    u: np.ndarray
    v: np.ndarray
    forward: np.ndarray | None = None
    backward: np.ndarray | None = None

    @cached_property
    def uses(self) -> np.ndarray:
        """(e,) int64 triangles using each edge."""
        if self.forward is None:
            return np.full(self.u.size, 2, np.int64)
        return self.forward + self.backward

    @cached_property
    def imbalance(self) -> np.ndarray:
        """(e,) int64 forward minus backward uses: zero on every edge of a closed surface."""
        if self.forward is None:
            return np.zeros(self.u.size, np.int64)
        return self.forward - self.backward

    def count(self, what: str) -> int:
        """Edges that are "unbalanced" (imbalance != 0), "conflicting" (|imbalance| > 1: the two
        faces disagree on winding), "open" (one use) or "nonmanifold" (more than two uses)."""
        if self.forward is None:
            return 0
        imbalance, uses = self.imbalance, self.uses
        return int(np.count_nonzero({"unbalanced": imbalance != 0,
                                     "conflicting": np.abs(imbalance) > 1,
                                     "open": uses == 1, "nonmanifold": uses > 2}[what]))


def _undirected_keys(tri: np.ndarray
                     ) -> Callable[[], Callable[[int, int], tuple[np.ndarray, np.ndarray]]]:
    """make_blocks for `sort_in_two`: blocks(lo, hi) gives the key min << 32 | max of every edge
    a→b of triangles lo..hi, as (those with a < b, those with a > b). Written as two uint32 words
    of a uint64: no shifts, and a sorted key splits back into its ids as views."""
    size = min(_CHUNK, tri.shape[0])

    def make_blocks() -> Callable[[int, int], tuple[np.ndarray, np.ndarray]]:
        following = np.empty((size, 3), tri.dtype)
        words = np.empty((size, 3, 2), np.uint32)
        forward = np.empty((size, 3), bool)
        backward = np.empty((size, 3), bool)

        def blocks(lo: int, hi: int) -> tuple[np.ndarray, np.ndarray]:
            k = hi - lo
            a, b, w = tri[lo:hi], following[:k], words[:k]
            b[:, :2] = a[:, 1:]
            b[:, 2] = a[:, 0]
            np.minimum(a, b, out=w[..., _HIGH], casting="unsafe")  # ids are in 0..2**31
            np.maximum(a, b, out=w[..., _LOW], casting="unsafe")
            np.less(a, b, out=forward[:k])
            np.logical_not(forward[:k], out=backward[:k])
            key = w.view(np.uint64).reshape(-1)
            return (np.compress(forward[:k].reshape(-1), key),
                    np.compress(backward[:k].reshape(-1), key))

        return blocks

    return make_blocks


def _strictly_increasing(keys: np.ndarray) -> bool:
    """No key repeats or comes before its predecessor (block by block: no large temporary)."""
    last = keys.size - 1
    return not any(np.any(keys[lo + 1 : hi + 1] <= keys[lo:hi])
                   for lo, hi in ((lo, min(lo + _CHUNK, last)) for lo in range(0, last, _CHUNK)))


def edges(tri: np.ndarray, n_ids: int, *, scratch: np.ndarray | None = None) -> Edges:
    """Edges of (t, 3) triangles of welded ids below ``n_ids``, each with three distinct ids.
    ``scratch``: a uint64 buffer of at least 3t to work in (overwritten), else one is allocated.

    The keys of the edges used forward (a < b) and backward are sorted apart, on two threads; a
    closed, consistently wound 2-manifold is the case where the two lists are equal and have no
    repeats (every edge used once each way). Anything else is counted from all keys together.
    """
    _key_shift(n_ids)  # refuses more ids than the keys hold
    keys, k = sort_in_two(_undirected_keys(tri), tri.shape[0], 3, _CHUNK, scratch)
    forward, backward = keys[:k], keys[k:]
    ids = id_dtype(n_ids)
    if (forward.size == backward.size and _strictly_increasing(forward)
            and np.array_equal(forward, backward)):
        words = forward.view(np.uint32).reshape(-1, 2)
        return Edges(words[:, _HIGH].astype(ids), words[:, _LOW].astype(ids))
    one = np.uint64(1)
    directed = np.concatenate((forward << one, (backward << one) | one))  # the direction as bit 0
    directed.sort()
    und = directed >> one
    first = np.flatnonzero(np.concatenate(([True], und[1:] != und[:-1]))) if und.size else und
    uses = np.diff(np.append(first, und.size))
    back = np.add.reduceat((directed & one).astype(np.int64), first) if first.size else uses
    words = und[first].view(np.uint32).reshape(-1, 2)
    return Edges(words[:, _HIGH].astype(ids), words[:, _LOW].astype(ids), uses - back, back)


# --- connected components -----------------------------------------------------------------------
def connected_components(n: int, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """(n,) label of each node: the smallest node of its component (graph edges u[i]–v[i]).

    Hook every root onto the smallest root across its edges (np.minimum.at), then jump pointers
    until every node points at a root; edges inside one tree are dropped each round. Labels only
    decrease, so no cycle forms; meshes with ids in file order settle in a handful of rounds.
    """
    parent: np.ndarray = np.arange(n, dtype=id_dtype(n))
    # np.minimum.at has a fast loop only for values of the array's own dtype
    u, v = u.astype(parent.dtype, copy=False), v.astype(parent.dtype, copy=False)
    blocks = range(0, u.size, _CHUNK)
    if not all(np.all(u[lo : lo + _CHUNK] < v[lo : lo + _CHUNK]) for lo in blocks):
        u, v = np.minimum(u, v), np.maximum(u, v)  # `edges` gives u < v: no copies then
    while u.size:  # u < v: the ends of the edges still between trees (roots after round one)
        for lo in range(0, u.size, _CHUNK):  # in blocks: the indices' cast to intp stays small
            np.minimum.at(parent, v[lo : lo + _CHUNK], u[lo : lo + _CHUNK])
        _jump_to_roots(parent)
        if not parent.any():  # every node under node 0: one component, nothing to check
            break
        u, v = parent[u], parent[v]
        cross = u != v
        if not np.any(cross):
            break
        u, v = np.minimum(u[cross], v[cross]), np.maximum(u[cross], v[cross])
    return parent


def _jump_to_roots(parent: np.ndarray) -> None:
    """Pointer jumping, in place, until every node points at a root (two jumps per check)."""
    grand = np.empty_like(parent)
    while True:
        np.take(parent, parent, out=grand, mode="clip")  # labels are node numbers: in range
        if np.array_equal(grand, parent):
            return
        np.take(grand, grand, out=parent, mode="clip")


def consistent_flips(tri: np.ndarray, n_ids: int) -> np.ndarray | None:
    """(t,) bool: the triangles to reverse so that every edge shared by exactly two triangles is
    used once each way; in each edge-connected piece the smaller class is chosen (ties keep the
    piece's first triangle). None if no such choice exists (a Möbius strip, a Klein bottle).

    How: on the double cover, node 2f is triangle f kept and 2f+1 reversed; an edge joins the
    states of two neighbours that agree. The surface is orientable iff no triangle's two states
    fall in one component (the same labelling also separates the two orientation classes).
    """
    t = tri.shape[0]
    keys = _edge_keys(tri, _key_shift(n_ids))
    order = np.argsort(keys)
    keys = keys[order]
    und = keys >> np.uint64(1)
    new = np.concatenate(([True], und[1:] != und[:-1], [True]))
    starts = np.flatnonzero(new[:-1])
    pair = starts[np.diff(np.flatnonzero(new)) == 2]  # edges used by exactly two triangles
    f, g = order[pair] // 3, order[pair + 1] // 3
    agree = (keys[pair] & np.uint64(1)) != (keys[pair + 1] & np.uint64(1))  # opposite directions
    flip = (~agree).astype(np.int64)
    node_u = np.concatenate((2 * f, 2 * f + 1))
    node_v = np.concatenate((2 * g + flip, 2 * g + 1 - flip))
    ids = id_dtype(2 * t)
    label = connected_components(2 * t, node_u.astype(ids), node_v.astype(ids))
    kept, reversed_ = label[0::2], label[1::2]
    if np.any(kept == reversed_):
        return None
    piece = np.minimum(kept, reversed_) // 2  # first triangle of the edge-connected piece
    change = kept != kept[piece]
    n_change = np.bincount(piece, weights=change, minlength=t)
    n_total = np.bincount(piece, minlength=t)
    return change ^ (2 * n_change > n_total)[piece]


# --- layout -----------------------------------------------------------------------------------
def is_soup(faces: np.ndarray, n_vertices: int) -> bool:
    """faces is [[0, 1, 2], [3, 4, 5], ...] over all vertices, the layout of an STL file."""
    if faces.shape[0] * 3 != n_vertices:
        return False
    flat = faces.reshape(-1)
    return all(np.array_equal(flat[lo : lo + _CHUNK], np.arange(lo, min(lo + _CHUNK, flat.size)))
               for lo in range(0, flat.size, _CHUNK))
