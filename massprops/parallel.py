"""Overlap numpy passes on two cores: numpy releases the GIL inside its loops, so array work on
two threads runs in parallel (long passes split in halves, independent passes side by side)."""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import TypeVar

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


def in_halves(fn: Callable[[int, int], _T], n: int, align: int) -> list[_T]:
    """[fn(0, mid), fn(mid, n)], the first half on a helper thread, mid a multiple of ``align``
    (the caller's block size); a pass shorter than two blocks runs here in one piece."""
    mid = n // 2 // align * align
    if not mid:
        return [fn(0, n)]
    first = in_background(fn, 0, mid)
    second = fn(mid, n)
    return [first(), second]
