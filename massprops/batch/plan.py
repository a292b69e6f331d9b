"""How a batch is cut into tasks: a cost model from file sizes, and chunks of small files.

The model only has to rank work and size chunks, not to predict run times: cost = a fixed
per-file part + a per-byte part (``os.stat``, no read). Measured here (2 shared cores,
read + health + integral in one process): a 12-triangle OBJ ~0.9 ms; ~25 ns per byte of
binary STL and 60-95 ns per byte of OBJ text.
"""

from __future__ import annotations

import os
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field

PER_FILE_S = 1e-3
"""Fixed cost of one file (open, parse set-up, health checks and integral of a tiny mesh)."""

PER_BYTE_S = 5e-8
"""Cost per byte of file, between binary STL (~25 ns) and OBJ text (~60-95 ns)."""

LOCAL_CHUNK_S = 0.05
"""Target cost of a task in a local pool: a task's round trip (~0.1 ms) stays below 1 % of it,
and chunks stay small enough to balance two workers near the end of a batch."""

CLUSTER_CHUNK_S = 0.5
"""Target cost of a task on a cluster, where a round trip through the scheduler costs ms."""

MAX_CHUNK_FILES = 256
"""At most this many files in one task (bounds what one lost task costs to redo)."""

POOL_MIN_S = 0.5
"""A local pool is started only for at least this much estimated work: starting its workers
(a fresh interpreter importing numpy and massprops, ~0.2 s here) must pay for itself."""


@dataclass
class Chunk:
    """Inputs that travel as one task, in input order.

    inputs : paths (str), or one input that must run in this process (``-``, a BadInput).
    cost : estimated seconds. local : run in this process, never sent to a worker.
    """

    inputs: list = field(default_factory=list)
    cost: float = 0.0
    local: bool = False


def estimate(path: str) -> float:
    """Estimated seconds to inspect ``path`` (PER_FILE_S if it cannot be stat'ed: the worker
    reports why)."""
    try:
        size = os.stat(path).st_size
    except (OSError, ValueError):
        size = 0
    return PER_FILE_S + PER_BYTE_S * size


def chunks(inputs: Iterable, target_s: float, *, single: bool = False) -> Iterator[Chunk]:
    """Cut ``inputs`` (paths, ``-`` and BadInputs, in order) into chunks of about ``target_s``
    estimated seconds, lazily. A file of at least ``target_s`` is a chunk of its own; ``-`` and
    BadInputs are chunks of their own marked local. ``single``: one input per chunk."""
    open_chunk = Chunk()
    for item in inputs:
        if not isinstance(item, str) or item == "-":
            if open_chunk.inputs:
                yield open_chunk
                open_chunk = Chunk()
            yield Chunk([item], PER_FILE_S, local=True)
            continue
        cost = PER_FILE_S if single else estimate(item)
        if single or cost >= target_s:
            if open_chunk.inputs:
                yield open_chunk
                open_chunk = Chunk()
            yield Chunk([item], cost)
            continue
        open_chunk.inputs.append(item)
        open_chunk.cost += cost
        if open_chunk.cost >= target_s or len(open_chunk.inputs) >= MAX_CHUNK_FILES:
            yield open_chunk
            open_chunk = Chunk()
    if open_chunk.inputs:
        yield open_chunk
