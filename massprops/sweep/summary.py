"""What a sweep's rows say together: each output's spread and its sensitivity to each value.

Per output component, over the samples that ran: mean, standard deviation (n − 1), the 5, 50
and 95 % quantiles (numpy's linear rule), and their own Monte Carlo uncertainty: sd/√n for the
mean; for a quantile p, half the distance between the order statistics at ranks
n p ∓ √(n p (1 − p)) (its distribution-free 68 % interval, no density assumed). Sensitivity: the
least-squares slope of each output component on each scalar varied value (all values at once,
with an intercept): d output / d value, in the output's unit per the value's; null where the
samples cannot tell (fewer samples than values + 2, or a value that did not vary). A tensor
(``inertia``) draw has no single value and gets no slope.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from massprops.sweep.sample import Row

QUANTILES = (0.05, 0.50, 0.95)


def _column(values: list[Any]) -> np.ndarray | None:
    """(n, k) float array of an output's values over the rows, or None if any is missing."""
    try:
        return np.array([np.ravel(np.asarray(v, dtype=np.float64)) for v in values])
    except (TypeError, ValueError):
        return None


def _shape(value: Any, numbers: np.ndarray) -> Any:
    """``numbers`` (k,) as the output was written: a scalar or a list."""
    out = [None if not math.isfinite(x) else float(x) for x in numbers]
    return out if isinstance(value, list) else out[0]


def _quantile_uncertainty(y: np.ndarray, p: float) -> np.ndarray:
    n = len(y)
    s = np.sort(y, axis=0)
    half = math.sqrt(n * p * (1 - p))
    lo = min(max(int(math.floor(n * p - half)), 0), n - 1)
    hi = min(max(int(math.ceil(n * p + half)) - 1, 0), n - 1)
    return 0.5 * (s[hi] - s[lo])


def statistics(y: np.ndarray, like: Any) -> dict[str, Any]:
    """The module's statistics of ``y`` (n, k), each written as ``like`` is."""
    n = len(y)
    sd = np.std(y, axis=0, ddof=1) if n > 1 else np.full(y.shape[1], math.nan)
    q = np.quantile(y, QUANTILES, axis=0)
    out = {"mean": _shape(like, y.mean(axis=0)), "sd": _shape(like, sd)}
    for p, row in zip(QUANTILES, q):
        out[f"p{round(100 * p):02d}"] = _shape(like, row)
    out["mean_uncertainty"] = _shape(like, sd / math.sqrt(n))
    out["quantile_uncertainty"] = [_shape(like, _quantile_uncertainty(y, p)) for p in QUANTILES]
    return out


def sensitivities(x: np.ndarray, y: np.ndarray, names: Sequence[str], like: Any
                  ) -> dict[str, Any]:
    """Slopes of ``y`` (n, k) on ``x`` (n, m), by value name; None where not determined."""
    n, m = x.shape
    spread = np.std(x, axis=0)
    used = [i for i in range(m) if spread[i] > 0]
    out: dict[str, Any] = {name: None for name in names}
    if not used or n < len(used) + 2:
        return out
    design = np.column_stack([np.ones(n), x[:, used] - x[:, used].mean(axis=0)])
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    for row, i in zip(coef[1:], used):
        out[names[i]] = _shape(like, row)
    return out


def summarize(rows: Sequence[Row], outputs: Sequence[str], keys: Sequence[str]) -> dict[str, Any]:
    """The contract's summary object of ``rows`` (failed ones counted, not used)."""
    ran = [r for r in rows if r.status == "ok" and r.outputs is not None]
    summary: dict[str, Any] = {}
    sensitivity: dict[str, Any] = {}
    scalar = [k for k in keys if ran and isinstance(ran[0].values.get(k), (int, float))]
    x = np.array([[r.values[k] for k in scalar] for r in ran], dtype=np.float64) \
        if ran else np.zeros((0, 0))
    for name in outputs:
        values = [r.outputs[name] for r in ran]  # type: ignore[index]
        y = _column(values) if values else None
        if y is None or not len(y) or not np.isfinite(y).all():
            summary[name] = None
            sensitivity[name] = {k: None for k in scalar}
            continue
        summary[name] = statistics(y, values[0])
        sensitivity[name] = sensitivities(x.reshape(len(ran), len(scalar)), y, scalar,
                                          values[0])
    return {"summary": summary, "sensitivity": sensitivity, "samples": len(rows),
            "failed": len(rows) - len(ran), "redrawn": sum(r.redrawn for r in rows)}
