"""`massprops precision` on a system: every method a system runs with (`methods`), dop853 over a
ladder of tolerances and rk4, midpoint and implicit over ladders of halving steps, each run's
error in the contract's metric against a reference run (`reference_run`: dop853 at rtol 1e-13
checked against 1e-12; Radau IIA at a fine step for a stiff system), next to its estimate.

A ladder stops as the one-body ladders do (`dynamics.precision`): once a run is within
AT_REFERENCE of the reference's accuracy, or took longer than MAX_RUN_S.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence

from massprops.dynamics.accuracy import global_estimate
from massprops.dynamics.compiled.compiling import prepare as prepare_kernels
from massprops.dynamics.precision import (
    AT_REFERENCE,
    MAX_RUN_S,
    SAMPLES,
    STEP_HALVINGS,
    PrecisionReport,
    PrecisionRun,
)
from massprops.dynamics.systems.methods import (
    SYSTEM_INTEGRATORS,
    choose,
    default_step,
    is_stiff,
    kernels,
)
from massprops.dynamics.systems.model import SystemScene
from massprops.dynamics.systems.outputs import distance
from massprops.dynamics.systems.run import prepare, simulate_system
from massprops.errors import ComputationError, MassPropsError, RunBudgetError, UsageError

RTOL_LADDER = tuple(10.0**-k for k in range(4, 12))
"""Settings, loose to tight; the reference runs at REFERENCE_RTOL."""

REFERENCE_RTOL, CHECK_RTOL = 1e-13, 1e-12

MAX_REFERENCE_STEPS = 2_000_000
"""The reference runs' bound: the truth may take longer than a rung."""

PILOT_SHARE = 50
"""The reference is first run over 1/PILOT_SHARE of the duration: a system whose reference
would run into MAX_REFERENCE_STEPS at that pace (minutes of stepping, then a refusal) is refused
at once (the pilot costs 1/PILOT_SHARE of the reference)."""

MAX_LADDER_STEPS = 200_000
"""Fixed steps that would take more steps than this are left out of a ladder, and every rung
stops at this many steps (the run bound): a method that cannot follow the system over its
duration fails that rung and its ladder ends, instead of running for hours."""


def ladder(scene: SystemScene, name: str, start: tuple) -> list[float]:
    """Settings from coarse to fine for method ``name``: RTOL_LADDER for dop853; for a fixed
    step, h0 / 2^k (k < STEP_HALVINGS), h0 = 16 × `methods.default_step` at ``start``, the
    (System, y0) of `run.prepare`."""
    if name == "dop853":
        return list(RTOL_LADDER)
    system, y0 = start
    h0 = 16.0 * default_step(system, y0, scene.time.duration, stiff=is_stiff(name))
    steps = [h0 / 2**k for k in range(STEP_HALVINGS)]
    return [h for h in steps if scene.time.duration / h <= MAX_LADDER_STEPS]


def precision_system(scene: SystemScene, integrators: Sequence[str] | None = None,
                     progress: Callable[[float], None] | None = None,
                     notice: Callable[[str], None] | None = None) -> PrecisionReport:
    """The work-precision ladders of ``scene`` for ``integrators`` (default: every method a
    system runs with), see the module doc; ``notice`` as for `simulate_system`."""
    names = [n for n in SYSTEM_INTEGRATORS if n != "auto"]
    if integrators:
        unknown = sorted(set(integrators) - set(names) - {"auto"})
        if unknown:
            raise UsageError(f"{scene.source}: integrator(s) {', '.join(unknown)} do not apply "
                             f"to a system; applicable: {', '.join(names)}")
        names = [n for n in names if n in integrators]
    every = scene.time.duration / SAMPLES
    system, y0, _ = prepare(scene)
    # every rung's kernels and the reference's choice (its stiffness probe), at once: one
    # notice, and a helper compiles some on the second core
    prepare_kernels(list(dict.fromkeys(k for n in (*names, "auto") for k in kernels(n))),
                    notice)
    ref, reference = reference_run(scene, every, (system, y0), notice)
    plan = [(n, s) for n in names for s in ladder(scene, n, (system, y0))]
    runs: list[PrecisionRun] = []
    done: set[str] = set()
    for k, (name, setting) in enumerate(plan):
        if progress is not None:
            progress(k / len(plan))
        if name in done:
            continue
        kind = "rtol" if name == "dop853" else "step_s"
        try:
            run = simulate_system(scene, integrator=name, rtol=setting, step=setting,
                                  every=every, max_steps=MAX_LADDER_STEPS)
        except MassPropsError as exc:  # a step beyond stability, Newton failing, ...
            why = exc.template.removeprefix(f"{scene.source}: ")  # settings said by the caller
            runs.append(PrecisionRun(name, setting, kind, None, None, None, 0, 0, why))
            if isinstance(exc, RunBudgetError):  # finer settings take more steps still
                done.add(name)
            continue
        error = distance(run.samples, ref.samples, scene.size)
        runs.append(PrecisionRun(name, setting, kind, run.wall_time_s, error,
                                 run.diagnostics["error_estimate"], run.steps, run.evaluations))
        if error < AT_REFERENCE * reference["accuracy"] or run.wall_time_s > MAX_RUN_S:
            done.add(name)
    return PrecisionReport(reference, tuple(runs))


def reference_run(scene: SystemScene, every: float, start: tuple, notice=None):
    """(run, description) of the truth the ladders are measured against, as for one body
    (`dynamics.precision.reference_run`): dop853 at REFERENCE_RTOL, its accuracy its distance
    to a run at CHECK_RTOL; for a stiff system (where `auto` takes implicit) Radau IIA at a
    quarter of its ladder's finest step, checked against 2 and 4 times that step by
    Richardson's rule (dop853 would need the stiff rate's steps). ``start``: (System, y0)."""
    system, y0 = start
    stiff = choose(system, y0, "auto", None, None)[0] == "implicit"
    method = "implicit" if stiff else "dop853"
    fine = ladder(scene, "implicit", start)[-1] / 4 if stiff else REFERENCE_RTOL
    settings = (fine, 2 * fine, 4 * fine) if stiff else (fine, CHECK_RTOL)
    refused = (f"{scene.source}: the reference run ({method} at "
               f"{'step' if stiff else 'rtol'} {fine:g}) needs more than "
               f"{MAX_REFERENCE_STEPS} steps: the system is too stiff over its duration to be "
               "measured; shorten time.duration")
    duration = scene.time.duration
    pilot = dataclasses.replace(scene, time=dataclasses.replace(
        scene.time, duration=duration / PILOT_SHARE))
    pace: float
    try:
        pace = PILOT_SHARE * simulate_system(
            pilot, integrator=method, rtol=fine, step=fine, every=duration, estimate=False,
            notice=notice, max_steps=2 * MAX_REFERENCE_STEPS // PILOT_SHARE).steps
    except RunBudgetError:
        pace = math.inf
    except ComputationError:
        pace = 0.0  # the run itself says what went wrong, in its own words, below
    if pace > MAX_REFERENCE_STEPS:
        raise ComputationError(refused.replace(
            " steps:", f" steps (the pace of its first {duration / PILOT_SHARE:.3g} s):", 1))
    try:
        runs = [simulate_system(scene, integrator=method, rtol=x, step=x, every=every,
                                estimate=False, notice=notice, max_steps=MAX_REFERENCE_STEPS)
                for x in settings]
    except RunBudgetError as exc:
        raise ComputationError(refused) from exc
    size = scene.size
    if stiff:
        accuracy = global_estimate("fixed", 5, distance(runs[0].samples, runs[1].samples, size),
                                   distance(runs[1].samples, runs[2].samples, size), 3)
        how = (f"implicit at step {fine:.3g} s against steps {2 * fine:.3g} s and "
               f"{4 * fine:.3g} s (Richardson with the observed order)")
    else:
        accuracy = distance(runs[1].samples, runs[0].samples, size)
        how = f"self-consistency: its distance to a run at rtol {CHECK_RTOL:g}"
    return runs[0], {"kind": "run", "integrator": method, "setting": fine,
                     "accuracy": accuracy, "checked": how}
