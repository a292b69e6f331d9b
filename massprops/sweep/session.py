"""A sweep from start to summary, as one object: the plan read and run once, where the samples
go (this process, a local pool started before the scene is read, or a Dask cluster), the rows
in sample order, and what they say together (`summary`, ``--linear``'s derivatives, the bands'
figure). The CLI opens one, prints its rows as they come and renders its summary."""

from __future__ import annotations

import os
from collections.abc import Callable, Generator, Sequence
from pathlib import Path
from typing import Any

from massprops.sweep.run import Prepared, prepare, run_sweep, start_pool
from massprops.sweep.sample import Row
from massprops.sweep.summary import summarize


class Sweep:
    """A sweep of the scene at ``path`` (arguments as `run.prepare`) on ``jobs`` local workers
    (None: `run.auto_jobs`; more than 1: the pool starts before the scene is read, so that its
    workers boot meanwhile) or the Dask scheduler at ``scheduler``. A context manager: leaving
    it stops the pool or closes the cluster's client, whatever happened."""

    def __init__(self, path: str | os.PathLike, varies: Sequence[str], *, samples: int | None,
                 seed: int = 0, outputs: Sequence[str] | None = None,
                 options: dict[str, Any] | None = None, bars: float | None = None,
                 series: bool = False, jobs: int | None = None, scheduler: str | None = None,
                 notice: Callable[[str], None] | None = None) -> None:
        self.jobs, self.executor, self.workers = jobs, None, None
        self._client: Any = None
        self._pool: Any = None
        if scheduler is not None:
            from massprops.batch.pool import dask_executor  # deferred: only a cluster's

            self.executor, self.workers, self._client = dask_executor(scheduler)
        elif jobs is not None and jobs > 1:
            self._pool = self.executor = start_pool(jobs)
            self.workers = jobs
        try:
            self.prepared: Prepared = prepare(path, varies, samples=samples, seed=seed,
                                              outputs=outputs, options=options, series=series,
                                              bars=bars, notice=notice)
        except BaseException:
            self.close()
            raise

    def __enter__(self) -> Sweep:
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def close(self) -> None:
        """Stop the pool this sweep started (its running samples are lost) or close the client."""
        if self._client is not None:
            self._client.close()
            self._client = None
        if self._pool is not None:
            from massprops.batch.pool import stop_pool  # deferred: the pool's side

            stop_pool(self._pool)
            self._pool = None

    def rows(self) -> Generator[Row, None, None]:
        """Every sample's row in sample order; closing the generator (Ctrl-C in the caller)
        stops the samples still running. The caller keeps the rows it took (only it knows which
        it has reported when Ctrl-C comes) and hands them to `summary`."""
        return run_sweep(self.prepared, jobs=self.jobs, executor=self.executor,
                         workers=self.workers)

    def summary(self, rows: Sequence[Row], *, linear: bool = False) -> dict[str, Any]:
        """The contract's summary of ``rows``; with ``linear``, `linear.linearize`'s
        derivatives under ``"linear"``."""
        plan = self.prepared.plan
        result = summarize(rows, plan.outputs, [key for key, _ in plan.value_keys])
        if linear:
            from massprops.sweep.linear import linearize  # deferred: only --linear

            result["linear"] = linearize(plan)
        return result

    def plot(self, rows: Sequence[Row], path: str | Path, *, force: bool = False,
             protect=()) -> None:
        """``rows``' outputs over time (`plots.plot_sweep`; the sweep was made with series)."""
        from massprops.sweep.plots import plot_sweep  # deferred: matplotlib

        plot_sweep(rows, self.prepared.plan.outputs, path, force=force, protect=protect)
