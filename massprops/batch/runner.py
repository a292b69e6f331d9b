"""`inspect_many`: tasks out to an executor, records back in input order, every input once.

Scheduling. Chunks (`plan`) are read ahead in input order while the window allows: work
behind the oldest unfinished task worth at most ``workers`` times max(WINDOW_S, that task's
cost, twice the time it has run), so memory stays bounded whatever the batch size and a long
head does not leave the other workers idle. Of these, IN_FLIGHT_PER_WORKER tasks per
worker are out on the executor at a time: the first waiting one, or a large file as soon as it
is in the window (largest first: started late, one worker would finish it alone). Records
leave in input order, the head task's as soon as it is done; the others keep their results.

Failures of the machinery (not of a file: a bad file is a record with its error) are retried
so that every input is still reported exactly once. A task whose future failed (a local worker
killed, e.g. out of memory, breaks the whole pool; Dask gives up on a task after its workers
died a few times) is split into one task per file; a single file that fails again is re-run
alone, with nothing else in flight, so that a crash is only blamed on the file that caused it;
if it fails alone too, its record says so (exit 3). A broken local pool is replaced, unless it
never finished a task (its workers cannot start here): then the batch goes on in this process.

Ctrl-C: `Batch.interrupt` cancels what has not finished, stops the local workers (and waits
for them: no orphans) and returns the records that were finished but not yet handed out, in
input order.
"""

from __future__ import annotations

import os
import time
from collections import deque
from collections.abc import Iterable, Iterator, Sized
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

from massprops.batch import plan
from massprops.batch.inputs import BadInput
from massprops.batch.records import MeshResult, inspect_one
from massprops.errors import ComputationError, UsageError, setting_ref

if TYPE_CHECKING:
    from concurrent.futures import Executor, Future, ProcessPoolExecutor

WINDOW_S = 4.0
"""Estimated seconds of work per worker read ahead behind the oldest unfinished task (where
large files are found early; memory: paths and finished records only)."""

MAX_TASKS_PER_WORKER = 64
"""Hard bound on tasks read ahead per worker (the cost model may underestimate)."""

IN_FLIGHT_PER_WORKER = 2
"""Tasks handed to the executor per worker: one running, one ready to start. More would only
fix the order in the executor's own queue (and be lost work on Ctrl-C)."""

LARGE_TASK_CHUNKS = 4
"""A task costing this many chunk targets is a large file: it goes out before the tasks ahead
of it in the window, so that it does not run alone at the end of the batch."""


@dataclass(eq=False)
class _Slot:
    """One task in the queue: its chunk, its future, and what the retries know about it."""

    chunk: plan.Chunk
    index: int  # position of its first input in the batch
    future: Future | None = None
    results: list[MeshResult] | None = None  # settled here (local inputs, a file given up on)
    alone: bool = False  # a suspect: run with nothing else in flight
    pool: Any = None  # the executor its future belongs to
    started: float | None = None  # time.monotonic() when it was handed out


def inspect_many(paths: Iterable, executor: Executor | None = None, *, jobs: int | None = None,
                 workers: int | None = None, chunk_s: float | None = None,
                 **options: Any) -> Batch:
    """Inspect every path; iterate the result for one `MeshResult` per input, in input order.

    paths : paths (str or os.PathLike; ``-`` = standard input, read in this process) and
        `BadInput` records, e.g. from `expand_inputs`; consumed lazily.
    executor : any ``concurrent.futures.Executor`` (e.g. ``Client.get_executor()`` of
        dask.distributed); it must be able to import massprops. It is not shut down here.
        Default: this process for ``jobs=1`` or a batch too small for a pool (< POOL_MIN_S of
        estimated work), else a local pool of ``jobs`` processes, stopped at the end.
    jobs : worker processes of the local pool (default `default_jobs`: the usable cores).
    workers : how many tasks ``executor`` runs at once (sizes the window; default: its
        ``_max_workers`` if it has one, else 8).
    chunk_s : target estimated seconds per task (default: `plan.LOCAL_CHUNK_S` for a local
        pool, `plan.CLUSTER_CHUNK_S` for any other executor).
    options : keyword arguments of `massprops.inspection.file.inspect_file` (``unit``, ``density``,
        ``mass``, ``allow_open``, ``format``, ...), the same for every file.

    Raises UsageError for jobs < 1; the first record raises TypeError for an option
    inspect_file does not take (checked once a local pool is booting: checking imports numpy,
    which then overlaps the pool's start). Use the Batch as a context manager (or call
    ``close``) when stopping before the end.
    """
    if jobs is not None and jobs < 1:
        raise UsageError(f"{setting_ref('jobs')} must be at least 1, got {jobs}")
    return Batch(paths, executor, jobs, options, workers, chunk_s)


def _check_options(options: dict[str, Any]) -> None:
    # deferred: a batch run in this process loads no pool or worker code
    from massprops.inspection.file import inspect_file

    code = inspect_file.__code__
    taken = set(code.co_varnames[1 : code.co_argcount + code.co_kwonlyargcount]) - {"name"}
    unknown = sorted(set(options) - taken)
    if unknown:
        raise TypeError(f"inspect_many: inspect_file takes no option {', '.join(unknown)}")


class Batch(Iterator[MeshResult]):
    """The records of a batch, in input order (see `inspect_many`).

    total : the number of inputs: known from the start if ``paths`` has a length, else once
        all have been read (None until then).
    seen : how many inputs have been read so far.
    parallel : whether tasks go to worker processes or an executor (False: this process).
    """

    def __init__(self, paths: Iterable, executor: Executor | None, jobs: int | None,
                 options: dict[str, Any], workers: int | None, chunk_s: float | None) -> None:
        # deferred: a batch run in this process loads no pool or worker code
        from massprops.batch.pool import default_jobs

        self._paths = iter(paths)
        self._executor = executor
        self._own_pool = False
        self._jobs = default_jobs() if jobs is None and executor is None else (jobs or 1)
        self._workers = workers
        self._chunk_s = chunk_s
        self._options = dict(options)
        self._cwd = os.getcwd()
        self._slots: deque[_Slot] = deque()
        self._queued_cost = 0.0  # estimated seconds of the chunks in _slots
        self._ready: deque[MeshResult] = deque()
        self._chunks: Iterator[plan.Chunk] | None = None
        self._lookahead: deque[plan.Chunk] = deque()
        self._local: Iterator[MeshResult] | None = None
        self._exhausted = False
        self._alone = False
        self._inline = False  # tasks run here: a local pool whose workers could not start
        self._pool_worked = False  # the current local pool has finished a task
        self._seen = 0
        self._closed = False
        self.total: int | None = len(paths) if isinstance(paths, Sized) else None
        self.parallel = False

    # --- iteration ---------------------------------------------------------------------------
    @property
    def seen(self) -> int:
        return self._seen

    def __iter__(self) -> Batch:
        return self

    def __next__(self) -> MeshResult:
        if self._closed:
            raise StopIteration
        if self._local is None and self._chunks is None:
            self._start()
        if self._local is not None:
            try:
                return next(self._local)
            except StopIteration:
                self.total = self._seen
                self.close()
                raise
        while not self._ready:
            self._fill()
            if not self._slots:
                self.total = self._seen
                self.close()
                raise StopIteration
            head = self._slots[0]
            results = self._settle(head)
            if results is not None:
                self._queued_cost -= self._slots.popleft().chunk.cost
                self._ready.extend(results)
        return self._ready.popleft()

    def __enter__(self) -> Batch:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    # --- start: this process, a local pool, or the caller's executor ---------------------------
    def _start(self) -> None:
        if self._executor is None and self._jobs == 1:
            _check_options(self._options)
            self._run_here(plan.chunks(self._counted(), 0.0, single=True))
            return
        local_pool = self._executor is None
        if self._chunk_s is None:
            self._chunk_s = plan.LOCAL_CHUNK_S if local_pool or _is_local(self._executor) \
                else plan.CLUSTER_CHUNK_S
        self._chunks = plan.chunks(self._counted(), self._chunk_s)
        if local_pool:  # look ahead: is there work for a pool, for how many workers?
            work, tasks, more = 0.0, 0, True
            while work < plan.POOL_MIN_S or tasks < 2:
                chunk = next(self._chunks, None)
                if chunk is None:
                    more = False
                    break
                self._lookahead.append(chunk)
                work += chunk.cost
                tasks += not chunk.local
            if not more:  # all read: a pool would cost more than it saves
                _check_options(self._options)
                self._run_here(iter(self._lookahead))
                return
            self._workers = self._jobs
            self._new_pool()  # its fork server boots meanwhile
        elif self._workers is None:
            self._workers = getattr(self._executor, "_max_workers", None) or 8
        _check_options(self._options)
        self.parallel = True

    def _counted(self) -> Iterator:
        for path in self._paths:
            self._seen += 1
            yield path if isinstance(path, (str, BadInput)) else os.fsdecode(path)

    def _run_here(self, chunks: Iterator[plan.Chunk]) -> None:
        self._local = (self._here(item) for chunk in chunks for item in chunk.inputs)

    def _here(self, item: str | BadInput) -> MeshResult:
        if isinstance(item, BadInput):
            return MeshResult.failed(item.name, item.error, keep=True)
        return inspect_one(item, self._options, keep_exception=True)

    def _new_pool(self) -> None:
        # deferred: a batch run in this process loads no pool or worker code
        from massprops.batch.pool import local_pool

        self._executor = local_pool(cast(int, self._workers))  # _start set it first
        self._own_pool = True
        self._pool_worked = False

    # --- the window ----------------------------------------------------------------------------
    # the window's methods run once _start has set _workers, _chunk_s and _chunks
    def _room(self) -> bool:
        tasks = len(self._slots)
        if tasks < 2 * cast(int, self._workers):
            return True
        if tasks >= MAX_TASKS_PER_WORKER * cast(int, self._workers):
            return False
        head = self._slots[0]
        # a head running longer than estimated (the model is rough) earns a longer window
        running = time.monotonic() - head.started if head.started is not None else 0.0
        queued = self._queued_cost - head.chunk.cost
        return queued < cast(int, self._workers) * max(WINDOW_S, head.chunk.cost, 2 * running)

    def _fill(self) -> None:
        while not self._exhausted and self._room():
            chunk = self._lookahead.popleft() if self._lookahead \
                else next(cast(Iterator[plan.Chunk], self._chunks), None)
            if chunk is None:
                self._exhausted = True
                break
            self._slots.append(_Slot(chunk, self._index_of_next()))
            self._queued_cost += chunk.cost
        self._top_up()

    def _index_of_next(self) -> int:
        last = self._slots[-1] if self._slots else None
        return 0 if last is None else last.index + len(last.chunk.inputs)

    def _running(self) -> list[_Slot]:
        return [s for s in self._slots if s.future is not None and not s.future.done()]

    def _top_up(self) -> None:
        """Keep IN_FLIGHT_PER_WORKER tasks per worker out; the next is the first waiting task,
        or the costliest one in the window if that is a large file (started early, it does
        not leave one worker alone with it at the end)."""
        if self._alone:
            return
        free = IN_FLIGHT_PER_WORKER * cast(int, self._workers) - len(self._running())
        while free > 0:
            waiting = [s for s in self._slots if s.future is None and s.results is None
                       and not s.chunk.local and not s.alone]
            if not waiting:
                return
            largest = max(waiting, key=lambda s: s.chunk.cost)
            large = largest.chunk.cost >= LARGE_TASK_CHUNKS * cast(float, self._chunk_s)
            self._submit(largest if large else waiting[0])
            free -= 1

    def _submit(self, slot: _Slot) -> None:
        # deferred: a batch run in this process loads no pool or worker code
        from concurrent.futures import BrokenExecutor, Future

        from massprops.batch.worker import run_chunk

        args = (self._cwd, slot.chunk.inputs, self._options, self._own_pool, slot.index)
        if self._inline:
            slot.future = Future()
            slot.future.set_result([self._here(item) for item in slot.chunk.inputs])
            slot.pool, slot.started = None, time.monotonic()
            return
        try:  # not inline: a local pool or the caller's executor
            slot.future = cast("Executor", self._executor).submit(run_chunk, *args)
        except BrokenExecutor:
            if not self._own_pool:
                raise
            self._replace_pool()  # a new pool, or none (workers cannot start): this process
            self._submit(slot)
            return
        except Exception as exc:  # shut down, or cannot start workers: the task fails below
            slot.future = Future()
            slot.future.set_exception(exc)
        slot.pool, slot.started = self._executor, time.monotonic()

    # --- finishing the head --------------------------------------------------------------------
    def _settle(self, slot: _Slot) -> list[MeshResult] | None:
        """The records of ``slot`` (waiting for them), or None when retries replaced it."""
        if slot.results is not None:
            return slot.results
        if slot.chunk.local:
            return [self._here(item) for item in slot.chunk.inputs]
        if slot.alone and slot.future is None:
            self._run_alone(slot)
        elif slot.future is None:
            self._submit(slot)  # the head runs now, whatever else is out
        self._wait_for(slot)  # the slot was handed out above or before: it has a future
        error = _failure(cast("Future", slot.future))
        if error is None:
            self._end_alone(slot)
            self._pool_worked |= self._own_pool and slot.pool is self._executor
            return cast("Future", slot.future).result()
        if self._own_pool and slot.pool is self._executor and _broken(error):
            self._replace_pool(keep=slot)
        self._retry(slot, error)
        return None

    def _wait_for(self, slot: _Slot) -> None:
        """Wait until ``slot`` is done, handing out more tasks as others finish."""
        from concurrent.futures import FIRST_COMPLETED, wait

        while not cast("Future", slot.future).done():  # handed out: _settle
            self._fill()  # reads on while the head runs long, and hands out tasks
            wait([cast("Future", s.future) for s in self._running()],
                 return_when=FIRST_COMPLETED)

    def _retry(self, slot: _Slot, error: BaseException) -> None:
        """Split a failed task into single files, or isolate a single file, or give up on it."""
        position = self._slots.index(slot)
        if len(slot.chunk.inputs) > 1:  # each file waits for its turn (see _top_up)
            self._slots.remove(slot)
            self._queued_cost -= slot.chunk.cost
            for k, path in enumerate(slot.chunk.inputs):
                single = _Slot(plan.Chunk([path], plan.estimate(path)), slot.index + k)
                self._slots.insert(position + k, single)
                self._queued_cost += single.chunk.cost
            return
        if not slot.alone:
            slot.alone, slot.future = True, None
            return
        self._end_alone(slot)
        path = slot.chunk.inputs[0]
        lost = ComputationError(
            f"{path}: the worker inspecting it stopped ({type(error).__name__}: {error}); "
            f"inspect it alone ({setting_ref('jobs')} 1) to see why")
        slot.results = [MeshResult.failed(path, lost)]

    def _run_alone(self, slot: _Slot) -> None:
        """Wait until nothing else runs, then run ``slot`` by itself."""
        from concurrent.futures import wait

        self._alone = True
        wait([cast("Future", s.future) for s in self._running() if s is not slot])
        self._submit(slot)  # on a pool broken meanwhile, _submit replaces it first

    def _end_alone(self, slot: _Slot) -> None:
        if slot.alone and self._alone:
            self._alone = False  # what waited while the suspect ran alone goes out again

    def _replace_pool(self, keep: _Slot | None = None) -> None:
        """A local worker died: the pool is broken. Start a new one and resubmit every task
        that was still out on the old one (its results are lost with it), but ``keep``."""
        # deferred: a batch run in this process loads no pool or worker code
        from massprops.batch.pool import stop_pool

        old = self._executor  # replaced only when it is our own local pool
        # also waits until the old pool has failed or cancelled all its tasks
        stop_pool(cast("ProcessPoolExecutor", old))
        self._pool_worked |= any(s.pool is old and s.future is not None and s.future.done()
                                 and _failure(s.future) is None for s in self._slots)
        if self._pool_worked:
            self._new_pool()
        else:  # it never finished a task: its workers cannot start here; go on in this process
            self._executor, self._own_pool, self._inline = None, False, True
        for slot in self._slots:  # back to waiting: _top_up hands them out again
            if slot is not keep and slot.pool is old and slot.future is not None \
                    and _failure(slot.future) is not None:
                slot.future = None

    # --- stopping ------------------------------------------------------------------------------
    def interrupt(self) -> list[MeshResult]:
        """Stop now (Ctrl-C): cancel what has not finished, stop the local workers, and return
        the records that were finished but not yet handed out, in input order (an input still
        running when this was called is left out)."""
        out = list(self._ready)
        self._ready.clear()
        for slot in self._slots:
            if slot.results is not None:
                out.extend(slot.results)
            elif slot.future is not None and slot.future.done() and _failure(slot.future) is None:
                out.extend(slot.future.result())
        self._stop(hard=True)
        return out

    def close(self) -> None:
        """Release the workers: wait for a local pool's processes to end (stopping them if the
        batch did not finish); cancel tasks still queued on a caller's executor."""
        self._stop(hard=bool(self._slots) or not self._exhausted)

    def _stop(self, hard: bool) -> None:
        if self._closed:
            return
        self._closed = True
        for slot in self._slots:
            if slot.future is not None:
                slot.future.cancel()
        self._slots.clear()
        if self._own_pool:
            # deferred: a batch run in this process loads no pool or worker code
            from massprops.batch.pool import stop_pool

            pool = cast("ProcessPoolExecutor", self._executor)  # our own: a local pool
            if hard:
                stop_pool(pool)
            else:
                pool.shutdown(wait=True)


def _failure(future: Future) -> BaseException | None:
    """The future's exception once it is done (waiting for it), cancellation included."""
    from concurrent.futures import CancelledError

    try:
        return future.exception()
    except CancelledError as exc:
        return exc


def _broken(error: BaseException | None) -> bool:
    from concurrent.futures import BrokenExecutor

    return isinstance(error, BrokenExecutor)


def _is_local(executor: Executor | None) -> bool:
    from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

    return isinstance(executor, (ProcessPoolExecutor, ThreadPoolExecutor))
