"""A sweep's samples run here, on a local pool or any executor, and given back in sample order.

The scene is read and run once here first (its nominal values): a bad scene or key fails before
any sample, the kernels it needs are compiled once into the cache (the workers then load them),
and the nominal run's outputs name what a sample can report. Samples travel in chunks (a task
on a local pool costs ~0.1 ms, on a cluster a few ms; a sample a few ms to seconds); rows come
back in sample order as soon as they and every row before them are done.
"""

from __future__ import annotations

import itertools
import math
import os
from collections.abc import Callable, Generator, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from massprops.dynamics import any_scene
from massprops.dynamics.scene import scene_text
from massprops.dynamics.systems.robot_scene import is_description
from massprops.errors import UsageError
from massprops.sweep import keys
from massprops.sweep.sample import (
    Plan,
    Row,
    Vary,
    bar_bodies,
    check_plan,
    mass_change,
    run_chunk,
)
from massprops.sweep.specs import parse_spec

if TYPE_CHECKING:  # concurrent.futures (and logging) load only when a pool is used
    from concurrent.futures import Executor, Future, ProcessPoolExecutor

SWEEP_PRELOAD = ("massprops.batch.worker", "massprops.sweep.sample",
                 "massprops.dynamics.systems.robot_scene", "massprops.dynamics.systems.run",
                 "massprops.dynamics.simulate", "massprops.dynamics.compiled.systems_kernel",
                 "massprops.sweep.forkwarm")
"""What a local pool's fork server imports before its workers fork: the sweep, both kinds of
scene and run, numba with the kernels' dispatchers, and numba's target initialised
(`forkwarm`): ~0.8 s a worker would each pay, ~0.1 s left (the kernels' loads)."""

SERIES_POINTS = 200
"""Sample intervals of a run whose outputs are kept over time (``--plot``)."""

MAX_SAMPLES = 10_000_000
"""A sweep's samples at most (a typo's 1e12 is refused, not started)."""


def parse_vary(text: str) -> Vary:
    """``KEY=SPEC`` as a Vary; UsageError (exit 2) when it is not one."""
    key, sep, spec = text.partition("=")
    if not sep or not key or not spec:
        raise UsageError(f"--vary {text!r}: expected KEY=SPEC, e.g. body.mass=relative:5%")
    steps = keys.parse_path(key.strip(), "--vary key")
    return Vary(key.strip(), steps, parse_spec(spec.strip()), mass_change(key.strip(), steps))


@dataclass(frozen=True)
class Prepared:
    """A plan checked and its scene run: ``plan.outputs`` the names each row reports,
    ``nominal`` their values as the scene is written."""

    plan: Plan
    nominal: dict[str, Any]
    sample_s: float = 0.0
    """A warm run's wall time (s): what a sample costs, less its scene's reading."""


def prepare(path: str | os.PathLike, varies: Sequence[str], *, samples: int | None,
            seed: int = 0, outputs: Sequence[str] | None = None,
            options: dict[str, Any] | None = None, description: dict[str, Any] | None = None,
            series: bool = False, bars: float | None = None,
            notice: Callable[[str], None] | None = None) -> Prepared:
    """The sweep of the scene at ``path`` (a YAML scene or a robot description) with ``varies``
    (``KEY=SPEC`` each), ``samples`` draws (per grid point; None: grids only, one each),
    ``outputs`` (names into a run's JSON, default `default_outputs`), ``options`` for
    `any_scene.simulate` (integrator, rtol, step, max_steps, estimate); ``series``: every row
    also carries its outputs at SERIES_POINTS + 1 times (for `plots`); ``bars``: every mesh
    body drawn within this many times inspect's bars (``--bars --bars-scale K``; None: not).
    Runs the nominal scene
    twice (``notice`` tells of a kernel compile; the second run is warm: what a sample costs).
    SceneError / RobotModelError (exit 1), UsageError (exit 2)."""
    parsed = tuple(parse_vary(v) for v in varies)
    if not parsed and bars is None:
        raise UsageError("a sweep needs at least one --vary KEY=SPEC (or --bars)")
    if bars is not None and not (math.isfinite(bars) and bars > 0):
        raise UsageError(f"--bars-scale {bars!r}: expected a positive number (1: the bars "
                         "inspect reports)")
    if len({v.key for v in parsed}) < len(parsed):
        raise UsageError("--vary: a key is given twice")
    grids = [v for v in parsed if v.spec.is_grid]
    if samples is None and (len(grids) < len(parsed) or bars is not None):
        raise UsageError("--samples N is needed when a value is drawn (only values: grids "
                         "run without it)")
    draws = 1 if samples is None else samples
    grid = tuple(itertools.product(*(v.spec.numbers for v in grids)))
    if len(grid) * draws > MAX_SAMPLES:
        raise UsageError(f"{len(grid) * draws:.3g} samples: at most {MAX_SAMPLES:.0e}")
    source = os.fspath(path)
    text = None if is_description(source) else scene_text(source)
    described = tuple(sorted((k, tuple(sorted(v.items())) if isinstance(v, dict) else v)
                             for k, v in (description or {}).items()))
    run_options = tuple(sorted((options or {}).items()))
    folder = os.path.dirname(os.path.abspath(source))
    plan = Plan(source, text, parsed, seed, draws, grid, (), run_options, described, folder)
    scene = check_plan(plan)
    found_bars = bar_bodies(plan, scene) if bars is not None else ()
    any_scene.simulate(scene, notice=notice, **dict(run_options))  # compiles or loads kernels
    result = any_scene.simulate(scene, **dict(run_options))
    found = result.as_dict()
    names = tuple(outputs) if outputs else default_outputs(found)
    nominal = {}
    for name in names:
        try:
            nominal[name] = keys.read_output(found, keys.parse_path(name, "--outputs name"))
        except KeyError:
            raise UsageError(f"--outputs {name}: a run of {source} has no such output (its "
                             f"defaults: {', '.join(default_outputs(found))})") from None
    every = scene.time.duration / SERIES_POINTS if series else None
    plan = Plan(source, text, parsed, seed, draws, grid, names, run_options, described, folder,
                every, bars, found_bars)
    return Prepared(plan, nominal, float(found["wall_time_s"]))


def default_outputs(found: dict[str, Any]) -> tuple[str, ...]:
    """Every body's final position and angular velocity, every joint's final coordinates (a
    system's) and reaction force, as names into a run's JSON ``found``."""
    final = found["final"]
    if "bodies" not in final:  # one body
        return ("final.position", "final.angular_velocity",
                *(f"final.joints[{i}].force_world" for i in range(len(final["joints"]))))
    names = [f"final.bodies.{b}.{q}" for b in final["bodies"]
             for q in ("position", "angular_velocity")]
    names += [f"final.joints.{j}.{q}" for j in final["joints"] for q in ("coordinates", "force")]
    return tuple(names)


def chunk_size(count: int, workers: int) -> int:
    """Samples per task: ~8 tasks per worker (balance), at most 50 (a row is not held back
    long)."""
    return max(1, min(50, count // max(1, 8 * workers)))


POOL_AFTER_S = 2.0
"""`auto_jobs`: samples whose runs add up to more than this (s, judged by a warm nominal run)
go to a pool; a shorter sweep runs in this process (a pool's start costs ~0.5-1 s)."""


def auto_jobs(prepared: Prepared) -> int:
    """Workers for a sweep that names none: one per core, or one per two cores while each run's
    error-estimate companions keep a second core busy (on a helper thread; a worker per core
    would take turns with them), when the runs add up to more than POOL_AFTER_S; else 1."""
    from massprops.batch.pool import default_jobs  # deferred: the pool's side, as below

    if prepared.sample_s * prepared.plan.count <= POOL_AFTER_S:
        return 1
    estimate = dict(prepared.plan.options).get("estimate", True)
    return max(1, default_jobs() // (2 if estimate else 1))


def start_pool(jobs: int) -> ProcessPoolExecutor:
    """A local pool for a sweep, started before `prepare` so that its fork server imports the
    dynamics (SWEEP_PRELOAD) while this process reads and runs the scene; pass it to
    `run_sweep` as ``executor`` and stop it with `batch.pool.stop_pool`."""
    from massprops.batch.pool import local_pool  # deferred: the pool's side, as below

    return local_pool(jobs, SWEEP_PRELOAD)


def run_sweep(prepared: Prepared, *, jobs: int | None = 1, executor: Executor | None = None,
              workers: int | None = None) -> Generator[Row, None, None]:
    """Every sample's row, in sample order: in this process (``jobs`` 1, no executor), a local
    pool of ``jobs`` processes (None: `auto_jobs`), or ``executor`` (a Dask client's, or
    `start_pool`'s; ``workers`` its workers). Closing the iterator (Ctrl-C in the caller) stops
    a pool it started; the rows given stand."""
    plan = prepared.plan
    if jobs is None:
        jobs = auto_jobs(prepared)
    if executor is None and jobs <= 1:
        for i in range(plan.count):
            yield run_chunk(plan, [i])[0]
        return
    # deferred: a sweep run here never loads the pool's side (concurrent.futures, logging)
    from massprops.batch.pool import local_pool, stop_pool

    pool = executor if executor is not None else local_pool(jobs, SWEEP_PRELOAD)
    size = chunk_size(plan.count, workers or jobs)
    starts = iter(range(0, plan.count, size))
    window: list[Future] = []
    done = False
    try:
        for start in itertools.islice(starts, 4 * (workers or jobs)):
            window.append(pool.submit(run_chunk, plan, list(range(start, min(start + size,
                                                                              plan.count)))))
        while window:
            rows = window.pop(0).result()
            nxt = next(starts, None)
            if nxt is not None:
                window.append(pool.submit(run_chunk, plan,
                                          list(range(nxt, min(nxt + size, plan.count)))))
            yield from rows
        done = True
    finally:
        for future in window:
            future.cancel()
        if executor is None:
            if done:
                pool.shutdown(wait=True)
            else:
                stop_pool(pool)  # type: ignore[arg-type]
