"""The integrators of systems, with a projection after every step: DOP853 with its 7th-order
dense output (`dynamics.compiled.systems_dop853`), and the registry's fixed-step methods rk4,
midpoint and implicit (`dynamics.compiled.systems_fixed`, Hermite dense output): one compiled
call per segment (the method's entry, `dynamics.compiled.systems_kernel.STEPS`) over the
system's arrays (`program`).

DOP853 is the project's own tableau with dop853.f's error norm and step control; the fixed-step
methods share its stages' right-hand side and the Newton rule. Each works on y = [q, u] of any
length: after each accepted step the quaternion coordinates are renormalised and (q, u)
projected onto Φ = 0, Φ̇ = 0 (the compiled form of System.project); the dense output of a step
is built from its start and its projected end, and each sample is projected in turn. The error
scale of component i is rtol × max(running max |y_i|, floor_i). A failure in the kernel comes
back as a status code; here it becomes the exception the run reports.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from massprops import tolerances
from massprops.dynamics import budget
from massprops.dynamics.compiled import systems_step as codes
from massprops.dynamics.compiled.systems_fixed import DIVERGED, MAX_PIECES
from massprops.dynamics.compiled.systems_kernel import METHODS, STEPS, step_dop853
from massprops.dynamics.compiled.systems_step import PROJECT_ITERATIONS
from massprops.dynamics.integrators._shared import STEP_UNDERFLOW, step_count
from massprops.dynamics.systems.system import SingularPose, spectral_radius
from massprops.errors import RunBudgetError, setting_ref

NARROW_RTOL = 1e-12
"""Tolerance of the run that finds a singular pose inside the step that jumped across it: its
steps are short enough to land within NEAR_SINGULAR_MARGIN of the pose (the parallelogram
four-bar's flat pose to 1e-6 s where steps at rtol 1e-9 span 0.25-0.72 s)."""

UNCLOSED_WILD = 1e3
"""A loop that cannot be closed by more than this many system sizes was not near a pose that
does not assemble: the state went wild (RK4 at 8 s steps: a residual of 4.5e49 m)."""

NARROW_RUNS = 8
"""Fine runs at most, each over the shorter stretch where the previous one crossed."""

NARROW_PIECES = 16
"""Each fine run goes over its stretch in this many pieces, each a segment of its own: no step
is longer than a piece, so each run shrinks the stretch at least this many times even where the
motion is so smooth that DOP853's error estimate is round-off and its steps would grow past the
pose again and again (a parallelogram four-bar turning at a constant rate)."""

NARROW_RESOLUTION = 1e-10
"""A stretch at most this long (relative to its end time, at least 1 s) is the pose's time."""

NARROW_STEPS = 100_000
"""Steps one locating run may take."""

CALL_STEPS = 20_000
"""Steps (with the fixed-step methods' retried pieces) one compiled call may take before it
hands control back: between calls Ctrl-C and the progress bar are served. Calls are cut by step
counts, never by timers, so results do not depend on the machine. A call stopped there goes on
from its last accepted state: DOP853 with a fresh first step (two evaluations per call), the
fixed-step methods on the same grid."""


class Run:
    """Samples ``y_out`` (n_out, ny) at ``t_out``, steps, evaluations, rejected steps, the
    largest projection corrections (position tangent, velocity) and the failure (None);
    ``t_reached`` (s) and the state ``y_last`` there; ``interrupted``: Ctrl-C stopped it;
    ``margin``: the smallest singularity margin it kept (`System.margin`); ``short_err``: the
    error of the fixed-step segments of one or two steps, which companions at 2h and 4h step
    alike and so cannot see (`_short_error`; absolute, max-norm over the state, summed)."""

    def __init__(self, n_out: int, ny: int) -> None:
        self.y_out = np.full((n_out, ny), np.nan)
        self.steps = self.nfev = self.rejected = 0
        self.moved_q = self.moved_u = 0.0
        self.failure: BaseException | None = None
        self.t_reached = 0.0
        self.y_last: np.ndarray | None = None
        self.interrupted = False
        self.margin = 1.0
        self.short_err = 0.0


def integrate(system, y0: np.ndarray, t_out: np.ndarray, setting: float, floors: np.ndarray,
              windows: np.ndarray, max_steps: int = budget.MAX_STEPS, method: str = "dop853",
              progress: Callable[[float], None] | None = None,
              watch: Callable[[int], None] | None = None) -> Run:
    """Integrate from t = 0 over [0, t_out[-1]] with ``method`` (dop853: ``setting`` is rtol;
    rk4, midpoint, implicit: the step h, s), stepping onto each window edge in ``windows``
    (sorted times where the loads jump). A singular pose, a failed projection, a step-size
    underflow or the step limit stops the run: ``Run.failure`` holds it and the samples before
    it are kept. ``Run.margin`` is the run's singularity margin (``system`` is only read: runs
    of one system may go side by side). ``progress(fraction of the run)`` and ``watch(steps
    so far)`` are called between compiled calls (CALL_STEPS); Ctrl-C there, or either raising
    KeyboardInterrupt, ends the run with what it computed (``Run.interrupted``)."""
    t_out = np.ascontiguousarray(t_out, dtype=float)
    run = Run(len(t_out), y0.size)
    duration = float(t_out[-1])
    edges = [0.0, *[w for w in windows if 0 < w < duration], duration]
    y = np.array(y0, dtype=float)
    scales = np.maximum(np.abs(y), floors)
    kout = 0
    while kout < len(t_out) and t_out[kout] <= 0.0:
        run.y_out[kout] = y
        kout += 1
    istats, fstats, accepted_b, accepted_u = _run_arrays(system, kout)
    yfail = np.zeros(y.size)
    try:
        _segments(system, y, edges, setting, method, scales, floors, t_out, run, istats,
                  fstats, accepted_b, accepted_u, yfail, max_steps, progress, watch)
    except KeyboardInterrupt:  # y and run.t_reached hold the last finished call's end
        run.interrupted = True
    run.y_last = y
    run.steps, run.nfev, run.rejected = (int(v) for v in istats[:3])
    run.moved_q, run.moved_u = float(fstats[0]), float(fstats[1])
    run.margin = float(fstats[2])
    return run


def _segments(system, y, edges, setting, method, scales, floors, t_out, run, istats, fstats,
              accepted_b, accepted_u, yfail, max_steps, progress, watch) -> None:
    """`integrate`'s walk over the segments between window edges, each in compiled calls of
    at most CALL_STEPS steps."""
    for t0, t1 in zip(edges[:-1], edges[1:]):
        within = scales.copy()  # each segment's error scales start from y0's running maxima
        # a fixed-step segment resumed mid-way keeps its grid: its own equal step, not h (the
        # kernels' step_count, in Python: a compiled `inner` has no wrapper to call from here)
        h = float(setting) if method == "dop853" else \
            (t1 - t0) / step_count.py_func(t0, t1, setting)
        short = method != "dop853" and (t1 - t0) <= 2 * h * (1 + 1e-12)
        y_start = y.copy() if short else None
        start = t0
        while True:
            bound = min(max_steps, int(istats[0] + istats[2]) + CALL_STEPS)
            STEPS[method](system.program, y, start, t1, h, METHODS[method], within, t_out,
                          run.y_out, istats, fstats, accepted_b, accepted_u, bound, yfail)
            if istats[3] != codes.STEP_LIMIT or bound >= max_steps:
                break
            istats[3] = codes.OK  # this call's share, not the run bound: go on from there
            start = run.t_reached = float(fstats[3])
            why = budget.exhausted(int(istats[0] + istats[2]), start / edges[-1], max_steps)
            if why is not None:  # at its pace, the bound would stop it late: stop it now
                run.failure = RunBudgetError(f"{system.scene.source}: the {method} run stopped "
                                             f"at t = {start:.6g} s: {why}; {_fewer(method)}")
                return
            if progress is not None:
                progress(start / edges[-1])
            if watch is not None:
                watch(int(istats[0]))
        if istats[3] != codes.OK:
            jumped = None
            if istats[3] == codes.CROSSED and fstats[4] < fstats[3]:  # a step jumped across it
                rtol = float(setting) if method == "dop853" else NARROW_RTOL
                low, high, seen = _narrow(system, y, float(fstats[4]), float(fstats[3]), rtol,
                                          scales, floors)
                fstats[4], fstats[3] = low, high
                jumped = None if seen else _jumped(system, low, high, method)
            run.failure = jumped or _failure(system, int(istats[3]), fstats, yfail, max_steps,
                                             method, t1, edges[-1])
            return
        if short:
            run.short_err += _short_error(system, y_start, y, t0, t1, h, method, within,
                                          accepted_b, accepted_u, max_steps)
        run.t_reached = t1
        if progress is not None:
            progress(t1 / edges[-1])


def _short_error(system, y_start, y_end, t0, t1, h, method, scales, accepted_b, accepted_u,
                 max_steps) -> float:
    """The error of a segment [t0, t1] of one or two fixed steps h (a load window shorter than
    the step): a 2h or 4h companion steps it the same way, so Richardson's rule is blind to it
    (the one-body engine keeps its kernels' local estimate for them). Stepped again in halves
    from ``y_start``, the difference to ``y_end`` is the step's error to within a factor
    2^p / (2^p − 1) ≤ 2, which is taken (absolute, max-norm over the state; inf where the
    halves fail)."""
    y = y_start.copy()
    istats, fstats, _, _ = _run_arrays(system, 0)
    STEPS[method](system.program, y, t0, t1, 0.5 * h, METHODS[method], scales.copy(),
                  np.empty(0), np.empty((0, y.size)), istats, fstats, accepted_b.copy(),
                  accepted_u.copy(), max_steps, np.zeros(y.size))
    if istats[3] != codes.OK:
        return np.inf
    return 2.0 * float(np.abs(y - y_end).max())


def _run_arrays(system, kout: int) -> tuple:
    """A fresh run's istats and fstats (`systems_dop853`'s layout; the next output ``kout``)
    and its last accepted B and U (none yet)."""
    m, nv = system.m, system.nv
    istats = np.array([0, 0, 0, codes.OK, kout, -1,
                       -1 if system.rank is None else system.rank], dtype=np.int64)
    fstats = np.array([0.0, 0.0, system.margin, 0.0, 0.0, 0.0, 1.0])
    return istats, fstats, np.zeros((m, nv)), np.zeros((m, max(m, nv)))


def _narrow(system, y: np.ndarray, low: float, high: float, rtol: float, scales: np.ndarray,
            floors: np.ndarray) -> tuple[float, float, bool]:
    """Where in [low, high] (s) a step crossed a singular pose: that stretch is run again from
    ``y`` (the state at ``low``) at NARROW_RTOL in NARROW_PIECES pieces, whose small steps reach
    the pose itself (`tolerances.NEAR_SINGULAR_MARGIN`): (t, t); or cross it again in a shorter
    step, which is run again in turn (NARROW_RUNS at most; a stretch of NARROW_RESOLUTION is the
    pose's time). Where a run sees nothing the interval stays; the
    flag says whether the first run saw the pose at all (a coarse step can jump the loop to a
    state beyond one that the motion itself never reaches: the four-bar at RK4 steps of 0.5 s)."""
    y_low, n = np.array(y, dtype=float), y.size
    for k in range(NARROW_RUNS):
        trial = y_low.copy()
        istats, fstats, accepted_b, accepted_u = _run_arrays(system, 0)
        scales_k = np.maximum(np.maximum(np.abs(trial), floors), scales)
        edges = np.linspace(low, high, NARROW_PIECES + 1)
        for a, b in zip(edges[:-1], edges[1:]):
            step_dop853(system.program, trial, float(a), float(b),
                        min(float(rtol), NARROW_RTOL), METHODS["dop853"], scales_k.copy(),
                        np.empty(0), np.empty((0, n)), istats, fstats, accepted_b, accepted_u,
                        NARROW_STEPS, np.zeros(n))
            if istats[3] != codes.OK:
                break
        if istats[3] != codes.CROSSED:
            if k == 0:
                return low, high, False
            break
        low, high, y_low = float(fstats[4]), float(fstats[3]), trial
        if high - low <= NARROW_RESOLUTION * max(1.0, abs(high)):
            low = high
        if low == high:
            break
    return low, high, True


def _jumped(system, low: float, high: float, method: str) -> BaseException:
    """The run's step from ``low`` to ``high`` crossed a singular pose that a fine run of that
    stretch does not reach: the step, not the mechanism, is at fault."""
    fix = (f"tighten {setting_ref('rtol')}" if method == "dop853"
           else f"shorten {setting_ref('step')}")
    return ArithmeticError(f"{system.scene.source}: the {method} step from t = {low:.6g} to "
                           f"{high:.6g} s jumped the "
                           "loop across a singular pose that the motion does not reach (a run "
                           f"at rtol {NARROW_RTOL:g} passes there); {fix}")


def _fewer(method: str) -> str:
    """What takes fewer steps with ``method``."""
    return (f"loosen {setting_ref('rtol')}" if method == "dop853"
            else f"lengthen {setting_ref('step')}")


def _rate_at(system, y: np.ndarray, t: float) -> float:
    """1/s: the fastest rate of the system at (t, y) (`system.spectral_radius`), inf where
    it cannot be had (a state so wild that the solve fails: as good as stiff)."""
    try:
        with np.errstate(all="ignore"):  # a wild state's rate overflows: inf
            rate = spectral_radius(system, y, t)
    except (ArithmeticError, np.linalg.LinAlgError):
        return math.inf
    return rate if math.isfinite(rate) else math.inf


def _outgrown(duration: float, rate: float, max_steps: int) -> str:
    """How a run of ``duration`` s whose fastest rate is ``rate`` (1/s) outgrows float64's
    time resolution and the run bound."""
    follow = duration * rate  # steps of 1 / rate: what following the fastest rate takes
    following = (f"following the fastest rate, {rate:.3g}/s, takes ~{follow:.2g} steps; "
                 if follow >= 1.0 else "")
    return (f"over {duration:.6g} s the run asks for more than float64 and the run bound give "
            f"(at t = {duration:.6g} s float64 resolves time to t·eps = "
            f"{duration * tolerances.EPS:.3g} s; {following}the bound is {max_steps:.3g} steps, "
            f"{setting_ref('max_steps')}); shorten {setting_ref('time.duration')}")


def _failure(system, status: int, fstats: np.ndarray, y: np.ndarray, max_steps: int,
             method: str, t1: float = math.inf, duration: float = math.inf) -> BaseException:
    """The exception of a kernel's failure ``status`` at fstats[3] (see systems_dop853), in a
    segment ending at ``t1`` of a run of ``duration`` (s)."""
    t, source = float(fstats[3]), system.scene.source
    fewer = _fewer(method)
    wild = (f"{source}: the {method} run diverged at t = {t:.6g} s: "
            + (f"its Newton iterations ran away; shorten {setting_ref('step')}"
               if method == "implicit" else
               "its step is beyond the method's stability there; "
               + (f"shorten {setting_ref('step')} or " if method != "dop853" else "")
               + f"run the implicit method ({setting_ref('integrator')})"))
    if status == codes.UNDERFLOW and method != "dop853":  # Newton failed in MAX_PIECES pieces
        rate = _rate_at(system, y, t)  # a step that resolves it, 1/ρ, may not fit the bound
        fits = not duration * rate > max_steps or not math.isfinite(rate)
        return ArithmeticError(f"{source}: {method}'s Newton iterations failed at "
                               f"t = {t:.6g} s even in {MAX_PIECES} pieces of the step; "
                               f"shorten {setting_ref('step')}"
                               + ("" if fits else f"; but {_outgrown(duration, rate, max_steps)}"))
    if status == codes.UNDERFLOW:
        floor = STEP_UNDERFLOW * max(abs(t), t1)  # the kernel's rule (systems_dop853.segment)
        rate = _rate_at(system, y, t)
        if rate * floor < 1.0:  # a step of 1/ρ resolves the fastest rate: not stiffness
            allows = (f"its fastest rate, {rate:.3g}/s, allows steps of ~{1.0 / rate:.3g} s"
                      if rate > 0 else "it has no rate of its own there")
            return RunBudgetError(f"{source}: dop853's step fell below {floor:.3g} s "
                                  f"({STEP_UNDERFLOW:g} of {max(abs(t), t1):.6g} s) at "
                                  f"t = {t:.6g} s where the system is not stiff ({allows}): "
                                  + _outgrown(duration, rate, max_steps)
                                  + f" or loosen {setting_ref('rtol')}")
        return ArithmeticError(f"{source}: dop853's step fell to round-off at t = {t:.6g} s "
                               "(every trial step failed or was rejected): the system is "
                               "too stiff or singular there for an explicit method; run the "
                               f"implicit method ({setting_ref('integrator')})")
    if status == DIVERGED:
        return ArithmeticError(wild)
    if status == codes.STEP_LIMIT:
        return RunBudgetError(f"{source}: the run took {max_steps} steps by "
                              f"t = {t:.6g} s, the run bound ({setting_ref('max_steps')}); "
                              f"raise it or {fewer}")
    # M is positive definite at any finite state of a valid scene
    indefinite = ArithmeticError(wild.replace("diverged", "went wild (its mass matrix lost "
                                              "positive definiteness)", 1))
    if status == codes.LINALG:
        return indefinite
    if status == codes.CROSSED:
        since = float(fstats[4])  # == t: an accepted state at the pose (NEAR_SINGULAR_MARGIN)
        return SingularPose(system.singular_message(t, np.zeros((system.m, 0)),
                                                    since=None if since == t else since))
    if status == codes.UNCLOSED and not fstats[5] < UNCLOSED_WILD * system.tree.size:
        return ArithmeticError(wild)  # a residual many sizes long: the step, not the loop
    if status == codes.UNCLOSED:
        return SingularPose(f"{system.scene.source}: the joints cannot be closed at "
                            f"t = {t:.6g} s (position residual {fstats[5]:.3g} m after "
                            f"{PROJECT_ITERATIONS} Newton steps): the loop cannot be "
                            "assembled there")
    try:  # the rank fell: the numpy solve at that state names the joints that lost it
        with np.errstate(all="ignore"):  # a wild state's overflow is said below, not warned
            system.solve(t, y)
    except SingularPose as exc:
        return exc
    except np.linalg.LinAlgError:  # not even M is positive definite there
        return indefinite
    return SingularPose(system.singular_message(t, np.zeros((system.m, 0))))
