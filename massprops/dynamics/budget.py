"""The run bound: how many steps and output samples one run may take, so that no scene runs for
hours or exhausts memory. Checked up front where the count is known, while running where not.

- Samples: at most `MAX_SAMPLES` output times per run (each keeps ~20 float64 numbers in memory
  and a line in the trajectory file); more is refused up front, naming the count and the
  interval that fits.
- Fixed steps: a run of duration T at step h takes ceil(T / h) steps (one more per force window
  edge); more than `MAX_STEPS` is refused up front, naming the count and the step that fits.
- Adaptive steps cannot be counted in advance: the run stops once it has taken `MAX_STEPS`, or
  earlier, once it has taken `PROJECT_AFTER`, if its pace so far (steps per simulated second)
  projects more than `PROJECT_MARGIN` times `MAX_STEPS` for the whole run. What was computed is
  kept (the CLI writes it) and the error (`RunBudgetError`, exit 3) says where it stopped and
  what to change.

Every run is bounded alike: the main run, the error estimate's companions and probe, and the
reference and ladder runs of ``precision`` (whose fixed-step ladders leave out rungs beyond
``precision.MAX_STEPS`` anyway). The closed form takes no steps; only its samples are bounded.

The other limits one body and a system share live here too: the output times (`sample_times`),
the fixed step a scene does not give (`default_step`), `auto`'s explicit-step budget, the energy
growth that means divergence and the largest speeds a start may have (`too_fast`).
"""

from __future__ import annotations

import math

import numpy as np

from massprops.errors import RunBudgetError, setting_ref

MAX_STEPS = 20_000_000
"""Steps one run may take unless the caller says otherwise (``simulate(max_steps=)``,
``simulate_system(max_steps=)``, the CLI's --max-steps), one body and systems alike (the one
bound: systems once had their own, 2e6, which stopped a one-body rk4 run there). Measured cost
per step (warm, one shared core, a body on a damped spring, the one-body kernels): rk4 ~1 µs,
midpoint ~2.5 µs, dop853 ~5 µs, implicit ~5 µs, splitting ~8 µs, splitting6 ~50 µs (nine drifts
per step), so a run reaches the bound after ~20 s (rk4) to ~2 min (dop853, implicit), 15 min at
most (splitting6), and a fixed-step run that needs more is refused in the first place."""

PROJECT_AFTER = 1_000_000
"""Steps an adaptive run takes before its pace is used to project the whole run (a start whose
transient needs small steps must not be judged on them alone)."""

PROJECT_MARGIN = 10.0
"""An adaptive run stops early only when its projection exceeds MAX_STEPS this many times."""

MAX_SAMPLES = 2_000_000
"""Output samples one run may keep (~0.3 GB of trajectory arrays, a ~0.5 GB CSV file)."""


def _where(source: str) -> str:
    return f"{source}: " if source else ""


def check_samples(duration: float, every: float, source: str = "") -> int:
    """The number of sample intervals k·every in [0, duration]; raises RunBudgetError (before
    anything is allocated) when the samples would exceed MAX_SAMPLES."""
    n = duration / every
    if not n < MAX_SAMPLES:
        raise RunBudgetError(
            f"{_where(source)}sampling every {every:.3g} s over {duration:.6g} s gives "
            f"{n:.3g} output samples, "
            f"more than the run bound of {MAX_SAMPLES:.0e}; set {setting_ref('output.every')} "
            f"to at least {duration / MAX_SAMPLES:.3g} s, or shorten time.duration")
    return int(math.floor(n * (1 + 1e-12)))


def check_fixed_steps(name: str, duration: float, step: float, edges: int,
                      source: str = "", limit: int | None = None) -> None:
    """Refuse a fixed-step run whose step count (duration / step, plus one per window edge)
    exceeds ``limit`` (default MAX_STEPS), naming the count and the step that fits."""
    limit = limit or MAX_STEPS
    steps = duration / step + edges
    if steps > limit:
        raise RunBudgetError(
            f"{_where(source)}{name} at step {step:.3g} s over {duration:.6g} s would take "
            f"{steps:.3g} steps, "
            f"more than the run bound of {limit:.3g} ({setting_ref('max_steps')}); set "
            f"{setting_ref('time.step')} "
            f"to at least {duration / limit:.3g} s, shorten time.duration, or use an adaptive "
            "or closed-form integrator (dop853, exact)")


def exhausted(steps: int, fraction_done: float, limit: int | None = None) -> str | None:
    """Why a run that has taken ``steps`` and covered ``fraction_done`` of its duration must
    stop now (``limit``: default MAX_STEPS), or None to go on."""
    limit = limit or MAX_STEPS
    if steps >= limit:
        return f"it has taken {steps:.3g} steps, the run bound ({setting_ref('max_steps')})"
    if steps >= min(PROJECT_AFTER, limit // 10) and fraction_done > 0.0:
        projected = steps / fraction_done
        if projected > PROJECT_MARGIN * limit:
            return (f"at its pace so far ({steps:.3g} steps for {100 * fraction_done:.3g} % of "
                    f"the run) it would need ~{projected:.2g} steps, beyond the run bound of "
                    f"{limit:.3g} ({setting_ref('max_steps')})")
    return None


STEP_BUDGET = 2_000_000
"""`auto` picks the implicit method when an explicit one would need more steps than this to
resolve the stiffest rate over the run (RK-type stability limit ~2.8 / rate)."""

ENERGY_BLOWUP = 1e6
"""A conservative or dissipative scene whose energy grows by this factor of its scale diverged."""

SQUARE_LIMIT = float(np.finfo(np.float64).max) / ENERGY_BLOWUP
"""1.8e302: the largest square of a start's speeds a run may form (`too_fast`)."""


def magnitude(vector) -> float:
    """|vector|, taken without overflow or underflow (scaled by its largest component first)."""
    v = np.asarray(vector, dtype=np.float64)
    largest = float(np.abs(v).max(initial=0.0))
    return largest * float(np.linalg.norm(v / largest)) if largest > 0 else 0.0


def too_fast(mass: float, moment: float, velocity, angular_velocity) -> tuple[str, str] | None:
    """(key, problem) when a body of ``mass`` (kg) and largest principal moment ``moment``
    (kg·m²) cannot start at ``velocity`` (m/s; key "velocity") or ``angular_velocity`` (rad/s;
    key "angular_velocity"), else None. A run squares a start's speeds: |v|², |ω|², the kinetic
    energy ½ m |v|² + ½ ω·Jω, the momenta |m v|² and |J ω|², and its divergence test multiplies
    that energy by ENERGY_BLOWUP; each must stay a float64 number, at most SQUARE_LIMIT, so
    |v| ≤ √SQUARE_LIMIT / max(1, √(m / 2), m) (the largest of v², ½ m v², m² v² is under the
    limit) and |ω| alike with the moment. Beyond, the run's numbers overflow (1e300 rad/s: numpy
    warned of overflows, then the step was 0 s)."""
    for key, speed, weight, unit in (("velocity", velocity, mass, "m/s"),
                                     ("angular_velocity", angular_velocity, moment, "rad/s")):
        limit = math.sqrt(SQUARE_LIMIT) / max(1.0, math.sqrt(weight / 2.0), weight)
        size = magnitude(speed)
        if not size <= limit:
            what = ("½ m |v|², |v|², |m v|²" if key == "velocity"
                    else "the kinetic energy ½ ω·Jω, |ω|², |J ω|²")
            return key, (f"a speed of {size:.3g} {unit} is too large for float64: a run squares "
                         f"it ({what}) and needs room for its divergence test "
                         f"({ENERGY_BLOWUP:.0e} times the energy), so this body (mass "
                         f"{mass:.3g} kg, largest moment {moment:.3g} kg·m²) may start at "
                         f"{limit:.3g} {unit} at most")
    return None


STEPS_PER_RUN = 1000
"""A fixed step the scene does not give is the duration / this, or shorter (`default_step`)."""

STEPS_PER_RATE = 0.1
"""A fixed step the scene does not give is at most this / the fastest rate it must resolve:
RK4 is stable to h ρ ≈ 2.8, and 0.1 keeps it accurate (`default_step`)."""


def default_step(duration: float, rate: float) -> float:
    """The fixed step (s) of a run the scene gives none: duration / STEPS_PER_RUN, and at most
    STEPS_PER_RATE / ``rate`` (1/s: the fastest rate the method must resolve, 0 for none). The
    one rule of both engines; each says which rate: a system the spectral radius of its
    right-hand side's Jacobian at the start, for explicit methods only
    (`systems.methods.default_step`), one free body its spin and, for explicit methods, its
    stiffest force (`simulate.default_step`)."""
    h = duration / STEPS_PER_RUN
    return min(h, STEPS_PER_RATE / rate) if rate > 0 else h


DIAGNOSTIC_SAMPLES = 100
"""Without a sampling interval, the run is still sampled at this many intervals (dense output,
cheap) so that drifts are maxima over the run and a divergence is located in time."""


FILE_SAMPLES = 1000
"""A run that writes a trajectory or a plot and is given no sampling interval is sampled at this
many intervals."""


def sampling_interval(duration: float, every: float | None, writes: bool) -> float | None:
    """The sampling interval (s) of a run: ``every`` (the caller's, else the scene's) as given;
    else duration / FILE_SAMPLES when the run ``writes`` a trajectory or a plot; else None (the
    run's DIAGNOSTIC_SAMPLES only)."""
    if every is None and writes:
        return duration / FILE_SAMPLES
    return every


def sample_times(duration: float, every: float | None, source: str = "") -> np.ndarray:
    """Output times: k·every below the duration, and the duration itself (never accumulated).
    Raises RunBudgetError when there would be more than MAX_SAMPLES."""
    if every is None:
        return np.linspace(0.0, duration, DIAGNOSTIC_SAMPLES + 1)
    n = check_samples(duration, every, source)
    t = every * np.arange(n + 1)
    return t if t[-1] >= duration * (1 - 1e-12) else np.append(t, duration)
