"""Overlap work on two cores: numpy releases the GIL inside its loops (and a ``nogil`` numba
kernel around its whole call), so work on two threads runs in parallel (long passes split in
halves, independent passes side by side, a cancellable job beside the main one)."""

from __future__ import annotations

import contextlib
import threading
from collections.abc import Callable
from typing import Generic, TypeVar

import numpy as np

_T = TypeVar("_T")


def in_background(fn: Callable[..., _T], *args) -> Callable[[], _T]:
    """Start fn(*args) on a helper thread; the returned function waits for its result (or
    re-raises its exception in the waiting thread)."""
    out: list = []

    def run() -> None:
        try:
            out.append(fn(*args))
        except Exception as exc:  # handed to the waiting thread
            out.append(exc)

    helper = threading.Thread(target=run, daemon=True)
    helper.start()

    def result() -> _T:
        helper.join()
        if isinstance(out[0], Exception):
            raise out[0]
        return out[0]

    return result


def beside(progress: Callable[[float], None], side) -> Callable[[float], None]:
    """The progress callback of a main run with work ``side`` beside it (anything with a
    ``fraction``, e.g. a `CancellableJob`; None: none): the mean of the two fractions."""
    if side is None:
        return progress
    return lambda fraction: progress(0.5 * fraction + 0.5 * side.fraction)


def in_halves(fn: Callable[[int, int], _T], n: int, align: int) -> list[_T]:
    """[fn(0, mid), fn(mid, n)], the first half on a helper thread, mid a multiple of ``align``
    (the caller's block size); a pass shorter than two blocks runs here in one piece."""
    mid = n // 2 // align * align
    if not mid:
        return [fn(0, n)]
    first = in_background(fn, 0, mid)
    second = fn(mid, n)
    return [first(), second]


def sort_in_two(make_blocks: Callable[[], Callable[[int, int], tuple[np.ndarray, np.ndarray]]],
                rows: int, width: int, align: int, out: np.ndarray | None = None
                ) -> tuple[np.ndarray, int]:
    """Keys of two kinds, made and sorted on two threads; (keys, k): keys (width · rows,) uint64,
    keys[:k] the sorted keys of kind 0, keys[k:] those of kind 1. ``out``: a uint64 buffer of at
    least width · rows to hold them (a view of it is returned), else a new array.

    make_blocks() gives each thread its function blocks(lo, hi) (which may reuse buffers of its
    own) returning the keys of rows lo..hi (hi - lo <= ``align``) as two 1-D uint64 arrays (kind
    0, kind 1), ``width`` keys per row in all. Each thread makes the keys of half the rows
    straight into its half of the result, one kind from each end, so no block is kept; after a
    swap that joins each kind, one thread sorts each. Kinds that split the key range (say, by the
    top bit) give one sorted array: two sorts of half the keys instead of one of all.
    """
    keys = np.empty(width * rows, np.uint64) if out is None else out[: width * rows]
    mid = rows // 2 // align * align

    def fill(start: int, stop: int, first: int) -> int:
        """Kind ``first`` from the front of the rows' part of keys, the other from its back;
        returns how many keys went to the front."""
        blocks = make_blocks()
        front, back = width * start, width * stop
        for lo in range(start, stop, align):
            pair = blocks(lo, min(lo + align, stop))
            ahead, behind = pair[first], pair[1 - first]
            keys[front : front + ahead.size] = ahead
            keys[back - behind.size : back] = behind
            front, back = front + ahead.size, back - behind.size
        return front - width * start

    if not mid:
        split = fill(0, rows, 0)
    else:  # [0s of the first half | its 1s | 1s of the second half | its 0s]
        head = in_background(fill, 0, mid, 0)
        tail_ones = fill(mid, rows, 1)
        zeros = head()
        tail_zeros = width * (rows - mid) - tail_ones
        ones = width * mid - zeros + tail_ones
        k = min(tail_zeros, ones)  # bring the trailing 0s forward: swap them with k 1s
        moved = keys[zeros : zeros + k].copy()
        keys[zeros : zeros + k] = keys[keys.size - k :]
        keys[keys.size - k :] = moved
        split = zeros + tail_zeros
    if not mid:  # fewer rows than two blocks: a thread would cost more than the sort it saves
        keys[:split].sort()
        keys[split:].sort()
        return keys, split
    second = in_background(np.ndarray.sort, keys[split:])
    keys[:split].sort()
    second()
    return keys, split


class CancellableJob(Generic[_T]):
    """fn(report) on a helper thread (started with `in_background`), where report(fraction) is
    the job's progress callback: it records the fraction (``job.fraction``, for the waiting
    thread to show) and, once `cancel` was called, raises KeyboardInterrupt inside the job. A job
    that stops cleanly on Ctrl-C between its chunks therefore stops the same way when cancelled
    (signals reach only the main thread, so this is how a helper learns of one)."""

    def __init__(self, fn: Callable[[Callable[[float], None]], _T]) -> None:
        self.fraction = 0.0
        self._cancelled = threading.Event()
        self._finished = threading.Event()

        def job() -> _T:
            try:
                return fn(self._report)
            finally:
                self._finished.set()

        self._result = in_background(job)

    def _report(self, fraction: float) -> None:
        self.fraction = fraction
        if self._cancelled.is_set():
            raise KeyboardInterrupt

    def cancel(self) -> None:
        """Ask the job to stop at its next progress report."""
        self._cancelled.set()

    def result(self, poll: Callable[[], None] | None = None, every: float = 0.1) -> _T:
        """Wait for fn's result (or re-raise its exception here), calling poll() every ``every``
        seconds meanwhile (e.g. to move a progress bar)."""
        if poll is not None:
            while not self._finished.wait(every):
                poll()
        return self._result()

    def stop(self) -> None:
        """Cancel the job and wait until its thread has ended, dropping its result or exception
        (for a caller that has its own outcome to report)."""
        self.cancel()
        with contextlib.suppress(Exception):  # dropped on purpose: see above
            self._result()
