"""Why a stated inertial differs from the computed one: the search over the named causes.

A model of the stated inertial is: a *base* (the computed inertial, or one of the `shapes`
alternatives), then a unit reading (`writing.UNITS`: none, length, mass, or both), then one
change of the tensor: none, ``about_point``, ``rotated`` / ``axes_permuted``
(`frames`), ``product_sign`` or ``decimal_slip`` (`writing`), each solved from the numbers, or
two composed (`_composed`: two decimal slips; a turn about the link origin or the stated COM),
each still leaving numbers to check it.
Its residual is the relative difference left, measured as ``--check`` measures
(`compare.relative_difference`: mass, COM / size, inertia in the 2-norm). A cause is named only
when its model leaves at most `tolerances.DIAGNOSIS_RTOL`; among those the fewest causes win,
then the smallest residual. A placeholder (`writing.is_placeholder`) is said when nothing else
fits; otherwise the causes are empty and the detail says what came nearest.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import cast

import numpy as np

from massprops.inertia import parallel_axis
from massprops.robot.doctor.frames import about_point, rotation
from massprops.robot.doctor.writing import UNITS, decimal_slip, is_placeholder, product_sign
from massprops.tolerances import DIAGNOSIS_RTOL

__all__ = ["Diagnosis", "diagnose"]


@dataclass(frozen=True)
class Diagnosis:
    """causes : ((name, parameters, phrase), ...), the contract's names; residual : the
    relative difference the causes leave; detail : one line saying it."""

    causes: tuple[tuple[str, dict, str], ...]
    residual: float
    detail: str

    def as_dict(self) -> dict:
        return {"causes": [{"cause": c, "parameters": p} for c, p, _ in self.causes],
                "residual": self.residual, "detail": self.detail}


Base = tuple[tuple, float, np.ndarray, np.ndarray]
"""(causes that made it, mass kg, COM (3,) m, inertia (3, 3) kg·m² about it), link frame."""


def diagnose(stated, computed, shapes: Callable[[], Sequence[Base]] | None = None,
             difference: Callable | None = None) -> Diagnosis:
    """The causes that explain ``stated`` (`model.StatedInertial`) against ``computed``
    (`combine.LinkMass`); ``shapes`` gives the other shapes' inertials when the computed one
    explains nothing (called at most once); ``difference`` is `compare.relative_difference`."""
    size = computed.size
    bases: list[Base] = [((), computed.mass, computed.center_of_mass, computed.inertia)]
    # the callers always pass difference
    direct = cast(Callable, difference)(stated.mass, stated.center_of_mass, stated.inertia,
                                        computed.mass, computed.center_of_mass, computed.inertia,
                                        size)
    if direct <= DIAGNOSIS_RTOL:
        return Diagnosis((), direct, f"differs by {direct:.3g}: within the doctor's allowance "
                         f"({DIAGNOSIS_RTOL:g}, the rounding of printed numbers); no cause named")
    best = _search(stated, bases, size, difference)
    if best[1] > DIAGNOSIS_RTOL and shapes is not None:
        more = list(shapes())
        if more:
            best = min(best, _search(stated, more, size, difference), key=lambda b: b[0])
    _key, residual, causes = best
    if residual <= DIAGNOSIS_RTOL:
        return Diagnosis(causes, residual, _say(causes))
    if is_placeholder(stated.inertia, computed.principal_moments):
        a = float(stated.inertia[0, 0])
        moments = ", ".join(f"{x:.3g}" for x in computed.principal_moments)
        cause = ("placeholder", {"value": a},
                 f"placeholder diag({a:g}, {a:g}, {a:g}), not the shape's ({moments})")
        return Diagnosis((cause,), direct, cause[2])
    near = f"; nearest: {_say(causes)}, leaving {residual:.3g}" if causes else ""
    return Diagnosis((), direct, f"unexplained: no named cause brings the difference "
                     f"({direct:.3g}) within {DIAGNOSIS_RTOL:g}{near}")


def _key(r: float, causes: tuple) -> tuple:
    """Models that fit first, the fewest causes first among them; then the smallest residual."""
    fits = r <= DIAGNOSIS_RTOL
    return (not fits, len(causes) if fits else 0, r)


def _search(stated, bases: Sequence[Base], size: float, difference) -> tuple:
    """(key, residual, causes) of the best model over ``bases``."""
    best = ((True, 0, float("inf")), float("inf"), ())
    s_com = np.asarray(stated.center_of_mass, dtype=np.float64)
    for base_causes, m, com, j in bases:
        for unit_causes, jm, mm, cm in UNITS:
            target = stated.inertia / jm
            models: list[tuple[tuple, np.ndarray, list[np.ndarray]]] = [((), j, [com])]
            models += [((c,), jj, coms) for c, jj, coms in
                       about_point(target, j, m, com, s_com / cm)]
            models += [((c,), jj, coms) for c, jj, coms in rotation(target, j, com,
                                                                      DIAGNOSIS_RTOL)]
            models += [((c,), jj, [com]) for c, jj in product_sign(j)]
            slips = decimal_slip(target, j)
            models += [((c,), jj, [com]) for c, jj in slips]
            models += _composed(target, j, m, com, s_com / cm, slips)
            for causes, jj, coms in models:
                every = (*base_causes, *unit_causes, *causes)
                if not every:
                    continue
                for c in coms:
                    r = difference(stated.mass, s_com, stated.inertia, mm * m, cm * c, jm * jj,
                                   cm * size)
                    key = _key(r, every)
                    if key < best[0]:
                        best = (key, r, every)
    return best


def _composed(target: np.ndarray, j: np.ndarray, m: float, com: np.ndarray,
              stated_com: np.ndarray, slips: list) -> list:
    """Two changes at once, each still solved from the numbers with data left to check it:

    - two decimal slips (each element's power of ten read from its own ratio; the other four
      elements must match);
    - a turn of the tensor about a *fixed* point: about the link origin, or about the stated COM
      where that differs from the computed one (the inertial frame's origin): R (J + m S(p − c))
      Rᵀ, R solved as ``rotated`` is (3 parameters, the 3 principal moments must match). The
      point is not solved for: a free point and a free turn are 6 parameters for 6 numbers and
      would fit nearly any tensor, naming causes the numbers cannot bear out."""
    out: list = []
    for a in range(len(slips)):
        for b in range(a + 1, len(slips)):
            (ca, ja), (cb, jb) = slips[a], slips[b]
            out.append(((ca, cb), ja + jb - j, [com]))
    points = [np.zeros(3)]
    if np.linalg.norm(stated_com - com) > 1e-9 * max(float(np.linalg.norm(com)), 1e-300):
        points.append(np.asarray(stated_com, dtype=np.float64))
    for p in points:
        d = p - com
        if not np.linalg.norm(d) > 0:
            continue
        where = ("the link origin" if not np.any(p) else "the inertial frame's origin")
        shift = ("about_point", {"point": p.tolist()},
                 f"inertia about {where} ({np.linalg.norm(d):.3g} m from the COM)")
        for c, jj, coms in rotation(target, parallel_axis(j, m, d), com, DIAGNOSIS_RTOL):
            out.append(((shift, c), jj, [*coms, p]))
    return out


def _say(causes) -> str:
    return ", ".join(phrase for _c, _p, phrase in causes)
