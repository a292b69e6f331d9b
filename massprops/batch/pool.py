"""Executors: the local process pool (start method, start-up, hard stop) and the Dask one."""

from __future__ import annotations

import contextlib
import os
from typing import TYPE_CHECKING, Any

from massprops.errors import UsageError, setting_ref

if TYPE_CHECKING:  # concurrent.futures (and logging) load only when a pool is used
    from concurrent.futures import Executor, ProcessPoolExecutor


def default_jobs() -> int:
    """The cores this process may run on (its CPU affinity; all cores where that is unknown)."""
    counter = getattr(os, "process_cpu_count", None)  # Python 3.13+
    if counter is not None:
        return max(1, counter() or 1)
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except (AttributeError, OSError):
        return max(1, os.cpu_count() or 1)


INSPECT_PRELOAD = ("massprops.batch.worker", "massprops.inspection.file")
"""What a batch's fork server imports before its workers fork: numpy and the mesh code."""


def local_pool(jobs: int, preload: tuple[str, ...] = INSPECT_PRELOAD) -> ProcessPoolExecutor:
    """``jobs`` worker processes that ignore Ctrl-C (see `worker.init_local_worker`).

    Start method: a fork server where the platform has one. Its workers fork from a clean
    server that imported the modules ``preload`` names once (numpy and the mesh code: ~0.2 s
    once per batch), never from this process: forking a process with threads (numpy's BLAS, a
    caller's) can deadlock, and a fork would copy unflushed output. Elsewhere (Windows) fresh
    interpreters (spawn). The first pool of a process starts its server: a later pool's
    ``preload`` is what that server imported."""
    import multiprocessing
    from concurrent.futures import ProcessPoolExecutor

    context: multiprocessing.context.BaseContext
    if "forkserver" in multiprocessing.get_all_start_methods():
        from multiprocessing import forkserver

        context = multiprocessing.get_context("forkserver")
        # imported once in the server, not again in every worker
        context.set_forkserver_preload(list(preload))
        forkserver.ensure_running()  # boots in the background until the first worker is due
    else:
        context = multiprocessing.get_context("spawn")
    # deferred: a batch too small for a pool never loads the worker side
    from massprops.batch.worker import init_local_worker

    return ProcessPoolExecutor(jobs, mp_context=context, initializer=init_local_worker)


def stop_pool(pool: ProcessPoolExecutor) -> None:
    """Stop ``pool`` now: cancel what has not started, end the workers (a running task is
    lost), and wait until they are gone (no orphan processes)."""
    # shutdown() forgets the processes and the manager thread: keep hold of them first
    processes = list((getattr(pool, "_processes", None) or {}).values())
    manager = getattr(pool, "_executor_manager_thread", None)
    pool.shutdown(wait=False, cancel_futures=True)
    for process in processes:
        with contextlib.suppress(Exception):  # already gone: nothing to stop
            process.terminate()
    for process in processes:
        with contextlib.suppress(Exception):
            process.join(_STOP_WAIT_S)
            if process.is_alive():  # terminate is SIGTERM; a worker stuck in C gets SIGKILL
                process.kill()
                process.join(_STOP_WAIT_S)
    if manager is not None:
        manager.join(_STOP_WAIT_S)


_STOP_WAIT_S = 10.0
"""How long a stopped worker may take to end before it is killed."""


def dask_executor(address: str, *, timeout: float = 10.0) -> tuple[Executor, int, Any]:
    """(executor, worker threads, client) for the Dask scheduler at ``address``.

    The executor is ``Client.get_executor(pure=False)``; close the client when done. Raises
    UsageError if dask.distributed is not installed (saying what to install) or the scheduler
    cannot be reached within ``timeout`` seconds."""
    try:
        from distributed import Client
    except ImportError as exc:
        raise UsageError(
            f"{setting_ref('scheduler')} needs dask.distributed, which is not installed; install "
            "it with: "
            "pip install 'massprops[dask]'") from exc
    try:
        client = Client(address, timeout=timeout, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise UsageError(f"cannot reach the Dask scheduler at {address!r}: {exc}") from exc
    threads = sum(client.nthreads().values())
    return client.get_executor(pure=False), max(1, threads), client


def end_helper_processes() -> None:
    """Stop the fork server and resource tracker a local pool started, and wait for them, for
    a process about to exit (the CLI): they would end by themselves once it has exited, but as
    orphans. Private multiprocessing API, so only where present; nothing if never started."""
    import sys

    for module, name in (("multiprocessing.forkserver", "_forkserver"),
                         ("multiprocessing.resource_tracker", "_resource_tracker")):
        helper = getattr(sys.modules.get(module), name, None)
        stop = getattr(helper, "_stop", None)
        if stop is not None:
            with contextlib.suppress(Exception):  # not running, or already gone
                stop()
