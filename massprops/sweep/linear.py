"""First-order sensitivities from the engine itself (``sweep --linear``): each output's
derivative by each drawn scalar value at the draws' centres, by central differences, and the
spread the delta method predicts from them.

The step is a tenth of the value's own spread, h = sd/10 (small against the spread, so the
derivative is the one at the centre, and large against the runs' own error, which the
difference divides by h). Each key takes four runs, all other keys at their centres:
D(h) = (f(c + h) − f(c − h)) / 2h and D(h/2). The derivative reported is D(h/2); its accuracy,
|D(h/2) − D(h)|, bounds both its truncation (D's error falls four times from h to h/2, so what
is left in D(h/2) is a third of that difference) and the runs' noise (which differs between the
two). A grid key or a drawn tensor has no derivative (null). The delta method's sd of an
output is √Σ (D_k sd_k)² over the keys, the keys drawn independently.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from massprops.sweep.sample import Plan, run_at, scene_value

STEP_OF_SPREAD = 0.1
"""h = STEP_OF_SPREAD × the value's sd (the module's rule)."""


def _flat(value: Any) -> np.ndarray:
    return np.ravel(np.asarray(value, dtype=np.float64))


def _shaped(like: Any, numbers: np.ndarray) -> Any:
    out = [float(x) if math.isfinite(x) else None for x in numbers]
    return out if isinstance(like, list) else out[0]


def linearize(plan: Plan) -> dict[str, Any]:
    """{OUTPUT: {"derivative": {KEY: ...}, "accuracy": {KEY: ...}, "sd": ...}} at the draws'
    centres (the module's rule); ComputationError from a run that fails."""
    centres: dict[str, float] = {}
    spreads: dict[str, float | None] = {}
    for v in plan.varies:
        own = scene_value(plan, v)
        if v.spec.is_grid or own is None:
            continue
        c = v.spec.centre(own)
        if c is None:
            continue
        centres[v.key] = c
        spreads[v.key] = v.spec.spread(own)
    out: dict[str, Any] = {name: {"derivative": {}, "accuracy": {}, "sd": None}
                           for name in plan.outputs}
    variance: dict[str, np.ndarray] = {}
    like: dict[str, Any] = {}
    for key, c in centres.items():
        sd = spreads[key]
        if not sd:
            for name in plan.outputs:
                out[name]["derivative"][key] = out[name]["accuracy"][key] = None
            continue
        h = STEP_OF_SPREAD * sd
        runs = {dh: run_at(plan, {**centres, key: c + dh})
                for dh in (-h, h, -h / 2, h / 2)}
        for name in plan.outputs:
            f = {dh: _flat(r.outputs[name]) for dh, r in runs.items()}  # type: ignore[index]
            coarse = (f[h] - f[-h]) / (2 * h)
            fine = (f[h / 2] - f[-h / 2]) / h
            like[name] = runs[h].outputs[name]  # type: ignore[index]
            out[name]["derivative"][key] = _shaped(like[name], fine)
            out[name]["accuracy"][key] = _shaped(like[name], np.abs(fine - coarse))
            variance[name] = variance.get(name, 0.0) + (fine * sd) ** 2
    for name, var in variance.items():
        out[name]["sd"] = _shaped(like[name], np.sqrt(var))
    return out
