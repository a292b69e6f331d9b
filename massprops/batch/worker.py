"""The task a worker process (local pool or Dask worker) runs: one chunk of files -> records.

Importable on its own and cheap to pickle by reference: workers import this module (the local
pool's fork server preloads it), never the CLI.
"""

from __future__ import annotations

import os
import signal
import warnings
from typing import Any

from massprops.batch.records import MeshResult, inspect_one


def init_local_worker() -> None:
    """Start-up of a local pool's worker: Ctrl-C in a terminal reaches the whole process group,
    and the parent alone decides what happens then (it stops the workers), so the workers ignore
    it instead of each printing a traceback. Python's warnings are ignored too: a worker's
    stderr is the user's terminal, where the parent prints one line per problem."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    warnings.simplefilter("ignore")


def run_chunk(cwd: str, paths: list[str], options: dict[str, Any], chdir: bool,
              index: int) -> list[MeshResult]:
    """Records of ``paths`` (as given, relative to ``cwd``), in order.

    chdir : work in ``cwd`` (a local pool's worker runs one task at a time, so it may), and the
        paths are read exactly as given, as one process would. Otherwise (a Dask worker runs
        tasks on threads, and its directory is its own) relative paths are joined onto ``cwd``
        and messages still name them as given: the cluster must see the same absolute paths.
    index : position of the chunk in the batch; unused here, it makes every task's arguments
        distinct (an engine may merge identical calls).
    """
    if chdir:
        if os.getcwd() != cwd:
            os.chdir(cwd)
        return [inspect_one(p, options) for p in paths]
    return [inspect_one(os.path.join(cwd, p), options, name=p) for p in paths]
