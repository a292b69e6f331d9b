"""Run a scene: frames at the edges, segments between force-window edges, closed forms where the
scene allows them, diagnostics at the end.

Inside, the rotation lives in the principal frame: q_p (principal -> world) and omega' (principal),
with J' = diag(I1, I2, I3). At the edges: A_body = A_p Rᵀ (R: principal axes as columns, body
frame), omega_body = R omega', omega_world = A_p omega'.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from massprops.dynamics.accuracy import (
    Scales,
    companion_settings,
    exact_roundoff,
    global_estimate,
    state_error,
)
from massprops.dynamics.forces import (
    DRAG,
    FORCE_BODY,
    FORCE_WORLD,
    SPRING,
    TORQUE_BODY,
    TORQUE_WORLD,
    ForceProgram,
    compile_forces,
    energy,
)
from massprops.dynamics.model import Scene
from massprops.dynamics.stiffness import unresolved, unresolved_mode_error
from massprops.errors import DivergenceError, UsageError
from massprops.parallel import CancellableJob
from massprops.rotation import canonical, matrix_to_quat, quat_multiply, quat_to_matrix

STEP_BUDGET = 2_000_000
"""`auto` picks the implicit method when an explicit one would need more steps than this to
resolve the stiffest rate over the run (RK-type stability limit ~2.8 / rate)."""

ENERGY_BLOWUP = 1e6
"""A conservative or dissipative scene whose energy grows by this factor of its scale diverged."""

CHUNK_STEPS = 50_000
"""Steps per compiled call (~0.05 s): between calls Ctrl-C and the progress bar are served.
Chunks are sized by step counts, never by timers, so results do not depend on the machine."""

FIRST_CHUNK = 1 / 32
"""An adaptive run's first call covers this fraction of the run; later ones grow or shrink
(at most ×16, at least ×½) toward CHUNK_STEPS steps, from the steps the previous call took."""


@dataclass(frozen=True, eq=False)
class Trajectory:
    """Sampled motion, SI, world frame unless named: t (n,) s; position (n, 3) COM; orientation
    (n, 4) body->world [w, x, y, z]; velocity (n, 3); angular_velocity (n, 3) world;
    angular_velocity_body (n, 3) body frame; angular_momentum (n, 3) world, about the COM,
    kg·m²/s; energy (n,) J or None where the scene makes it meaningless (external work)."""

    t: np.ndarray
    position: np.ndarray
    orientation: np.ndarray
    velocity: np.ndarray
    angular_velocity: np.ndarray
    angular_velocity_body: np.ndarray
    angular_momentum: np.ndarray
    energy: np.ndarray | None = None

    def row(self, i: int) -> dict:
        return {"t": float(self.t[i]), "position": self.position[i].tolist(),
                "orientation": self.orientation[i].tolist(), "velocity": self.velocity[i].tolist(),
                "angular_velocity": self.angular_velocity[i].tolist(),
                "angular_velocity_body": self.angular_velocity_body[i].tolist()}


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

    def as_dict(self) -> dict:
        return {"integrator": self.integrator, "reason": self.reason, "steps": self.steps,
                "evaluations": self.evaluations, "rejected_steps": self.rejected,
                "wall_time_s": self.wall_time_s, "warmup_time_s": self.warmup_time_s,
                "interrupted": self.interrupted, "final": self.trajectory.row(-1),
                "diagnostics": self.diagnostics}


# --- frames at the edges -----------------------------------------------------------------------
def initial_principal_state(scene: Scene) -> np.ndarray:
    """(13,) [r, v, q_p, omega'] at t = 0 from the scene's world/body initial values."""
    body, ini = scene.body, scene.initial
    q_r = matrix_to_quat(body.principal_axes)  # principal -> body
    q_p = canonical(quat_multiply(ini.orientation, q_r))
    if ini.angular_velocity_frame == "body":
        w_p = body.principal_axes.T @ ini.angular_velocity
    else:
        w_p = quat_to_matrix(q_p).T @ ini.angular_velocity
    return np.concatenate([ini.position, ini.velocity, q_p, w_p])


def to_world(scene: Scene, t: np.ndarray, y: np.ndarray, program: ForceProgram,
             with_energy: bool) -> Trajectory:
    """Principal-frame states (n, 13) -> a Trajectory in the contract's frames."""
    r_axes = scene.body.principal_axes
    q_p = y[:, 6:10] / np.linalg.norm(y[:, 6:10], axis=1, keepdims=True)
    q_body = canonical(quat_multiply(q_p, matrix_to_quat(r_axes.T)))
    w_p = y[:, 10:13]
    a_p = quat_to_matrix(q_p)
    w_world = np.einsum("nij,nj->ni", a_p, w_p)
    h_world = np.einsum("nij,nj->ni", a_p, program.inertia * w_p)
    return Trajectory(t.copy(), y[:, 0:3].copy(), q_body, y[:, 3:6].copy(), w_world,
                      w_p @ r_axes.T, h_world, energy(y, program) if with_energy else None)


# --- choosing a method -------------------------------------------------------------------------
def choose_integrator(scene: Scene, program: ForceProgram, available: Mapping
                      ) -> tuple[str, str]:
    """(name, reason) for ``time.integrator: auto``."""
    if not program.has_torque and program.translation_closed_form and "exact" in available:
        return "exact", "torque-free with constant force: closed-form solution, no time stepping"
    rate = program.stiffest_rate
    explicit_steps = scene.time.duration * rate / 2.8
    if rate > 0 and explicit_steps > STEP_BUDGET and "implicit" in available:
        return "implicit", (f"stiff: fastest rate {rate:.3g}/s would need ~{explicit_steps:.2g} "
                            f"explicit steps (> {STEP_BUDGET:.0e})")
    return "dop853", "non-stiff with forces or torques: adaptive 8th order"


def is_conservative(program: ForceProgram) -> bool:
    """Energy is conserved: only gravity and undamped springs, no windows."""
    codes = program.codes
    if np.isin(codes, [FORCE_WORLD, FORCE_BODY, TORQUE_WORLD, TORQUE_BODY]).any():
        return False
    if (codes == DRAG).any() and np.any(program.params[codes == DRAG, 0:2] != 0):
        return False
    return not np.any(program.params[codes == SPRING, 9] != 0)


def cannot_gain_energy(program: ForceProgram) -> bool:
    """No term does external work (only gravity, springs, dampers, drag)."""
    return not np.isin(program.codes, [FORCE_WORLD, FORCE_BODY, TORQUE_WORLD, TORQUE_BODY]).any()


DIAGNOSTIC_SAMPLES = 100
"""Without a sampling interval, the run is still sampled at this many intervals (dense output,
cheap) so that drifts are maxima over the run and a divergence is located in time."""


def sample_times(duration: float, every: float | None) -> np.ndarray:
    """Output times: k·every below the duration, and the duration itself (never accumulated)."""
    if every is None:
        return np.linspace(0.0, duration, DIAGNOSTIC_SAMPLES + 1)
    n = int(math.floor(duration / every * (1 + 1e-12)))
    t = every * np.arange(n + 1)
    return t if t[-1] >= duration * (1 - 1e-12) else np.append(t, duration)


# --- the run -----------------------------------------------------------------------------------
def simulate(scene: Scene, *, integrator: str | None = None, rtol: float | None = None,
             step: float | None = None, every: float | None = None,
             progress: Callable[[float], None] | None = None) -> SimulationResult:
    """Integrate ``scene``; options override the scene's time/output settings.

    progress(fraction) is called between compiled chunks of the main run, and while waiting for
    the error estimate's companion runs (on a helper thread, see `_start_companions`), always on
    the calling thread. Ctrl-C during the run returns the samples computed so far with
    ``interrupted=True`` (the caller exits 130).
    Raises DivergenceError (exit 3) naming the time and the likely cause.
    """
    from massprops.dynamics.integrators import INTEGRATORS

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
    if spec.kind == "exact" and (program.has_torque or not program.translation_closed_form):
        raise UsageError(f"{scene.source}: integrator exact solves only torque-free scenes with "
                         "constant forces (gravity, world-frame forces at the centre of mass); "
                         "use auto, dop853 or a splitting method")
    duration = scene.time.duration
    t_out = sample_times(duration, every if every is not None else scene.output.every)
    setting = _setting(spec, scene, program, rtol, step)
    side = _start_companions(scene, program, spec, setting, t_out)
    wait = True
    try:
        return _run_and_check(scene, program, spec, name, reason, setting, t_out, progress, side)
    except KeyboardInterrupt:  # Ctrl-C while the kernel compiles or loads, before the run's
        wait = False  # chunks: leave now; the helper stops at its first report (a compile later)
        raise
    finally:  # a main run that failed or was interrupted no longer needs its companions
        if side is not None and wait:
            side.stop()
        elif side is not None:
            side.cancel()


def _run_and_check(scene, program, spec, name, reason, setting, t_out, progress,
                   side: CancellableJob | None) -> SimulationResult:
    """The main run, its diagnostics and divergence checks, then the error estimate from the
    companion runs of ``side`` (running meanwhile on another thread; None for closed forms)."""
    main_progress = None if progress is None else _joint_progress(progress, side)
    run = run_once(scene, program, spec, setting, t_out, main_progress)
    conservative = is_conservative(program)
    traj = to_world(scene, run.t, run.y, program, with_energy=conservative
                    or cannot_gain_energy(program))
    diagnostics = _diagnostics(program, run.y, traj, conservative)
    result = SimulationResult(
        integrator=name, reason=reason, steps=int(run.stats[0]),
        evaluations=int(run.stats[1]), rejected=int(run.stats[2]),
        wall_time_s=run.wall, warmup_time_s=run.warmup, trajectory=traj,
        diagnostics=diagnostics, interrupted=run.interrupted)
    onset = _energy_blowup(traj)  # only scenes that cannot gain energy carry an energy
    if onset is not None:  # name when it started, even if the state overflowed only later
        later = f" ({run.failure.split(': ', 1)[1].split(';')[0]})" if run.failure else ""
        raise DivergenceError(
            f"{scene.source}: {name} diverged near t = {onset:.6g} s: the energy grew by more "
            f"than {ENERGY_BLOWUP:.0e} times its initial value{later}; "
            + _stability_hint(program, setting, name), partial=result)
    if run.failure is not None:
        raise DivergenceError(f"{scene.source}: {run.failure}", partial=result)
    if not run.interrupted:
        others = None if side is None else _companion_runs(side, progress)
        diagnostics["error_estimate"] = _error_estimate(scene, program, spec, setting, traj,
                                                        others, run.short_err)
    return result


# --- the error-estimate companions, beside the main run -----------------------------------------
def _start_companions(scene: Scene, program: ForceProgram, spec, setting: float,
                      t_out: np.ndarray) -> CancellableJob | None:
    """The companion runs of the error estimate (accuracy.companion_settings), one after the
    other on a helper thread, or None for a method that needs none. They run while the main run
    does: the kernels release the GIL (_jit.kernel), so on two cores the estimate adds little
    wall time to the main run (a fixed step's 2h and 4h companions cost 3/4 of it, dop853's at
    rtol / 20 ~1.45 times). Every run is deterministic in its own arrays: the numbers are
    bit-identical to running them all one after the other."""
    settings = companion_settings(spec.kind, setting)
    if not settings:
        return None

    def companions(report: Callable[[float], None]) -> list[RawRun]:
        runs: list[RawRun] = []
        for k, other in enumerate(settings):
            def part(fraction: float, k: int = k) -> None:  # of all companions together
                report((k + fraction) / len(settings))

            runs.append(run_once(scene, program, spec, other, t_out, part))
            if runs[-1].interrupted or runs[-1].failure is not None:
                break  # the next companion could add nothing
        return runs

    return CancellableJob(companions)


def _joint_progress(progress: Callable[[float], None], side: CancellableJob | None
                    ) -> Callable[[float], None]:
    """The main run's progress callback: the mean of the main run's and the companions'
    fractions (called on this thread only, between the main run's chunks)."""
    if side is None:
        return progress
    return lambda fraction: progress(0.5 * fraction + 0.5 * side.fraction)


def _companion_runs(side: CancellableJob, progress: Callable[[float], None] | None
                    ) -> list[RawRun] | None:
    """Wait for the companions (moving the progress bar meanwhile); None when they cannot give
    an estimate: Ctrl-C while waiting (as when they ran after the main run), or a setting the
    method refuses (dop853 at rtol / 20 below round-off): the main run's result stands."""
    poll = None if progress is None else (lambda: progress(0.5 + 0.5 * side.fraction))
    try:
        return side.result(poll)
    except (KeyboardInterrupt, UsageError):
        return None


def scale_floors(scene: Scene) -> np.ndarray:
    """(4,) smallest error scales of the r, v, q, ω blocks for error-controlled methods: the body
    size, size/duration, 1, 1/duration (the floors of the contract's metric, accuracy.Scales)."""
    size, duration = scene.body.size, scene.time.duration
    return np.array([size, size / duration, 1.0, 1.0 / duration])


@dataclass(frozen=True, eq=False)
class RawRun:
    """One integration in the principal frame: samples t (n,), y (n, 13) up to where it got,
    stats [steps, nfev, rejected, njev, status], wall and warm-up seconds, failure message, and
    short_err: the kernels' own local error estimates (absolute, max-norm over the state) summed
    over the fixed-step segments of one or two steps, which a 2h companion run cannot see."""

    t: np.ndarray
    y: np.ndarray
    stats: np.ndarray
    wall: float
    warmup: float
    failure: str | None
    interrupted: bool
    short_err: float = 0.0


def run_once(scene: Scene, program: ForceProgram, spec, setting: float, t_out: np.ndarray,
             progress: Callable[[float], None] | None = None) -> RawRun:
    """Integrate ``scene`` once with ``spec`` at ``setting``, sampled at ``t_out``."""
    runner = _Runner(spec, program, setting, progress, scene.time.duration,
                     scale_floors(scene))
    y_out, t_reached, interrupted = runner.run(initial_principal_state(scene), t_out)
    keep = t_out <= t_reached
    t_kept, y_kept = t_out[keep], y_out[keep]
    if t_kept[-1] < t_reached:  # interrupted or failed between samples: keep the last state
        t_kept, y_kept = np.append(t_kept, t_reached), np.vstack([y_kept, runner.y_last])
    return RawRun(t_kept, y_kept, runner.stats, runner.wall, runner.warmup, runner.failure,
                  interrupted, runner.short_err)


def _error_estimate(scene, program, spec, setting, traj, others: list[RawRun] | None,
                    short_err: float = 0.0) -> float | None:
    """Global error estimate in the contract's metric (see massprops.dynamics.accuracy) from the
    companion runs ``others`` (in accuracy.companion_settings order); None when it cannot be had
    (interrupted, missing, or the first companion diverged). ``short_err`` (see RawRun) is added
    in the metric's units, conservatively: its component is unknown, so it is divided by the
    smallest scale (a quaternion error δ is an angle of about 2δ)."""
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
                               d_companions) + blind
    if unresolved(spec, setting, program):  # a mode all three runs fail alike: measured apart
        estimate = max(estimate, unresolved_mode_error(scene, program, spec, setting, scales))
    return estimate


def _setting(spec, scene: Scene, program: ForceProgram, rtol: float | None,
             step: float | None) -> float:
    if spec.kind == "adaptive":
        return float(rtol if rtol is not None else scene.time.rtol)
    if spec.kind == "fixed":
        h = step if step is not None else scene.time.step
        if h is None:
            h = default_step(scene, program, stiff=spec.stiff)
        return float(h)
    return 0.0


def default_step(scene: Scene, program: ForceProgram, *, stiff: bool) -> float:
    """A fixed step when the scene gives none: 1/1000 of the run, and small against the spin rate
    (0.05 rad per step) and, for explicit methods, against the stiffest rate (0.1 per step). A
    stiff method steps over the stiff rate: that is its point."""
    ini = scene.initial
    spin = float(np.linalg.norm(ini.angular_velocity))
    rate = max(spin / 0.5, 0.0 if stiff else program.stiffest_rate)
    return min(scene.time.duration / 1e3, 0.1 / rate) if rate > 0 else scene.time.duration / 1e3


def _energy_blowup(traj: Trajectory) -> float | None:
    """First sample time where the energy of a scene that cannot gain energy is no longer finite
    or has grown ENERGY_BLOWUP-fold; None if it never does (or the scene has no energy)."""
    e = traj.energy
    if e is None or len(e) < 2:
        return None
    scale = max(abs(e[0]), 1e-300)
    with np.errstate(invalid="ignore"):
        bad = ~np.isfinite(e) | (e - e[0] > ENERGY_BLOWUP * scale)
    return float(traj.t[int(np.argmax(bad))]) if bad.any() else None


def _stability_hint(program: ForceProgram, setting: float, name: str) -> str:
    rate = program.stiffest_rate
    if rate > 0:
        return (f"the stiffest term has rate {rate:.3g}/s, so explicit steps must stay below "
                f"~{2.8 / rate:.3g} s (step here: {setting:.3g}); use integrator implicit or a "
                "smaller step")
    return "try a smaller step or tolerance"


def _diagnostics(program: ForceProgram, y: np.ndarray, traj: Trajectory, conservative: bool
                 ) -> dict:
    qn = np.abs(np.linalg.norm(y[:, 6:10], axis=1) - 1.0)
    out = {"energy_rel_drift": None, "angular_momentum_rel_drift": None,
           "quaternion_norm_error": float(qn.max()), "error_estimate": None}
    if conservative and traj.energy is not None:
        e = traj.energy
        kinetic = 0.5 * program.mass * np.sum(y[0, 3:6] ** 2) + 0.5 * np.sum(
            program.inertia * y[0, 10:13] ** 2)
        scale = max(abs(e[0]), kinetic, 1e-300)
        out["energy_rel_drift"] = float(np.max(np.abs(e - e[0])) / scale)
    if not program.has_torque:
        h = traj.angular_momentum
        scale = np.linalg.norm(h[0])
        drift = np.max(np.linalg.norm(h - h[0], axis=1))
        out["angular_momentum_rel_drift"] = float(drift / scale) if scale > 0 else float(drift)
    return out


class _Runner:
    """Walks the segments between window edges in chunks, filling the samples."""

    def __init__(self, spec, program: ForceProgram, setting: float, progress, duration: float,
                 floors: np.ndarray):
        self.spec, self.program, self.setting, self.floors = spec, program, setting, floors
        self.progress, self.duration = progress, duration
        self.stats = np.zeros(5, dtype=np.int64)
        self.wall, self.warmup = 0.0, 0.0
        self.failure: str | None = None
        self.y_last = None
        self.t_now = 0.0
        self.short_err = 0.0

    def run(self, y0: np.ndarray, t_out: np.ndarray):
        p = self.program
        rot_only = p.translation_closed_form
        y_full = y0.copy()
        y_out = np.full((len(t_out), 13), np.nan)
        edges = np.concatenate([[0.0], p.breakpoints(0.0, self.duration), [self.duration]])
        self._warm_up(y0, rot_only)
        start = time.perf_counter()
        self.t_now, interrupted = 0.0, False
        try:
            for t0, t1 in zip(edges[:-1], edges[1:]):
                active = p.active(0.5 * (t0 + t1))
                self._segment(y_full, t0, t1, active, rot_only, t_out, y_out)
                if self.failure is not None:
                    break
        except KeyboardInterrupt:  # y_full and self.t_now hold the last finished chunk
            interrupted = True
        self.wall = time.perf_counter() - start
        self.y_last = y_full
        return y_out, self.t_now, interrupted

    def _warm_up(self, y0: np.ndarray, rot_only: bool) -> None:
        """Compile or load the kernel from cache on a tiny problem; timed apart from the run."""
        p = self.program
        start = time.perf_counter()
        y = (y0[6:] if rot_only else y0).copy()
        self.spec.run_segment(y, 0.0, 1e-9, self.setting if self.setting else 1e-9,
                              (p.active(0.0), p.codes, p.params, p.mass, p.inertia, self.floors),
                              rot_only, np.empty(0), np.empty((0, y.size)),
                              np.zeros(5, dtype=np.int64))
        self.warmup = time.perf_counter() - start

    def _segment(self, y_full, t0, t1, active, rot_only, t_out, y_out) -> None:
        """Advance y_full (13,) from t0 to t1 in chunks and fill the samples; self.t_now follows
        the time reached after every chunk (so Ctrl-C keeps it)."""
        p = self.program
        first = t0 == 0.0
        sel = np.flatnonzero((t_out >= t0) & (t_out <= t1) if first else
                             (t_out > t0) & (t_out <= t1))
        accel = p.constant_force(active) / p.mass if rot_only else None
        arrays = (active, p.codes, p.params, p.mass, p.inertia, self.floors)
        # a segment of one or two steps (a force window shorter than the step) is stepped the
        # same way by a 2h companion, so its error is invisible to Richardson: keep the kernel's
        # own local estimate of it
        short = self.spec.kind == "fixed" and (t1 - t0) <= 2 * self.setting * (1 + 1e-12)
        t = t0
        length = self._first_chunk(t0, t1)
        while t < t1:
            t_end = self._chunk_end(t, t0, t1, length)
            idx = sel[(t_out[sel] >= t) & (t_out[sel] <= t_end)] if t == t0 else \
                sel[(t_out[sel] > t) & (t_out[sel] <= t_end)]
            y = y_full[6:].copy() if rot_only else y_full.copy()
            ys = np.empty((idx.size, y.size))
            steps_before = int(self.stats[0])
            err, t_reached = self.spec.run_segment(y, t, t_end, self.setting, arrays, rot_only,
                                                   t_out[idx], ys, self.stats)
            if rot_only:
                r0, v0 = y_full[0:3].copy(), y_full[3:6].copy()
                tau = t_out[idx] - t
                ys = np.hstack([r0 + np.outer(tau, v0) + 0.5 * np.outer(tau**2, accel),
                                v0 + np.outer(tau, accel), ys])
                dt = t_reached - t
                y_full[0:3] = r0 + v0 * dt + 0.5 * accel * dt * dt
                y_full[3:6] = v0 + accel * dt
                y_full[6:] = y
            else:
                y_full[:] = y
            good = t_out[idx] <= t_reached
            y_out[idx[good]] = ys[good]
            self.t_now = t_reached
            if short:
                self.short_err += err
            if self.stats[4] != 0 or t_reached < t_end:  # NaN, underflow, or stopped early
                self.failure = self._failure_message(t_reached)
                return
            if self.progress is not None:
                self.progress(t_end / self.duration)
            taken = max(int(self.stats[0]) - steps_before, 1)
            length = (t_end - t) * min(16.0, max(0.5, CHUNK_STEPS / taken))
            t = t_end

    def _first_chunk(self, t0: float, t1: float) -> float:
        if self.spec.kind == "exact":  # no steps: one evaluation per sample, cost independent of t
            return t1 - t0
        if self.spec.kind == "fixed":
            return CHUNK_STEPS * self.setting
        return FIRST_CHUNK * self.duration

    def _chunk_end(self, t: float, t0: float, t1: float, length: float) -> float:
        """End of the next call: t + length, on the segment's step grid for fixed steps."""
        if self.spec.kind != "fixed":
            return t1 if t + length >= t1 * (1 - 1e-12) else t + length
        n = max(1, math.ceil((t1 - t0) / self.setting * (1 - 1e-12)))
        h = (t1 - t0) / n
        k = round((t - t0) / h) + max(1, round(length / h))
        return t1 if k >= n else t0 + k * h

    def _failure_message(self, t_reached: float) -> str:
        status = int(self.stats[4])
        what = "the state became NaN or infinite" if status == 1 else \
            "the step size fell below round-off (the problem is stiff or singular there)" \
            if status == 2 else "the integrator stopped early"
        return (f"{self.spec.name} diverged at t = {t_reached:.6g} s: {what}; "
                + _stability_hint(self.program, self.setting, self.spec.name))
