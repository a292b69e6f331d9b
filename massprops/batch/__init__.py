"""Many meshes: inputs expanded, inspected in parallel, reported in input order.

``inspect_many(paths, executor=None, **options)`` inspects every path like
`massprops.inspection.file.inspect_file` (``options`` are its keyword arguments: ``unit``,
``density``, ``mass``, ``allow_open``, ``format``, and whatever it accepts later) and yields one
`MeshResult` per input, **in input order**, each as soon as it and every input before it are
done. Work runs

- in this process, when that is all a pool could do (``jobs=1``, or a batch too small to pay
  for starting worker processes): the same calls, in the same order, as a plain loop;
- in a local pool of ``jobs`` worker processes (default: the cores this process may use);
- on any ``concurrent.futures.Executor`` given as ``executor``: a ``dask.distributed``
  ``Client.get_executor()`` spreads a batch over a cluster (`dask_executor`).

Small files travel in chunks (a task costs ~0.1 ms locally, a few ms on a cluster) sized by a
cost model from file sizes (`plan`); a large file is a task of its own and keeps its own
two-thread path. A result is a small picklable record (the JSON object, the warnings, or an
error's message and exit code; never mesh arrays). A task whose worker died is split and
retried, a suspect file alone, so every input is reported exactly once (`runner`).

Modules: `inputs` (files, directories, globs, lists on stdin), `records` (one mesh -> one
record), `plan` (cost model and chunks), `runner` (ordering, window, retries, Ctrl-C),
`pool` (the local process pool and the Dask executor), `worker` (the task a worker runs),
`table` (CSV columns). The library never prints; the CLI renders the records.
"""

from __future__ import annotations

from massprops.batch.inputs import BadInput, expand_inputs, mesh_extensions
from massprops.batch.pool import dask_executor, default_jobs
from massprops.batch.records import ErrorInfo, MeshResult, inspect_one
from massprops.batch.runner import Batch, inspect_many

__all__ = [
    "BadInput",
    "Batch",
    "ErrorInfo",
    "MeshResult",
    "dask_executor",
    "default_jobs",
    "expand_inputs",
    "inspect_many",
    "inspect_one",
    "mesh_extensions",
]
