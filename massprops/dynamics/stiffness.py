"""The one error a stiff method's companion runs cannot see: an oscillation faster than the step.

A fixed-step stiff method (``implicit``, Radau IIA; ``midpoint``) stays stable far beyond the
explicit step limit, but a mode with rate λ and h·λ > 1 is not followed: Radau damps it out
within a few steps, the midpoint rule keeps its amplitude at an aliased phase (and does not damp
a fast decaying mode at all). The 2h and 4h companions of the error estimate (accuracy.py) treat
the mode the same way, so their differences miss it, while the truth keeps oscillating: on
``sample_scenes/unstable.yaml`` Radau at h = 8 ms is 100 % wrong where Richardson says 1e-5.

The probe measures it directly where it can exist: over a short window from the start, long
enough for the method to have removed the mode (PROBE_STEPS steps) and for the mode to have
oscillated (PROBE_PERIODS periods of the stiffest rate), the run is compared with dop853 at
PROBE_RTOL, which resolves it. Scenes whose step resolves every rate never run it.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from massprops.dynamics.accuracy import Scales, state_error
from massprops.dynamics.forces import ForceProgram
from massprops.dynamics.frames import to_world
from massprops.dynamics.model import Scene
from massprops.dynamics.runner import run_once

PROBE_STEPS = 16
"""Steps of the method inside the window: Radau's |R(hλ)| <= 0.6 for h·λ > 1 leaves < 3e-4."""

PROBE_PERIODS = 20.0
"""Periods 2π/λ of the stiffest rate inside the window."""

PROBE_SAMPLES = 64
PROBE_RTOL = 1e-10


def unresolved(spec, setting: float, program: ForceProgram) -> bool:
    """Whether a run of ``spec`` at ``setting`` leaves a rate of the scene unresolved: a
    fixed-step stiff method whose step × the stiffest rate (1/s) exceeds 1."""
    return spec.kind == "fixed" and spec.stiff and setting * program.stiffest_rate > 1.0


def unresolved_mode_error(scene: Scene, program: ForceProgram, spec, setting: float,
                          scales: Scales) -> float:
    """The error (contract metric, ``scales``) of ``spec`` at step ``setting`` against a
    resolving dop853 run over the probe window [0, W], W = min(duration, max(PROBE_STEPS·h,
    PROBE_PERIODS·2π/λ)). inf when either run fails there (the caller reports no estimate)."""
    from massprops.dynamics.integrators import INTEGRATORS  # lazy registry: dop853 on demand

    rate = program.stiffest_rate
    period = 2 * math.pi / rate
    window = min(scene.time.duration, max(PROBE_STEPS * setting, PROBE_PERIODS * period))
    short = dataclasses.replace(scene, time=dataclasses.replace(scene.time, duration=window))
    t_probe = np.linspace(0.0, window, PROBE_SAMPLES + 1)
    runs = [run_once(short, program, s, x, t_probe)
            for s, x in ((spec, setting), (INTEGRATORS["dop853"], PROBE_RTOL))]
    if any(run.failure is not None or run.interrupted for run in runs):
        return math.inf
    ours, resolved = (to_world(short, run.t, run.y, program, with_energy=False) for run in runs)
    return state_error(ours, resolved, scales)
