"""Causes of numbers written wrong: units, signs, a slipped decimal, a placeholder.

- ``length_unit``: the inertia in mm², cm² or in² (``factor`` L², what takes it to SI: 1e-06
  for mm) and/or the COM in that unit (``com_factor`` L); the stated numbers are the SI ones
  divided by the factor;
- ``mass_unit``: the mass in grams (``factor`` 1e-3). The stated mass is kept by default, so
  the computed tensor carries the 1000× mass and the stated one looks 1000× too small; with
  ``--density`` the mass itself is 1000× the geometry's;
- ``product_sign``: every product of inertia with the opposite sign (+∫xy dm, the convention
  of some CAD tools, against URDF's −∫xy dm);
- ``decimal_slip``: one of the six numbers off by a power of ten (``element``, ``factor`` =
  stated / right);
- ``placeholder``: an equal diagonal with no products where the shape's moments differ (the
  tensor is not a measurement of anything: no factor explains it).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["ELEMENTS", "UNITS", "decimal_slip", "is_placeholder", "product_sign"]

_LENGTHS = (("mm", 1e-3), ("cm", 1e-2), ("in", 0.0254))

ELEMENTS = ((0, 0, "ixx"), (1, 1, "iyy"), (2, 2, "izz"), (0, 1, "ixy"), (0, 2, "ixz"),
            (1, 2, "iyz"))


def _units():
    """(causes, inertia multiplier, mass multiplier, COM multiplier): stated ≈ multiplier × SI."""
    out = [((), 1.0, 1.0, 1.0)]
    for unit, f in _LENGTHS:
        out.append(((("length_unit", {"unit": unit, "factor": f * f, "com_factor": f},
                      f"in {unit}² (the COM in {unit})"),), 1 / (f * f), 1.0, 1 / f))
        out.append(((("length_unit", {"unit": unit, "factor": f * f, "com_factor": 1.0},
                      f"in {unit}²"),), 1 / (f * f), 1.0, 1.0))
        out.append(((("length_unit", {"unit": unit, "factor": 1.0, "com_factor": f},
                      f"the COM in {unit}"),), 1.0, 1.0, 1 / f))
    gram = ("mass_unit", {"unit": "g", "factor": 1e-3}, "the mass in g")
    out.append(((gram,), 1e-3, 1.0, 1.0))   # the stated (gram) mass kept: tensor looks small
    out.append(((gram,), 1.0, 1e3, 1.0))    # --density: the mass itself 1000×
    for unit, f in _LENGTHS:
        for com in (1.0, 1 / f):
            length = ("length_unit", {"unit": unit, "factor": f * f,
                                      "com_factor": 1.0 if com == 1.0 else f},
                      f"in {unit}²" + (f" (the COM in {unit})" if com != 1.0 else ""))
            out.append(((length, gram), 1e-3 / (f * f), 1.0, com))
    return tuple(out)


UNITS = _units()


def product_sign(inertia: np.ndarray):
    """[(cause, the tensor with its products negated)], [] when it has no products."""
    if np.max(np.abs(inertia - np.diag(np.diag(inertia)))) == 0:
        return []
    flipped = 2 * np.diag(np.diag(inertia)) - inertia
    return [(("product_sign", {}, "products of inertia with the opposite sign (+∫xy dm)"),
             flipped)]


def decimal_slip(target: np.ndarray, inertia: np.ndarray):
    """[(cause, the tensor with one element × 10^k)] for each element whose ratio to the
    target is a power of ten (k = ±1 ... ±6)."""
    out = []
    for i, j, name in ELEMENTS:
        if inertia[i, j] == 0 or target[i, j] == 0:
            continue
        ratio = target[i, j] / inertia[i, j]
        if ratio <= 0:
            continue
        k = round(math.log10(ratio))
        if k == 0 or abs(k) > 6 or abs(math.log10(ratio) - k) > 1e-3:
            continue
        slipped = inertia.copy()
        slipped[i, j] *= 10.0 ** k
        slipped[j, i] = slipped[i, j]
        out.append((("decimal_slip", {"element": name, "factor": 10.0 ** k},
                     f"{name} off by 10^{k} (a slipped decimal)"), slipped))
    return out


def is_placeholder(stated: np.ndarray, computed_moments: np.ndarray) -> bool:
    """An equal diagonal, no products, and a shape whose moments differ by more than 5 %."""
    d = np.diag(stated)
    if d[0] <= 0 or np.max(np.abs(d - d[0])) > 1e-9 * d[0]:
        return False
    if np.max(np.abs(stated - np.diag(d))) > 1e-9 * d[0]:
        return False
    lo, hi = float(computed_moments[0]), float(computed_moments[2])
    return hi > 0 and (hi - lo) > 0.05 * hi
