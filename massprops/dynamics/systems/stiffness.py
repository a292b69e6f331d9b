"""A system's fastest rate, and the one error a stiff method's companion runs cannot see: an
oscillation faster than the step (one body is the system of one body: its runs use this too).

A fixed-step stiff method (``implicit``, Radau IIA; ``midpoint``) stays stable far beyond the
explicit step limit, but a mode with rate ρ and h·ρ > 1 is not followed: Radau damps it out
within a few steps, the midpoint rule keeps its amplitude at an aliased phase (and does not damp
a fast decaying mode at all). The 2h and 4h companions of the error estimate treat the mode
the same way, so Richardson sees nothing while the truth keeps oscillating: on
``sample_scenes/unstable.yaml`` Radau at h = 8 ms is 100 % wrong where Richardson says 1e-5; a
double pendulum with an undamped k = 1e8 N·m/rad elbow spring at h = 1 ms was wrong by 1.9e-4
(its elbow's small fast swing) where the companions said 1e-11.

The probe measures it directly where it can exist: over a short window from the start, long
enough for the method to have removed the mode (PROBE_STEPS steps) and for the mode to have
oscillated (PROBE_PERIODS periods of the fastest rate), the run is compared with dop853 at
PROBE_RTOL, which resolves it, in the whole run's scales. Runs whose step resolves every rate
never run it.

Where it compares: PROBE_SAMPLES points spread over the second half of the window, where the
method has had PROBE_STEPS / 2 steps to remove the mode, and every sample time of the run inside
the window. Not the first half's points: a start off the slow manifold of a fast decaying mode
(heavy_top_damped's pivot, a layer ~1e-6 s long) leaves a remnant that Radau removes by a
factor |R(hρ)| per step (~3/(hρ), 2.6e-3 there) while the truth loses it within the layer: 9e-6
of the angular velocity inside the first step, 7e-8 at its end, nothing 3 steps later. That
error is real only at the times a run is sampled, and is counted exactly there.
"""

from __future__ import annotations

import math

import numpy as np

from massprops.dynamics.systems.integrate import integrate
from massprops.dynamics.systems.outputs import Samples, distance, evaluate_states
from massprops.dynamics.systems.system import spectral_radius

PROBE_STEPS = 16
"""Steps of the method inside the window: Radau's |R(hρ)| <= 0.6 for h·ρ > 1 leaves < 3e-4."""

PROBE_PERIODS = 20.0
"""Periods 2π/ρ of the fastest rate inside the window."""

PROBE_SAMPLES = 64
"""Comparison points over the second half of the window."""

PROBE_RTOL = 1e-12
"""The resolving run's tolerance. Its error is the probe's floor: at 1e-10 it was up to 3e-9 of
heavy_top_damped's angular velocity (while the implicit run is good to 7e-11 there), which alone
made that scene's estimate 9e-9; 1e-12 costs little on a window of 16 steps."""

PROBE_MAX_STEPS = 100_000
"""Steps the probe's runs may take: a rate of 1e12/s (a damper on a tiny inertia) would need
~1e9 DOP853 steps over the window, minutes or more; beyond this the estimate is unknown (None)."""


def fastest_rate(system, y0: np.ndarray) -> float:
    """ρ(∂ẏ/∂y) at (0, y0), 1/s: the spectral radius of the right-hand side's Jacobian by
    forward differences (n + 1 evaluations of the compiled right-hand side, the one the runs
    step: the numpy model's took 28 ms each on dm_control's 85-dof dog, 5 s of its run), kept
    on ``system`` (a `System`). The caller has the systems kernel ready
    (`compiling.prepare`), as a run needs it anyway."""
    if getattr(system, "fastest_rate", None) is None:
        system.fastest_rate = spectral_radius(system, y0)
    return system.fastest_rate


def unresolved_mode_error(system, y0: np.ndarray, name: str, h: float, floors: np.ndarray,
                          windows: np.ndarray, t_out: np.ndarray, samples: Samples,
                          limit: int) -> float:
    """The error (`outputs.distance` in the scales of ``samples``, the whole run) of method
    ``name`` at step ``h`` against dop853 at PROBE_RTOL over [0, W], W = PROBE_STEPS steps or
    PROBE_PERIODS periods 2π/ρ, whichever is longer (on the run's own step grid, within the
    duration); 0 where h ρ ≤ 1, inf where either run fails or needs more than PROBE_MAX_STEPS
    (no estimate then)."""
    rate = fastest_rate(system, y0)
    if h * rate <= 1.0:
        return 0.0
    duration = float(t_out[-1])
    window = max(PROBE_STEPS * h, PROBE_PERIODS * 2.0 * math.pi / rate)
    window = min(duration, h * math.ceil(window / h * (1.0 - 1e-12)))
    t_probe = np.union1d(np.linspace(0.5 * window, window, PROBE_SAMPLES),
                         t_out[t_out <= window])
    inside = windows[windows < window]
    bound = min(limit, PROBE_MAX_STEPS)
    runs = [integrate(system, y0, t_probe, setting, floors, inside, bound, method)
            for method, setting in ((name, h), ("dop853", PROBE_RTOL))]
    if any(run.failure is not None for run in runs):
        return math.inf
    ours, resolved = (evaluate_states(system, t_probe, run.y_out) for run in runs)
    return distance(ours, resolved, system.scene.size, scales=samples)
