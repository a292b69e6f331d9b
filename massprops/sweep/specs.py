"""How a value varies: ``normal:MEAN:SD``, ``uniform:LOW:HIGH``, ``lognormal:MEDIAN:FACTOR``,
``relative:P`` (the scene's own value times 1 + P·N(0, 1); ``5%`` is 0.05) and ``values:A,B,C``
(a grid). A spec draws from the generator it is given, so that sample i's values depend on the
seed and i only (`draws.sample_rng`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from massprops.errors import UsageError

KINDS = ("normal", "uniform", "lognormal", "relative", "values")


@dataclass(frozen=True)
class Spec:
    """A parsed SPEC: ``kind`` (one of KINDS) and its numbers (``values``: the grid)."""

    kind: str
    numbers: tuple[float, ...]
    text: str

    @property
    def is_grid(self) -> bool:
        return self.kind == "values"

    def draw(self, rng: np.random.Generator, nominal: float) -> float:
        """One value; ``nominal`` is the scene's own (used by ``relative``)."""
        a = self.numbers
        if self.kind == "normal":
            return float(a[0] + a[1] * rng.standard_normal())
        if self.kind == "uniform":
            return float(rng.uniform(a[0], a[1]))
        if self.kind == "lognormal":
            return float(a[0] * a[1] ** rng.standard_normal())
        if self.kind == "relative":
            return float(nominal * (1.0 + a[0] * rng.standard_normal()))
        raise ValueError("a grid is not drawn")  # the caller takes its values in turn

    def centre(self, nominal: float) -> float | None:
        """Where the draws centre (the mean; a lognormal's median), None for a grid."""
        a = self.numbers
        return {"normal": a[0], "uniform": 0.5 * (a[0] + a[-1]), "lognormal": a[0],
                "relative": nominal}.get(self.kind)

    def spread(self, nominal: float) -> float | None:
        """The draws' standard deviation (a lognormal's: of its log times its median, the
        first-order spread), None for a grid."""
        a = self.numbers
        return {"normal": a[-1], "uniform": (a[-1] - a[0]) / math.sqrt(12),
                "lognormal": a[0] * math.log(a[-1]),
                "relative": abs(nominal) * a[0]}.get(self.kind)

    @property
    def relative_sd(self) -> float:
        """P of ``relative:P`` (a fraction)."""
        return self.numbers[0]


def _number(text: str, spec: str) -> float:
    try:
        value = float(text[:-1]) / 100 if text.endswith("%") else float(text)
    except ValueError:
        raise UsageError(f"--vary spec {spec!r}: {text!r} is not a number") from None
    if not math.isfinite(value):
        raise UsageError(f"--vary spec {spec!r}: {text!r} is not finite")
    return value


def parse_spec(text: str) -> Spec:
    """The Spec written as ``text``; UsageError (exit 2) naming what is wrong."""
    kind, _, rest = text.partition(":")
    if kind not in KINDS or not rest:
        raise UsageError(f"--vary spec {text!r}: expected one of normal:MEAN:SD, uniform:LOW:"
                         "HIGH, lognormal:MEDIAN:FACTOR, relative:P, values:A,B,...")
    if kind == "values":
        numbers = tuple(_number(v.strip(), text) for v in rest.split(","))
        return Spec(kind, numbers, text)
    parts = rest.split(":")
    want = 1 if kind == "relative" else 2
    if len(parts) != want:
        raise UsageError(f"--vary spec {text!r}: {kind} takes {want} number"
                         f"{'s' if want > 1 else ''}")
    numbers = tuple(_number(p, text) for p in parts)
    problem = {"normal": numbers[-1] < 0 and "SD must be >= 0",
               "uniform": numbers[0] > numbers[-1] and "LOW must be <= HIGH",
               "lognormal": (numbers[0] <= 0 or numbers[-1] < 1)
               and "MEDIAN must be > 0 and FACTOR >= 1",
               "relative": numbers[0] < 0 and "P must be >= 0"}[kind]
    if problem:
        raise UsageError(f"--vary spec {text!r}: {problem}")
    return Spec(kind, numbers, text)
