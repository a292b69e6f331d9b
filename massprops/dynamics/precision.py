"""Error against run time: every applicable integrator over a ladder of settings, measured against
the exact solution where the scene has one, else against a reference run converged far beyond
the tightest setting (and checked).

Each run reports its wall time (best of repeats for short runs: timers on a shared machine only
ever add), steps, evaluations, its error in the contract's metric (massprops.dynamics.accuracy),
and its own `error_estimate`, so the estimate's honesty can be read off next to the truth.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from massprops.dynamics.accuracy import Scales, exact_roundoff, global_estimate, state_error
from massprops.dynamics.budget import sample_times
from massprops.dynamics.compiled.compiling import prepare
from massprops.dynamics.forces import ForceProgram
from massprops.dynamics.frames import to_world
from massprops.dynamics.integrators import INTEGRATORS, SYSTEM_METHODS
from massprops.dynamics.model import Scene
from massprops.dynamics.program import compile_forces
from massprops.dynamics.runner import run_once
from massprops.dynamics.simulate import choose_integrator, default_step, simulate
from massprops.errors import ComputationError, MassPropsError, UsageError

RTOL_LADDER = tuple(10.0**-k for k in range(3, 13))
"""Adaptive settings, loose to tight; the reference runs at 1e-13 (see `reference_run`)."""

STEP_HALVINGS = 10
"""Fixed-step ladder: h0, h0/2, ..., h0/2^9 with h0 = 16 × the scene's default step."""

MAX_RUNG_STEPS = 2_000_000
"""Fixed-step settings that would take more steps than this are left out of the ladder (a
tenth of the run bound, budget.MAX_STEPS, which bounds every rung's run as any run's)."""

SAMPLES = 10
"""Errors are the worst over this many equally spaced times (and the end), not the end alone."""

AT_REFERENCE = 3.0
"""A ladder stops once a run's error is within this factor of the reference's own accuracy:
finer rungs would only measure the reference."""

MAX_RUN_S = 1.0
"""A ladder stops after a rung that took longer than this: the next one would take twice as long
(fixed steps halve), and the diagram has its shape by then."""

MIN_TIMED_S = 0.2
"""Short runs are repeated (up to 5 times) until they have used this much time; best is kept."""


@dataclass(frozen=True)
class PrecisionRun:
    """One rung of a ladder. error and estimate are in the contract's metric; None = the run
    failed or its error could not be measured (error: ``reason`` says why) or unavailable
    (estimate). A failed rung is a row like any other: wall_time_s, steps and evaluations are
    what it spent until it stopped (wall_time_s None when it never started)."""

    integrator: str
    setting: float
    setting_name: str
    wall_time_s: float | None
    error: float | None
    estimate: float | None
    steps: int
    evaluations: int
    reason: str | None = None

    def as_dict(self) -> dict:
        return {"integrator": self.integrator, "setting": self.setting,
                "setting_name": self.setting_name, "wall_time_s": self.wall_time_s,
                "error": self.error, "error_estimate": self.estimate, "steps": self.steps,
                "evaluations": self.evaluations, "reason": self.reason}


@dataclass(frozen=True)
class PrecisionReport:
    """reference: how the truth was obtained (kind "exact" or "run", method, setting, its own
    accuracy and how that was checked); runs: every rung of every ladder."""

    reference: dict
    runs: tuple[PrecisionRun, ...]

    def as_dict(self) -> dict:
        return {"reference": self.reference, "runs": [r.as_dict() for r in self.runs]}


def applicable(scene: Scene, program: ForceProgram, registry: Mapping) -> list[str]:
    """Integrators that can run this scene (exact only where a closed form exists:
    ForceProgram.exact_solvable)."""
    closed = program.exact_solvable
    return [name for name, spec in registry.items() if spec.kind != "exact" or closed]


def ladder(spec, scene: Scene, program: ForceProgram) -> list[float]:
    """Settings from coarse to fine for one integrator."""
    if spec.kind == "adaptive":
        return list(RTOL_LADDER)
    if spec.kind == "exact":
        return [0.0]
    h0 = 16.0 * default_step(scene, program, stiff=spec.stiff)
    steps = [h0 / 2**k for k in range(STEP_HALVINGS)]
    return [h for h in steps if scene.time.duration / h <= MAX_RUNG_STEPS]


def precision(scene: Scene, *, integrators: Sequence[str] | None = None,
              progress: Callable[[float], None] | None = None,
              notice: Callable[[str], None] | None = None) -> PrecisionReport:
    """Run the ladders of ``integrators`` (default: every applicable one) on ``scene``.

    notice(text) is called once if compiled kernels are missing from numba's cache and are being
    compiled (all of them are made ready first: massprops.dynamics.compiled.compiling.prepare)."""
    program = compile_forces(scene)
    names = applicable(scene, program, INTEGRATORS)
    if integrators:
        unknown = sorted(set(integrators) - set(names))
        if unknown:
            raise UsageError(f"{scene.source}: integrator(s) {', '.join(unknown)} do not apply "
                             f"to this scene; applicable: {', '.join(names)}")
        names = [n for n in names if n in integrators]
    # the times every rung's `simulate(every=...)` samples, so that all compare at each
    every = scene.time.duration / SAMPLES  # every run samples at the same times
    # the rungs' kernels and the reference's (a time-stepped method's: its systems entries)
    method = reference_method(scene, program, INTEGRATORS)
    prepare(list(dict.fromkeys(k for n in (*names, method) for k in _kernels(n))), notice)
    truth, reference = reference_run(scene, program, INTEGRATORS, every)
    scales = Scales.of(scene.body.size, truth, scene.time.duration)
    plan = [(n, s) for n in names for s in ladder(INTEGRATORS[n], scene, program)]
    floor = AT_REFERENCE * reference["accuracy"]
    runs, done = [], set()
    for i, (name, setting) in enumerate(plan):
        if name not in done:
            run = _rung(scene, program, INTEGRATORS[name], setting, truth, scales)
            runs.append(run)
            if ((run.error is not None and run.error <= floor)
                    or (run.wall_time_s or 0.0) > MAX_RUN_S):
                done.add(name)
        if progress is not None:
            progress((i + 1) / len(plan))
    return PrecisionReport(reference, tuple(runs))


def reference_method(scene: Scene, program: ForceProgram, registry: Mapping) -> str:
    """The integrator of `reference_run`: exact, implicit (stiff scenes) or dop853."""
    if "exact" in applicable(scene, program, registry):
        return "exact"
    return "implicit" if choose_integrator(scene, program, registry)[0] == "implicit" else "dop853"


def reference_run(scene: Scene, program: ForceProgram, registry: Mapping, every: float):
    """(trajectory, description) of the truth the ladders are measured against, sampled every
    ``every`` s.

    exact where it applies; else dop853 at rtol 1e-13 checked against rtol 1e-12 (their distance
    bounds the tighter one's error by tolerance proportionality: ~1/9 of it), or, for stiff
    scenes, the implicit method at a step 4× finer than its finest rung checked against twice
    that step by Richardson's rule.
    """
    method = reference_method(scene, program, registry)
    if method == "exact":
        truth = _trajectory(scene, program, registry["exact"], 0.0, every)
        scales = Scales.of(scene.body.size, truth, scene.time.duration)
        return truth, {"kind": "exact", "integrator": "exact", "setting": None,
                       "accuracy": exact_roundoff(truth, scales),
                       "checked": "closed form; accuracy is its round-off bound"}
    if method == "implicit":
        spec = registry["implicit"]
        fine = ladder(spec, scene, program)[-1] / 4
        truth, check, coarse = (_trajectory(scene, program, spec, k * fine, every)
                                for k in (1, 2, 4))
        scales = Scales.of(scene.body.size, truth, scene.time.duration)
        accuracy = global_estimate(spec.kind, spec.order, state_error(truth, check, scales),
                                   state_error(check, coarse, scales), spec.estimate_order)
        how = (f"implicit at step {fine:.3g} s against steps {2 * fine:.3g} s and "
               f"{4 * fine:.3g} s (Richardson with the observed order)")
    else:
        spec, fine = registry["dop853"], 1e-13
        truth, check = (_trajectory(scene, program, spec, rtol, every) for rtol in (fine, 1e-12))
        scales = Scales.of(scene.body.size, truth, scene.time.duration)
        accuracy = state_error(truth, check, scales) / 9
        how = "dop853 at rtol 1e-13 against rtol 1e-12 (tolerance proportionality)"
    return truth, {"kind": "run", "integrator": spec.name, "setting": fine,
                   "accuracy": accuracy, "checked": how}


def _kernels(name: str) -> list[str]:
    """The kernels (`compiling.prepare`'s names) a run of ``name`` uses: a time-stepped
    method's systems entries (`systems.methods.kernels`), else its own."""
    if name not in SYSTEM_METHODS:
        return [name]
    # deferred: the systems engine, loaded when a time-stepped run is asked for
    from massprops.dynamics.systems.methods import kernels

    return kernels(name)


@dataclass(frozen=True)
class WorldRun:
    """One run's world-frame samples (`frames.Trajectory`, up to where it got), its steps,
    evaluations and main-run seconds; ``failure``: why it ended short (None: it did not), in
    words that follow the scene's name; ``interrupted``: Ctrl-C stopped it."""

    trajectory: object
    steps: int
    evaluations: int
    wall: float
    failure: str | None = None
    interrupted: bool = False


def one_run(scene: Scene, program: ForceProgram, spec, setting: float, every: float, *,
            estimate: bool = False, max_steps: int | None = None) -> WorldRun:
    """``scene`` (its compiled ``program``) run once with ``spec`` at ``setting`` (rtol or step,
    s), sampled every ``every`` s as `simulate` samples (`budget.sample_times`), on the engine
    `simulate` runs it on: a time-stepping method through `simulate` itself (its error
    estimate's companions beside it only with ``estimate``), a splitting method or the closed
    form on its one-body kernel (`runner.run_once`). The reference, the rungs' repeats and the
    benchmarks all time and measure runs this one way."""
    if spec.name in SYSTEM_METHODS:
        try:
            res = simulate(scene, integrator=spec.name, rtol=setting, step=setting, every=every,
                           max_steps=max_steps, estimate=estimate)
        except ComputationError as exc:
            part: Any = exc.partial  # a SimulationResult, as far as the run got
            if part is None:
                raise
            return WorldRun(part.trajectory, part.steps, part.evaluations, part.wall_time_s,
                            exc.template.removeprefix(f"{scene.source}: "))
        return WorldRun(res.trajectory, res.steps, res.evaluations, res.wall_time_s,
                        interrupted=res.interrupted)
    t_out = sample_times(scene.time.duration, every)
    run = run_once(scene, program, spec, setting, t_out, max_steps=max_steps)
    traj = to_world(scene, run.t, run.y, program, with_energy=False)
    return WorldRun(traj, int(run.stats[0]), int(run.stats[1]), run.wall,
                    None if run.failure is None else str(run.failure), run.interrupted)


def _trajectory(scene, program, spec, setting, every: float):
    """The world-frame samples, every ``every`` s, of one reference run of ``spec`` at
    ``setting`` (`one_run`: a time-stepped method with no estimate of its own, the reference
    checks itself against a second run)."""
    run = one_run(scene, program, spec, setting, every)
    if run.interrupted:  # Ctrl-C: a part of a run is no reference
        raise KeyboardInterrupt
    if run.failure is not None:
        raise ComputationError(f"{scene.source}: the reference run failed: {run.failure}")
    return run.trajectory


def _main_wall(scene, program, spec, setting, every: float) -> float:
    """The wall time (s) of one more main run of ``spec`` at ``setting`` as `simulate` runs it
    (a time-stepped method with its estimate's companions beside it, `one_run`)."""
    run = one_run(scene, program, spec, setting, every, estimate=True)
    if run.interrupted:
        raise KeyboardInterrupt
    return run.wall


def _rung(scene, program, spec, setting, truth, scales) -> PrecisionRun:
    every = scene.time.duration / SAMPLES
    name = {"adaptive": "rtol", "fixed": "step_s"}.get(spec.kind, "none")
    try:
        result = simulate(scene, integrator=spec.name, rtol=setting, step=setting, every=every)
    except MassPropsError as exc:  # diverged, out of budget, a setting the method refuses
        part = getattr(exc, "partial", None)
        why = exc.template.removeprefix(f"{scene.source}: ")  # settings said by the caller
        if part is None:
            return PrecisionRun(spec.name, setting, name, None, None, None, 0, 0, why)
        return PrecisionRun(spec.name, setting, name, part.wall_time_s, None, None, part.steps,
                            part.evaluations, why)
    if result.interrupted:  # Ctrl-C: a part of a run is no rung (simulate returns it whole)
        raise KeyboardInterrupt
    error = state_error(result.trajectory, truth, scales)
    wall, spent, tries = result.wall_time_s, result.wall_time_s, 1
    while spent < MIN_TIMED_S and tries < 5:  # best of repeats: only the main run is timed
        again = _main_wall(scene, program, spec, setting, every)
        wall, spent, tries = min(wall, again), spent + again, tries + 1
    measured = math.isfinite(error)
    return PrecisionRun(spec.name, setting, name, wall, error if measured else None,
                        result.diagnostics["error_estimate"], result.steps, result.evaluations,
                        None if measured else "its state ran away: the error overflows")
