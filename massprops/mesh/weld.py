"""Identify mesh vertices by their exact coordinates (no tolerance): a hash, one sort, an exact
check. Indexed formats split vertices at UV seams and STL is unwelded soup; the topology of the
surface is the topology of the positions."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from massprops.mesh.topology import connected_components, id_dtype
from massprops.parallel import in_halves, sort_in_two

_HASH_MULTIPLIERS = (np.uint64(0x9E3779B97F4A7C15), np.uint64(0xBF58476D1CE4E5B9),
                     np.uint64(0x94D049BB133111EB))  # odd splitmix64 constants, one per axis
_FINAL_MULTIPLIER = np.uint64(0xD6E8FEB86659FD93)
_CHUNK = 1 << 15  # rows per block of chunked passes: a block's temporaries stay in L2


# --- weld: file vertices -> distinct positions ---------------------------------------------------
def _sorted_keys(v: np.ndarray, shift: int, prefix_bits: int, out: np.ndarray | None
                 ) -> np.ndarray:
    """(n,) uint64, sorted: a hash of each (n, 3) float64 coordinate row in the high bits and the
    row index in the low ``shift`` bits, so equal rows are adjacent, each group in file order.
    Made and sorted on two threads, split by the hash's top bit (see `sort_in_two`)."""
    s29, s31 = np.uint64(29), np.uint64(31)
    high = ~np.uint64((1 << max(64 - prefix_bits, shift)) - 1)
    top = np.uint64(1 << 63)
    size = min(_CHUNK, v.shape[0])

    def make_blocks() -> Callable[[int, int], tuple[np.ndarray, np.ndarray]]:
        columns = np.empty((3, size))  # x, y, z rows: contiguous passes
        folded = np.empty((3, size), np.uint64)
        hashes = np.empty(size, np.uint64)
        low = np.empty(size, bool)
        high_bit = np.empty(size, bool)
        rows = np.arange(size, dtype=np.uint64)

        def blocks(lo: int, hi: int) -> tuple[np.ndarray, np.ndarray]:
            k = hi - lo
            c, f, x = columns[:, :k], folded[:, :k], hashes[:k]
            np.add(v[lo:hi].T, 0.0, out=c)  # -0.0 + 0.0 = +0.0: equal values, equal bits
            t = c.view(np.uint64)
            np.right_shift(t, s29, out=f)  # float32-born values end in 29 zero bits: fold
            t ^= f  # the high bits down, then the multiplies carry them up again
            np.multiply(t[0], _HASH_MULTIPLIERS[0], out=x)
            for axis in (1, 2):
                t[axis] *= _HASH_MULTIPLIERS[axis]
                x ^= t[axis]
            np.right_shift(x, s31, out=f[0])
            x ^= f[0]
            x *= _FINAL_MULTIPLIER
            x &= high
            np.add(rows[:k], np.uint64(lo), out=f[1])
            x |= f[1]
            np.less(x, top, out=low[:k])
            np.logical_not(low[:k], out=high_bit[:k])
            return np.compress(low[:k], x), np.compress(high_bit[:k], x)

        return blocks

    return sort_in_two(make_blocks, v.shape[0], 1, _CHUNK, out)[0]


def _run_starts(key: np.ndarray, shift: int) -> np.ndarray:
    """(n,) bool: sorted key i starts a run of equal hash prefixes (key 0 always does)."""
    out = np.empty(key.size, bool)
    out[:1] = True
    low = np.uint64((1 << shift) - 1)
    for lo in range(1, key.size, _CHUNK):
        hi = min(lo + _CHUNK, key.size)
        np.greater(key[lo:hi] ^ key[lo - 1 : hi - 1], low, out=out[lo:hi])
    return out


def _equal_to_previous(v: np.ndarray, order: np.ndarray) -> np.ndarray:
    """(n-1,) bool: row order[i+1] of v equals row order[i], exactly."""
    out = np.empty(max(order.size - 1, 0), bool)
    for lo in range(0, out.size, _CHUNK):
        hi = min(lo + _CHUNK, out.size)
        rows = np.take(v, order[lo : hi + 1], axis=0)
        np.all(rows[1:] == rows[:-1], axis=1, out=out[lo:hi])
    return out


def _untangle(v: np.ndarray, order: np.ndarray, tied: np.ndarray, same: np.ndarray) -> None:
    """Hash collision repair, in place: inside every run of equal hash prefixes that holds
    different coordinates, sort by the exact coordinates (stable: file order among equals)."""
    run = np.concatenate(([0], np.cumsum(~tied)))
    pos = np.flatnonzero(np.isin(run, run[1:][tied & ~same]))
    rows = v[order[pos]]
    order[pos] = order[pos][np.lexsort((rows[:, 2], rows[:, 1], rows[:, 0], run[pos]))]
    pairs = pos[pos > 0]
    same[pairs - 1] = np.all(v[order[pairs]] == v[order[pairs - 1]], axis=1)


def _first_use_ids(order: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Number the runs of equal rows of the sorted ``order`` (``starts``: where each run begins)
    by their first use in the file. Returns inv and reps as `weld` does.

    File order keeps neighbouring vertices close in id: later gathers stay in cache and the
    connected-components pass settles in a few rounds. Written to allocate little (fresh pages
    cost more than the arithmetic here): the ids go to their rows block by block.
    """
    n = order.size
    firsts = np.compress(starts, order)  # ties sort by file index: a run's first is its first use
    inv: np.ndarray = np.zeros(n, id_dtype(n))  # first as scratch: 1 + the rank of each first use
    inv[firsts] = 1
    np.cumsum(inv, out=inv)
    new_id = inv[firsts]
    new_id -= 1
    reps = np.empty(firsts.size, np.int64)
    reps[new_id] = firsts

    def scatter(start: int, stop: int) -> None:
        """inv[order[i]] = new_id[run of sorted row i] for start <= i < stop."""
        run = np.count_nonzero(starts[:start]) - 1
        for lo in range(start, stop, _CHUNK):
            hi = min(lo + _CHUNK, stop)
            runs = np.cumsum(starts[lo:hi], dtype=np.intp)
            runs += run
            run = int(runs[-1])
            inv[order[lo:hi]] = new_id[runs]  # a permutation: the halves write apart

    in_halves(scatter, n, _CHUNK)
    return inv, reps


def _rows_match(v: np.ndarray, reps: np.ndarray, inv: np.ndarray) -> bool:
    """Every row of v equals the row of its id's first vertex, exactly."""
    def match(start: int, stop: int) -> bool:
        first = np.empty((min(_CHUNK, stop - start), 3))
        for lo in range(start, stop, _CHUNK):
            hi = min(lo + _CHUNK, stop)
            rows = first[: hi - lo]
            # ids and reps are in range by construction: mode="clip" skips the bounds checks
            np.take(v, np.take(reps, inv[lo:hi], mode="clip"), axis=0, out=rows, mode="clip")
            if not np.array_equal(rows, v[lo:hi]):
                return False
        return True

    return all(in_halves(match, v.shape[0], _CHUNK))


def weld(vertices: np.ndarray, *, prefix_bits: int = 64, scratch: np.ndarray | None = None
         ) -> tuple[np.ndarray, np.ndarray]:
    """Identify vertices by exact coordinates (-0.0 == 0.0; no tolerance).

    vertices : (n, 3) float64.
    Returns ``inv`` (n,) int32 (int64 past 2**31), the welded id of each vertex, ids numbered in
    order of first use; and ``reps`` (u,) int64, the first vertex of each id (ascending).
    ``prefix_bits`` < 64 weakens the hash, for tests of the collision repair only.
    ``scratch`` : a uint64 buffer of at least n to work in (its contents are overwritten), so a
    caller can lend the same memory to several passes; else one is allocated.

    How: sort a hash in the high bits with the row index packed into the low bits (np.sort of
    uint64, no argsort), so equal coordinates end up adjacent. Then every vertex is compared with
    the first vertex of its run; that comparison is the exact check. A hash collision shows as a
    run holding two positions and is repaired by sorting that run by the coordinates themselves.
    """
    n = vertices.shape[0]
    if n == 0:
        return np.empty(0, np.int32), np.empty(0, np.int64)
    v = np.ascontiguousarray(vertices)
    shift = max(1, (n - 1).bit_length())
    key = _sorted_keys(v, shift, prefix_bits, scratch)
    starts = _run_starts(key, shift)
    np.bitwise_and(key, np.uint64((1 << shift) - 1), out=key)
    order = key.view(np.int64)
    inv, reps = _first_use_ids(order, starts)
    if not _rows_match(v, reps, inv):
        tied = ~starts[1:]
        same = _equal_to_previous(v, order)
        _untangle(v, order, tied, same)
        starts[1:] = ~same
        inv, reps = _first_use_ids(order, starts)
    return inv, reps


# --- near weld: the two sides of a round-off crack --------------------------------------------
def near_groups(points: np.ndarray, tol: float) -> np.ndarray:
    """(k,) index of the point each of ``points`` (k, 3) is welded to: its group's first point,
    or itself. Points within ``tol`` of each other in every coordinate form a group (chains
    included); a group wider than ``tol`` on some axis is not a cluster of one position's copies
    but a run of distinct points, and is left alone."""
    from scipy.spatial import cKDTree  # only a mesh with open edges gets here

    k = points.shape[0]
    pairs = cKDTree(points).query_pairs(tol, p=np.inf, output_type="ndarray")
    if not pairs.size:
        return np.arange(k)
    label = connected_components(k, pairs[:, 0], pairs[:, 1]).astype(np.int64)
    low = np.full((k, 3), np.inf)
    high = np.full((k, 3), -np.inf)
    np.minimum.at(low, label, points)
    np.maximum.at(high, label, points)
    narrow = np.all(high - low <= tol, axis=1)
    return np.where(narrow[label], label, np.arange(k))
