"""`massprops precision` on a system: every method a system runs with (`methods`), dop853 over a
ladder of tolerances and rk4, midpoint and implicit over ladders of halving steps, each run's
error in the contract's metric against a reference run at rtol 1e-13 whose own accuracy is
measured against a run at 1e-12 (self-consistency), next to its error estimate.

A ladder stops as the one-body ladders do (`dynamics.precision`): once a run is within
AT_REFERENCE of the reference's accuracy, or took longer than MAX_RUN_S.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from massprops.dynamics.precision import (
    AT_REFERENCE,
    MAX_RUN_S,
    SAMPLES,
    STEP_HALVINGS,
    PrecisionReport,
    PrecisionRun,
)
from massprops.dynamics.systems.methods import SYSTEM_INTEGRATORS, default_step
from massprops.dynamics.systems.model import SystemScene
from massprops.dynamics.systems.outputs import distance
from massprops.dynamics.systems.run import prepare, simulate_system
from massprops.errors import MassPropsError, UsageError

RTOL_LADDER = tuple(10.0**-k for k in range(4, 12))
"""Settings, loose to tight; the reference runs at REFERENCE_RTOL."""

REFERENCE_RTOL, CHECK_RTOL = 1e-13, 1e-12

MAX_LADDER_STEPS = 200_000
"""Fixed steps that would take more steps than this are left out of a ladder."""


def ladder(scene: SystemScene, name: str) -> list[float]:
    """Settings from coarse to fine for method ``name``: RTOL_LADDER for dop853; for a fixed
    step, h0 / 2^k (k < STEP_HALVINGS), h0 = 16 × `methods.default_step`."""
    if name == "dop853":
        return list(RTOL_LADDER)
    system, y0, _ = prepare(scene)
    h0 = 16.0 * default_step(system, y0, scene.time.duration, stiff=name == "implicit")
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
    ref = simulate_system(scene, rtol=REFERENCE_RTOL, every=every, estimate=False,
                          notice=notice)
    check = simulate_system(scene, rtol=CHECK_RTOL, every=every, estimate=False)
    size = scene.size
    reference = {"kind": "run", "integrator": "dop853", "setting": REFERENCE_RTOL,
                 "accuracy": distance(check.samples, ref.samples, size),
                 "checked": f"self-consistency: its distance to a run at rtol {CHECK_RTOL:g}"}
    plan = [(n, s) for n in names for s in ladder(scene, n)]
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
                                  every=every)
        except MassPropsError as exc:  # a step beyond stability, Newton failing, ...
            why = exc.template.removeprefix(f"{scene.source}: ")  # settings said by the caller
            runs.append(PrecisionRun(name, setting, kind, None, None, None, 0, 0, why))
            continue
        error = distance(run.samples, ref.samples, size)
        runs.append(PrecisionRun(name, setting, kind, run.wall_time_s, error,
                                 run.diagnostics["error_estimate"], run.steps, run.evaluations))
        if error < AT_REFERENCE * reference["accuracy"] or run.wall_time_s > MAX_RUN_S:
            done.add(name)
    return PrecisionReport(reference, tuple(runs))
