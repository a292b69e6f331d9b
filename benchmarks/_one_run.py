"""One run of a one-body scene with any registry method, on the engine `simulate` runs it on,
as world-frame samples: the benchmarks' common way to time and measure a single run.

A time-stepping method (`integrators.SYSTEM_METHODS`) runs on the systems engine through
`simulate` with its error estimate left out (only the main run is timed); a splitting method or
the closed form on its one-body kernel (`runner.run_once`).
"""

from __future__ import annotations

from dataclasses import dataclass

from massprops.dynamics.budget import sample_times
from massprops.dynamics.frames import to_world
from massprops.dynamics.integrators import INTEGRATORS, SYSTEM_METHODS
from massprops.dynamics.runner import run_once
from massprops.dynamics.simulate import simulate
from massprops.errors import ComputationError


@dataclass(frozen=True)
class WorldRun:
    """trajectory: world-frame samples (`frames.Trajectory`, up to where the run got); steps,
    evaluations; wall: the main run's seconds; failure: why it ended short (None: it did not)."""

    trajectory: object
    steps: int
    evaluations: int
    wall: float
    failure: str | None


def run_any(scene, program, name: str, setting: float, samples: int,
            max_steps: int | None = None) -> WorldRun:
    """``scene`` (its compiled ``program``) run with method ``name`` at ``setting`` (rtol or
    step, s), sampled every duration / ``samples`` as `simulate` samples (`budget.sample_times`:
    runs of either engine compare at the same times)."""
    duration = scene.time.duration
    if name in SYSTEM_METHODS:
        try:
            res = simulate(scene, integrator=name, rtol=setting, step=setting,
                           every=duration / samples, max_steps=max_steps, estimate=False)
        except ComputationError as exc:
            part = exc.partial
            if part is None:
                raise
            return WorldRun(part.trajectory, part.steps, part.evaluations, part.wall_time_s,
                            str(exc))
        return WorldRun(res.trajectory, res.steps, res.evaluations, res.wall_time_s, None)
    t_out = sample_times(duration, duration / samples)  # simulate's times: the two compare
    run = run_once(scene, program, INTEGRATORS[name], setting, t_out, max_steps=max_steps)
    traj = to_world(scene, run.t, run.y, program, with_energy=False)
    failure = None if run.failure is None else str(run.failure)
    return WorldRun(traj, int(run.stats[0]), int(run.stats[1]), run.wall, failure)
