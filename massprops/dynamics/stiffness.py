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

Where it compares: PROBE_SAMPLES points spread over the second half of the window, where the
method has had PROBE_STEPS / 2 steps to remove the mode, and every sample time of the run inside
the window. Not the first half's points: a start off the slow manifold of a fast decaying mode
(heavy_top_damped's pivot, a layer ~1e-6 s long) leaves a remnant that Radau removes by a
factor |R(hλ)| per step (~3/(hλ), 2.6e-3 there) while the truth loses it within the layer: 9e-6
of the angular velocity inside the first step, 7e-8 at its end, nothing 3 steps later. That
error is real only at the times a run is sampled, and is counted exactly there.
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
"""Comparison points over the second half of the window."""

PROBE_RTOL = 1e-12
"""The resolving run's tolerance. Its error is the probe's floor: at 1e-10 it was up to 3e-9 of
heavy_top_damped's angular velocity (while the implicit run is good to 7e-11 there), which alone
made that scene's estimate 9e-9; 1e-12 costs little on a window of 16 steps."""


def unresolved(spec, setting: float, program: ForceProgram) -> bool:
    """Whether a run of ``spec`` at ``setting`` leaves a rate of the scene unresolved: a
    fixed-step stiff method whose step × the stiffest rate (1/s) exceeds 1."""
    return spec.kind == "fixed" and spec.stiff and setting * program.stiffest_rate > 1.0


def unresolved_mode_error(scene: Scene, program: ForceProgram, spec, setting: float,
                          scales: Scales, t_samples: np.ndarray | None = None) -> float:
    """The error (contract metric, ``scales``) of ``spec`` at step ``setting`` against a
    resolving dop853 run over the probe window [0, W], W = min(duration, max(PROBE_STEPS·h,
    PROBE_PERIODS·2π/λ)), at the times the module doc says (``t_samples``: the run's sample
    times, s). inf when either run fails there (the caller reports no estimate)."""
    from massprops.dynamics.integrators import INTEGRATORS  # lazy registry: dop853 on demand

    rate = program.stiffest_rate
    period = 2 * math.pi / rate
    window = min(scene.time.duration, max(PROBE_STEPS * setting, PROBE_PERIODS * period))
    short = dataclasses.replace(scene, time=dataclasses.replace(scene.time, duration=window))
    own = np.empty(0) if t_samples is None else np.asarray(t_samples, dtype=float)
    t_probe = np.union1d(np.linspace(0.5 * window, window, PROBE_SAMPLES),
                         own[(own >= 0.0) & (own <= window)])
    runs = [run_once(short, program, s, x, t_probe)
            for s, x in ((spec, setting), (INTEGRATORS["dop853"], PROBE_RTOL))]
    if any(run.failure is not None or run.interrupted for run in runs):
        return math.inf
    ours, resolved = (to_world(short, run.t, run.y, program, with_energy=False) for run in runs)
    return state_error(ours, resolved, scales)
