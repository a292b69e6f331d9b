"""Identify mesh vertices by their exact coordinates (no tolerance): a hash, one sort, an exact
check. Indexed formats split vertices at UV seams and STL is unwelded soup; the topology of the
surface is the topology of the positions."""

from __future__ import annotations

import numpy as np

from massprops.parallel import in_halves

_SIGN_BIT = np.uint64(1 << 63)
_HASH_MULTIPLIERS = (np.uint64(0x9E3779B97F4A7C15), np.uint64(0xBF58476D1CE4E5B9),
                     np.uint64(0x94D049BB133111EB))  # odd splitmix64 constants
_CHUNK = 1 << 16  # rows per block of chunked passes: temporaries stay in cache, not in new pages


def id_dtype(n: int) -> type:
    """Narrowest index type for ids below n: int32 halves memory traffic against int64."""
    return np.int32 if n < 2**31 else np.int64


# --- weld: file vertices -> distinct positions ---------------------------------------------------
def _sort_keys(bits: np.ndarray, shift: int, prefix_bits: int) -> np.ndarray:
    """(n,) uint64: a hash of each (n, 3) coordinate bit-pattern row in the high bits and the row
    index in the low ``shift`` bits, so one plain sort groups equal rows, each group in file order.
    """
    n = bits.shape[0]
    key = np.empty(n, np.uint64)
    s29, s31 = np.uint64(29), np.uint64(31)
    high = ~np.uint64((1 << max(64 - prefix_bits, shift)) - 1)

    def fill(start: int, stop: int) -> None:
        for lo in range(start, stop, _CHUNK):
            b = bits[lo : min(lo + _CHUNK, stop)]
            if np.any(b == _SIGN_BIT):  # -0.0 == 0.0 but their bit patterns differ
                b = np.where(b == _SIGN_BIT, np.uint64(0), b)
            t = b ^ (b >> s29)  # float32-born values end in 29 zero bits: fold high bits down
            x = t[:, 0] * _HASH_MULTIPLIERS[0]  # the multiply carries low bits into high ones
            x ^= x >> s31
            for k in (1, 2):
                x ^= t[:, k]
                x *= _HASH_MULTIPLIERS[k]
                x ^= x >> s31
            x &= high
            x |= np.arange(lo, lo + x.size, dtype=np.uint64)
            key[lo : lo + x.size] = x

    in_halves(fill, n, _CHUNK)
    return key


def _same_prefix(key: np.ndarray, shift: int) -> np.ndarray:
    """(n-1,) bool: sorted key i+1 has the same hash prefix as key i."""
    out = np.empty(max(key.size - 1, 0), bool)
    low = np.uint64((1 << shift) - 1)
    for lo in range(0, out.size, _CHUNK):
        hi = min(lo + _CHUNK, out.size)
        np.less_equal(key[lo + 1 : hi + 1] ^ key[lo:hi], low, out=out[lo:hi])
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


def _first_use_ids(order: np.ndarray, same: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Number the runs of equal rows of the sorted ``order`` by their first use in the file.

    File order keeps neighbouring vertices close in id: later gathers stay in cache and the
    connected-components pass settles in a few rounds. Returns inv and reps as `weld` does.
    Written to allocate little: fresh pages cost more than the arithmetic here.
    """
    n = order.size
    flags = np.empty(n, bool)  # first, "row starts a run"; then, "row is a first use"
    flags[0] = True
    np.logical_not(same, out=flags[1:])
    starts = np.flatnonzero(flags)
    firsts = order[starts]  # ties sort by file index, so a run's first row is its first use
    lengths = np.empty_like(starts)
    np.subtract(starts[1:], starts[:-1], out=lengths[:-1])
    lengths[-1] = n - starts[-1]
    flags[:] = False
    flags[firsts] = True
    inv = np.empty(n, id_dtype(n))
    np.cumsum(flags, out=inv)  # scratch: 1 + rank of each first use
    new_id = inv[firsts]
    new_id -= 1
    inv[order] = np.repeat(new_id, lengths)
    return inv, np.flatnonzero(flags)


def _rows_match(v: np.ndarray, reps: np.ndarray, inv: np.ndarray) -> bool:
    """Every row of v equals the row of its id's first vertex, exactly."""
    def match(start: int, stop: int) -> bool:
        for lo in range(start, stop, _CHUNK):
            hi = min(lo + _CHUNK, stop)
            if not np.array_equal(np.take(v, reps[inv[lo:hi]], axis=0), v[lo:hi]):
                return False
        return True

    return all(in_halves(match, v.shape[0], _CHUNK))


def weld(vertices: np.ndarray, *, prefix_bits: int = 64) -> tuple[np.ndarray, np.ndarray]:
    """Identify vertices by exact coordinates (-0.0 == 0.0; no tolerance).

    vertices : (n, 3) float64.
    Returns ``inv`` (n,) int32 (int64 past 2**31), the welded id of each vertex, ids numbered in
    order of first use; and ``reps`` (u,) int64, the first vertex of each id (ascending).
    ``prefix_bits`` < 64 weakens the hash, for tests of the collision repair only.

    How: sort a hash in the high bits with the row index packed into the low bits (one np.sort of
    uint64, no argsort), so equal coordinates end up adjacent. Then every vertex is compared with
    the first vertex of its run; that comparison is the exact check. A hash collision shows as a
    run holding two positions and is repaired by sorting that run by the coordinates themselves.
    """
    n = vertices.shape[0]
    if n == 0:
        return np.empty(0, np.int32), np.empty(0, np.int64)
    v = np.ascontiguousarray(vertices)
    shift = max(1, (n - 1).bit_length())
    key = _sort_keys(v.view(np.uint64), shift, prefix_bits)
    key.sort()
    same = _same_prefix(key, shift)
    np.bitwise_and(key, np.uint64((1 << shift) - 1), out=key)
    order = key.view(np.int64)
    inv, reps = _first_use_ids(order, same)
    if not _rows_match(v, reps, inv):
        tied = same
        same = _equal_to_previous(v, order)
        _untangle(v, order, tied, same)
        inv, reps = _first_use_ids(order, same)
    return inv, reps
