"""One run of a one-body scene with any registry method, by name, sampled ``samples`` times:
the benchmarks' way to time and measure a single run, which is `precision`'s own
(`dynamics.precision.one_run`: on the engine `simulate` runs it on, the main run alone timed).
"""

from __future__ import annotations

from massprops.dynamics.integrators import INTEGRATORS
from massprops.dynamics.precision import WorldRun, one_run


def run_any(scene, program, name: str, setting: float, samples: int,
            max_steps: int | None = None) -> WorldRun:
    """``scene`` (its compiled ``program``) run with method ``name`` at ``setting`` (rtol or
    step, s), sampled every duration / ``samples``, with no error estimate."""
    return one_run(scene, program, INTEGRATORS[name], setting, scene.time.duration / samples,
                   max_steps=max_steps)
