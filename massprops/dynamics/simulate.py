"""Run a scene: choose the method, run it beside its error-estimate companions, convert at the
edges (frames.py), check for divergence, report diagnostics.

A time-stepped method (`integrators.SYSTEM_METHODS`) runs the body as the system of one body
(`systems.one_body`, `systems.run.simulate_system`): one engine for one body and many. Its
samples come back here as the states the one-body edges take (`_engine_states`), so the
trajectory, reactions and diagnostics keep the one-body contract. The closed forms and the
splitting methods (one free body's exact rotation flows, which have no system form) run on the
one-body kernels (runner.py).
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from massprops.dynamics.accuracy import (
    Scales,
    companion_settings,
    estimate_note,
    exact_roundoff,
    global_estimate,
    state_error,
)
from massprops.dynamics.budget import (
    ENERGY_BLOWUP,
    STEP_BUDGET,
    check_fixed_steps,
    sample_times,
)
from massprops.dynamics.budget import default_step as budget_default_step
from massprops.dynamics.compiled.compiling import prepare
from massprops.dynamics.forces import (
    DRAG,
    FORCE_BODY,
    FORCE_WORLD,
    GRAVITY,
    SPRING,
    TORQUE_BODY,
    TORQUE_WORLD,
    ForceProgram,
)
from massprops.dynamics.frames import Trajectory, to_world
from massprops.dynamics.integrators import INTEGRATORS, SYSTEM_METHODS
from massprops.dynamics.integrators.base import check_rtol, ignored_settings
from massprops.dynamics.model import Scene
from massprops.dynamics.program import compile_forces
from massprops.dynamics.runner import RawRun, run_once, stability_hint
from massprops.errors import ComputationError, DivergenceError, RunBudgetError, UsageError
from massprops.parallel import CancellableJob, beside
from massprops.rotation import canonical, matrix_to_quat, quat_multiply, quat_to_matrix


@dataclass(frozen=True, eq=False)
class SimulationResult:
    """What `massprops simulate` reports. ``trajectory`` holds the samples (always t = 0 and the
    last time reached); ``interrupted`` is set when Ctrl-C stopped the run early."""

    integrator: str
    reason: str
    steps: int
    evaluations: int
    rejected: int
    wall_time_s: float
    warmup_time_s: float
    trajectory: Trajectory
    diagnostics: dict
    interrupted: bool = False
    notes: tuple[str, ...] = field(default=())

    def row(self, n: int) -> dict:
        """Sample ``n``'s state as the contract's ``final`` object."""
        return self.trajectory.row(n)

    def as_dict(self) -> dict:
        return {"integrator": self.integrator, "reason": self.reason, "steps": self.steps,
                "evaluations": self.evaluations, "rejected_steps": self.rejected,
                "wall_time_s": self.wall_time_s, "warmup_time_s": self.warmup_time_s,
                "interrupted": self.interrupted, "final": self.trajectory.row(-1),
                "diagnostics": self.diagnostics}


# --- choosing a method -------------------------------------------------------------------------
def choose_integrator(scene: Scene, program: ForceProgram, available: Mapping
                      ) -> tuple[str, str]:
    """(name, reason) for ``time.integrator: auto``."""
    if program.exact_solvable and "exact" in available:
        if program.joints is not None and program.joints.closed_form:
            return "exact", ("heavy symmetric top on a fixed point: closed form (Lagrange "
                             "top), no time stepping")
        return "exact", "torque-free with constant force: closed-form solution, no time stepping"
    rate = program.stiffest_rate
    explicit_steps = scene.time.duration * rate / 2.8
    if rate > 0 and explicit_steps > STEP_BUDGET and "implicit" in available:
        return "implicit", (f"stiff: fastest rate {rate:.3g}/s would need ~{explicit_steps:.2g} "
                            f"explicit steps (> {STEP_BUDGET:.0e})")
    return "dop853", "non-stiff with forces or torques: adaptive 8th order"


def is_conservative(program: ForceProgram) -> bool:
    """Energy is conserved: only gravity and undamped springs, no windows (a held body: judged
    on its own forces and its joints' drive and damping)."""
    if program.joints is not None:
        program = program.joints.physical
    codes = program.codes
    if np.isin(codes, [FORCE_WORLD, FORCE_BODY, TORQUE_WORLD, TORQUE_BODY]).any():
        return False
    if (codes == DRAG).any() and np.any(program.params[codes == DRAG, 0:2] != 0):
        return False
    return not np.any(program.params[codes == SPRING, 9] != 0)


def cannot_gain_energy(program: ForceProgram) -> bool:
    """No term does external work (only gravity, springs, dampers, drag)."""
    if program.joints is not None:
        program = program.joints.physical
    return not np.isin(program.codes, [FORCE_WORLD, FORCE_BODY, TORQUE_WORLD, TORQUE_BODY]).any()


# --- the run -----------------------------------------------------------------------------------
def simulate(scene: Scene, *, integrator: str | None = None, rtol: float | None = None,
             step: float | None = None, every: float | None = None,
             progress: Callable[[float], None] | None = None,
             notice: Callable[[str], None] | None = None,
             max_steps: int | None = None, estimate: bool = True) -> SimulationResult:
    """Integrate ``scene``; options override the scene's time/output settings.

    progress(fraction) is called between compiled chunks of the main run, and while waiting for
    the error estimate's companion runs (on a helper thread, see `_start_companions`), always on
    the calling thread. notice(text) is called once, on the calling thread, if the run's
    compiled kernels are not in numba's cache and are being compiled (massprops.dynamics
    .compiling.prepare). Ctrl-C during the run returns the samples computed so far with
    ``interrupted=True`` (the caller exits 130). ``max_steps`` bounds every run of the call
    (default budget.MAX_STEPS; see massprops.dynamics.budget). ``estimate=False`` leaves out the
    error estimate's companion runs (``error_estimate`` is then None; a closed form's round-off
    bound costs nothing and stays).
    Raises DivergenceError (exit 3) naming the time and the likely cause, RunBudgetError (exit 3)
    when the run bound refuses or stops the run (both carry what was computed).
    """
    program = compile_forces(scene)
    name = integrator or scene.time.integrator
    if name == "auto":
        name, reason = choose_integrator(scene, program, INTEGRATORS)
    elif name not in INTEGRATORS:
        raise UsageError(f"unknown integrator {name!r}; choose from auto, "
                         + ", ".join(sorted(INTEGRATORS)))
    else:
        reason = "chosen by the user"
    spec = INTEGRATORS[name]
    ignored = ignored_settings(spec, rtol, step)
    result = _simulate(scene, program, spec, name, reason, rtol, step, every, progress, notice,
                       max_steps, estimate)
    if ignored is None:
        return result
    return dataclasses.replace(result, notes=(f"{scene.source}: {ignored}", *result.notes))


def _simulate(scene: Scene, program: ForceProgram, spec, name: str, reason: str,
              rtol: float | None, step: float | None, every: float | None, progress, notice,
              max_steps: int | None, estimate: bool = True) -> SimulationResult:
    """`simulate` once its method is known (``spec``, ``name`` and why, ``reason``)."""
    if spec.kind == "exact" and not program.exact_solvable:
        raise UsageError(f"{scene.source}: integrator exact solves only torque-free scenes with "
                         "constant forces (gravity, world-frame forces at the centre of mass) "
                         "and the heavy symmetric top on a fixed point; use auto, dop853 or a "
                         "splitting method")
    duration = scene.time.duration
    t_out = sample_times(duration, every if every is not None else scene.output.every,
                         str(scene.source))
    setting = _setting(spec, scene, program, rtol, step)
    if spec.kind == "fixed":  # the run bound: refused before anything is compiled or run
        check_fixed_steps(name, duration, setting, len(program.breakpoints(0.0, duration)),
                          str(scene.source), max_steps)
    if name in SYSTEM_METHODS:
        return _as_system(scene, program, spec, name, reason, setting,
                          every if every is not None else scene.output.every, progress, notice,
                          max_steps, estimate)
    prepare([spec.name], notice)
    side = _start_companions(scene, program, spec, setting, t_out, max_steps) \
        if estimate else None
    wait = True
    try:
        return _run_and_check(scene, program, spec, name, reason, setting, t_out, progress, side,
                              max_steps)
    except KeyboardInterrupt:  # Ctrl-C while the kernel compiles or loads, before the run's
        wait = False  # chunks: leave now; the helper stops at its first report (a compile later)
        raise
    finally:  # a main run that failed or was interrupted no longer needs its companions
        if side is not None and wait:
            side.stop()
        elif side is not None:
            side.cancel()


def _run_and_check(scene, program, spec, name, reason, setting, t_out, progress,
                   side: CancellableJob | None, max_steps: int | None = None
                   ) -> SimulationResult:
    """The main run, its diagnostics and divergence checks, then the error estimate from the
    companion runs of ``side`` (running meanwhile on another thread; None for closed forms)."""
    main_progress = None if progress is None else beside(progress, side)
    run = run_once(scene, program, spec, setting, t_out, main_progress, max_steps)
    conservative = is_conservative(program)
    traj = to_world(scene, run.t, run.y, program, with_energy=conservative
                    or cannot_gain_energy(program))
    floor = _energy_floor(program, scene.body.size, run.y[0])
    diagnostics = _diagnostics(program, run.y, traj, conservative, floor)
    result = SimulationResult(
        integrator=name, reason=reason, steps=int(run.stats[0]),
        evaluations=int(run.stats[1]), rejected=int(run.stats[2]),
        wall_time_s=run.wall, warmup_time_s=run.warmup, trajectory=traj,
        diagnostics=diagnostics, interrupted=run.interrupted)
    onset = _energy_blowup(traj, floor)  # only scenes that cannot gain energy carry an energy
    if onset is not None:  # name when it started, even if the state overflowed only later
        raise _blowup(scene, program, name, setting, onset, result,
                      f" ({run.failure.what})" if run.failure else "")
    if run.failure is not None and run.exhausted:
        raise RunBudgetError(f"{scene.source}: {run.failure}", partial=result)
    if run.failure is not None:
        raise DivergenceError(f"{scene.source}: {run.failure}", partial=result)
    if not run.interrupted and (side is not None or spec.kind == "exact"):
        others = None if side is None else _companion_runs(side, progress)
        diagnostics["error_estimate"] = _error_estimate(scene, program, spec, setting, traj,
                                                        others, run.short_err,
                                                        int(run.stats[0]))
        note = estimate_note(scene.source, diagnostics["error_estimate"], name, spec.kind)
        if note is not None:
            result = dataclasses.replace(result, notes=(*result.notes, note))
    return result


# --- one body as the system of one body ---------------------------------------------------------
def _as_system(scene: Scene, program: ForceProgram, spec, name: str, reason: str,
               setting: float, every: float | None, progress, notice,
               max_steps: int | None, estimate: bool = True) -> SimulationResult:
    """``scene`` run with ``name`` at ``setting`` as the system of one body, its result in the
    one-body contract's terms; a failure carries its samples the same way (``partial``)."""
    # deferred: the systems engine, loaded when a run starts (as the registry is)
    from massprops.dynamics.systems.methods import kernels
    from massprops.dynamics.systems.one_body import as_system
    from massprops.dynamics.systems.run import simulate_system

    start = time.perf_counter()
    prepare(kernels(name), notice)
    warmup = time.perf_counter() - start
    fixed = spec.kind == "fixed"
    try:
        run = simulate_system(as_system(scene), integrator=name,
                              rtol=None if fixed else setting, step=setting if fixed else None,
                              every=every, estimate=estimate, max_steps=max_steps,
                              progress=progress, interruptible=True)
    except ComputationError as exc:  # said as one body's failures are, with its samples
        if exc.partial is None:
            raise
        part, floor = _one_body_result(scene, program, exc.partial, name, reason, warmup)
        if isinstance(exc, RunBudgetError):
            raise RunBudgetError(exc.template, partial=part) from exc
        onset = _energy_blowup(part.trajectory, floor)  # when it started, not where it broke
        if onset is not None:
            raise _blowup(scene, program, name, setting, onset, part) from exc
        hint = stability_hint(program, setting, name) \
            if program.stiffest_rate > 0 and not spec.stiff else ""  # an explicit step's limit
        raise DivergenceError(exc.template + (f"; {hint}" if hint else ""),
                              partial=part) from exc
    result, floor = _one_body_result(scene, program, run, name, reason, warmup)
    onset = _energy_blowup(result.trajectory, floor)
    if onset is not None:
        raise _blowup(scene, program, name, setting, onset, result)
    note = estimate_note(scene.source, result.diagnostics["error_estimate"], name, spec.kind)
    return result if note is None else dataclasses.replace(result, notes=(note,))


def _blowup(scene: Scene, program: ForceProgram, name: str, setting: float, onset: float,
            partial: SimulationResult, later: str = "") -> DivergenceError:
    """The divergence of a run whose energy grew ENERGY_BLOWUP-fold from ``onset`` (s);
    ``later``: what then stopped the run, if anything did."""
    return DivergenceError(
        f"{scene.source}: {name} diverged near t = {onset:.6g} s: the energy grew by more than "
        f"{ENERGY_BLOWUP:.0e} times its initial value{later}; "
        + stability_hint(program, setting, name), partial=partial)


def _one_body_result(scene: Scene, program: ForceProgram, run, name: str, reason: str,
                     warmup: float) -> tuple[SimulationResult, float]:
    """A system run of the one body (`systems.run.SystemResult`) as a one-body result, and its
    energy floor (J, `_energy_floor`): its samples turned into the states the one-body edges
    take, then the one-body trajectory, reactions and diagnostics, with the run's error
    estimate (in the one-body metric: the system's length is the body's size,
    `systems.one_body`)."""
    y = _engine_states(scene, program, run.samples)
    conservative = is_conservative(program)
    traj = to_world(scene, run.samples.t, y, program,
                    with_energy=conservative or cannot_gain_energy(program))
    floor = _energy_floor(program, scene.body.size, y[0])
    diagnostics = _diagnostics(program, y, traj, conservative, floor)
    diagnostics["error_estimate"] = run.diagnostics.get("error_estimate")
    return SimulationResult(
        integrator=name, reason=reason, steps=run.steps, evaluations=run.evaluations,
        rejected=run.rejected, wall_time_s=run.wall_time_s, warmup_time_s=warmup,
        trajectory=traj, diagnostics=diagnostics, interrupted=run.interrupted), floor


def _engine_states(scene: Scene, program: ForceProgram, samples) -> np.ndarray:
    """(n, 13) the states the one-body kernels step, from the one body's system samples: a free
    body's [r, v, q_p, ω_p] (principal frame, frames.py), a held body's pinned-body state
    [P, 0, q_E, ω_E] (joints.reduction: frame E of J_P's axes about the held point P)."""
    q = samples.orientation[:, 0]
    w_body = np.einsum("nji,nj->ni", quat_to_matrix(q), samples.angular_velocity[:, 0])
    if program.joints is None:
        axes = scene.body.principal_axes  # v_body = A v_principal
        r, v = samples.position[:, 0], samples.velocity[:, 0]
    else:
        model = program.joints
        axes = model.pinned.principal_axes  # v_body = R_E v_E
        r = np.broadcast_to(model.y0[0:3], (len(q), 3))
        v = np.zeros((len(q), 3))
    q_frame = canonical(quat_multiply(q, matrix_to_quat(axes)))
    return np.hstack([r, v, q_frame, w_body @ axes])


# --- the error-estimate companions, beside the main run -----------------------------------------
def _start_companions(scene: Scene, program: ForceProgram, spec, setting: float,
                      t_out: np.ndarray, max_steps: int | None = None
                      ) -> CancellableJob | None:
    """The companion runs of the error estimate (accuracy.companion_settings), one after the
    other on a helper thread, or None for a method that needs none. They run while the main run
    does: the kernels release the GIL (compiled.jit.kernel), so on two cores the estimate adds
    little wall time to the main run (a fixed step's 2h and 4h companions cost 3/4 of it,
    dop853's at rtol / 20 ~1.45 times). Every run is deterministic in its own arrays: the numbers
    are bit-identical to running them all one after the other."""
    settings = companion_settings(spec.kind, setting)
    if not settings:
        return None

    def companions(report: Callable[[float], None]) -> list[RawRun]:
        runs: list[RawRun] = []
        for k, other in enumerate(settings):
            def part(fraction: float, k: int = k) -> None:  # of all companions together
                report((k + fraction) / len(settings))

            runs.append(run_once(scene, program, spec, other, t_out, part, max_steps))
            if runs[-1].interrupted or runs[-1].failure is not None:
                break  # the next companion could add nothing
        return runs

    return CancellableJob(companions)


def _companion_runs(side: CancellableJob, progress: Callable[[float], None] | None
                    ) -> list[RawRun] | None:
    """Wait for the companions (moving the progress bar meanwhile); None when they cannot give
    an estimate: Ctrl-C while waiting (as when they ran after the main run), or a setting the
    method refuses: the main run's result stands."""
    poll = None if progress is None else (lambda: progress(0.5 + 0.5 * side.fraction))
    try:
        return side.result(poll)
    except (KeyboardInterrupt, UsageError):
        return None


def _error_estimate(scene, program, spec, setting, traj, others: list[RawRun] | None,
                    short_err: float = 0.0, steps: int = 0) -> float | None:
    """Global error estimate in the contract's metric (see massprops.dynamics.accuracy) from the
    companion runs ``others`` (in accuracy.companion_settings order); None when it cannot be had
    (interrupted, missing, or the first companion diverged). ``short_err`` (see RawRun) is added
    in the metric's units, conservatively: its component is unknown, so it is divided by the
    smallest scale (a quaternion error δ is an angle of about 2δ); and the round-off of the main
    run's ``steps`` position updates (`_position_roundoff`)."""
    scales = Scales.of(scene.body.size, traj, scene.time.duration)
    if not companion_settings(spec.kind, setting):
        return exact_roundoff(traj, scales)
    if not others or others[0].interrupted:
        return None
    if others[0].failure is not None:  # the 2h companion diverged: h is near the stability limit
        return None  # and the error cannot be estimated this way: reported as unknown (null)
    first = to_world(scene, others[0].t, others[0].y, program, with_energy=False)
    d_companions = None  # no second companion, or it diverged (4h beyond the stability limit)
    if len(others) > 1 and not others[1].interrupted and others[1].failure is None:
        second = to_world(scene, others[1].t, others[1].y, program, with_energy=False)
        d_companions = state_error(first, second, scales)
    blind = short_err * max(1 / scales.size, 1 / scales.velocity, 2.0,
                            1 / scales.angular_velocity)
    estimate = global_estimate(spec.kind, spec.order, state_error(traj, first, scales),
                               d_companions, spec.estimate_order) + blind \
        + _position_roundoff(traj, scales, steps)
    return estimate if math.isfinite(estimate) else None  # a companion ran away: size unknown


def _position_roundoff(traj: Trajectory, scales: Scales, steps: int) -> float:
    """The round-off of ``steps`` position updates in the contract's metric, which the step
    companions cannot see (they round alike): each update of r is rounded to eps |r|, and the
    roundings add up as a random walk, 4 eps |r|max / size √steps. It matters far from the
    origin: a body at 1e5 sizes taking 1e5 steps of splitting6 (far.yaml) has ~3e-8 of it where
    its truncation estimate says 5e-10."""
    eps = float(np.finfo(float).eps)
    with np.errstate(over="ignore"):
        reach = float(np.max(np.linalg.norm(traj.position, axis=1))) / scales.size
    return 4 * eps * reach * math.sqrt(max(steps, 1))


def _setting(spec, scene: Scene, program: ForceProgram, rtol: float | None,
             step: float | None) -> float:
    if spec.kind == "adaptive":  # refused before a kernel is compiled or loaded
        check_rtol(float(rtol if rtol is not None else scene.time.rtol), str(scene.source))
        return float(rtol if rtol is not None else scene.time.rtol)
    if spec.kind == "fixed":
        h = step if step is not None else scene.time.step
        if h is None:
            h = default_step(scene, program, stiff=spec.stiff)
        return float(h)
    return 0.0


def default_step(scene: Scene, program: ForceProgram, *, stiff: bool) -> float:
    """A fixed step when the scene gives none, `budget.default_step`'s rule: the fastest rate is
    twice the spin (0.05 rad per step) and, for explicit methods, the stiffest force's rate. A
    stiff method steps over the stiff rate: that is its point."""
    spin = float(np.linalg.norm(scene.initial.angular_velocity))
    rate = max(spin / 0.5, 0.0 if stiff else program.stiffest_rate)
    return budget_default_step(scene.time.duration, rate)


def _energy_floor(program: ForceProgram, size: float, y0: np.ndarray) -> float:
    """An energy scale of the scene that does not vanish when the total energy happens to be
    zero (a body at rest level with the origin of the potential): the initial kinetic energy,
    m |g| × size per gravity term, k × size² per spring (J)."""
    kinetic = 0.5 * program.mass * float(y0[3:6] @ y0[3:6]) + 0.5 * float(
        program.inertia @ y0[10:13] ** 2)
    own = program.joints.physical if program.joints is not None else program
    rows = own.params[own.codes == GRAVITY]
    weight = float(np.sum(np.linalg.norm(rows[:, 0:3], axis=1))) * size
    springs = float(np.sum(own.params[own.codes == SPRING, 7])) * size * size
    return kinetic + weight + springs


def _energy_blowup(traj: Trajectory, floor: float = 0.0) -> float | None:
    """First sample time where the energy of a scene that cannot gain energy is no longer finite
    or has grown ENERGY_BLOWUP-fold of its scale (|E0|, at least ``floor``, J); None if it never
    does (or the scene has no energy)."""
    e = traj.energy
    if e is None or len(e) < 2:
        return None
    scale = max(abs(e[0]), floor, 1e-300)
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(e) | (e - e[0] > ENERGY_BLOWUP * scale)
    return float(traj.t[int(np.argmax(bad))]) if bad.any() else None


def _diagnostics(program: ForceProgram, y: np.ndarray, traj: Trajectory, conservative: bool,
                 floor: float = 0.0) -> dict:
    with np.errstate(over="ignore", invalid="ignore"):  # a run-away state: inf, reported null
        return {key: value if value is None or math.isfinite(value) else None
                for key, value in _drifts(program, y, traj, conservative, floor).items()}


def _drifts(program: ForceProgram, y: np.ndarray, traj: Trajectory, conservative: bool,
            floor: float = 0.0) -> dict:
    qn = np.abs(np.linalg.norm(y[:, 6:10], axis=1) - 1.0)
    out = {"energy_rel_drift": None, "angular_momentum_rel_drift": None,
           "quaternion_norm_error": float(qn.max()), "error_estimate": None,
           "constraint_drift": None}
    if conservative and traj.energy is not None:
        e = traj.energy
        kinetic = 0.5 * program.mass * np.sum(y[0, 3:6] ** 2) + 0.5 * np.sum(
            program.inertia * y[0, 10:13] ** 2)
        scale = max(abs(e[0]), kinetic, floor, 1e-300)
        out["energy_rel_drift"] = float(np.max(np.abs(e - e[0])) / scale)
    if not program.has_torque:
        h = traj.angular_momentum
        scale = np.linalg.norm(h[0])
        drift = np.max(np.linalg.norm(h - h[0], axis=1))
        out["angular_momentum_rel_drift"] = float(drift / scale) if scale > 0 else float(drift)
    if program.joints is not None:  # about the held point, and the joints' own drift
        out.update(program.joints.diagnostics(y, traj))
    return out
