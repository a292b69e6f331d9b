"""`massprops precision` on a system: dop853 (the systems' own) over a ladder of tolerances,
each run's error in the contract's metric against a reference run at rtol 1e-13 whose own
accuracy is measured against a run at 1e-12 (self-consistency), next to its error estimate."""

from __future__ import annotations

from massprops.dynamics.precision import (
    AT_REFERENCE,
    MAX_RUN_S,
    SAMPLES,
    PrecisionReport,
    PrecisionRun,
)
from massprops.dynamics.systems.model import SystemScene
from massprops.dynamics.systems.run import distance, simulate_system
from massprops.errors import ComputationError

RTOL_LADDER = tuple(10.0**-k for k in range(4, 12))
"""Settings, loose to tight; the reference runs at REFERENCE_RTOL."""

REFERENCE_RTOL, CHECK_RTOL = 1e-13, 1e-12


def precision_system(scene: SystemScene, progress=None) -> PrecisionReport:
    """The work-precision ladder of ``scene`` (see the module doc)."""
    every = scene.time.duration / SAMPLES
    ref = simulate_system(scene, rtol=REFERENCE_RTOL, every=every, estimate=False)
    check = simulate_system(scene, rtol=CHECK_RTOL, every=every, estimate=False)
    size = scene.size
    reference = {"kind": "run", "integrator": "dop853", "setting": REFERENCE_RTOL,
                 "accuracy": distance(check.samples, ref.samples, size),
                 "checked": f"self-consistency: its distance to a run at rtol {CHECK_RTOL:g}"}
    runs: list[PrecisionRun] = []
    for k, rtol in enumerate(RTOL_LADDER):
        if progress is not None:
            progress(k / len(RTOL_LADDER))
        try:
            run = simulate_system(scene, rtol=rtol, every=every)
        except ComputationError as exc:
            runs.append(PrecisionRun("dop853", rtol, "rtol", None, None, None, 0, 0,
                                     str(exc)))
            continue
        error = distance(run.samples, ref.samples, size)
        runs.append(PrecisionRun("dop853", rtol, "rtol", run.wall_time_s, error,
                                 run.diagnostics["error_estimate"], run.steps, run.evaluations))
        if error < AT_REFERENCE * reference["accuracy"] or run.wall_time_s > MAX_RUN_S:
            break
    return PrecisionReport(reference, runs)
