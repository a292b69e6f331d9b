"""Whether an inertial (mass, centre of mass, inertia about it; link frame, SI) can belong to a
body made of the link's geometry. Four tests, each True, False, or None when it cannot be judged
(no geometry to judge against):

- ``positive_definite``: m > 0 and every principal moment > 0;
- ``triangle``: each principal moment at most the sum of the other two. Equivalently the
  second moment about the COM, Σ_c = ∫ r rᵀ dm = ½ tr(J) I − J, is positive semidefinite (its
  eigenvalues are ½ tr J − λ_i, i.e. (λ_j + λ_k − λ_i) / 2);
- ``com_inside``: the COM lies in the convex hull of the link's geometry (`bounds`);
- ``realizable``: Wensing, Kim & Slotine (2017), "Linear matrix inequalities for physically
  consistent inertial parameter identification": with Σ = ∫ x xᵀ dm about the frame origin
  (Σ = Σ_c + m c cᵀ) the pseudo-inertia P = [[Σ, m c], [m cᵀ, m]] = ∫ [x; 1][x; 1]ᵀ dm must be
  positive semidefinite, and for an ellipsoid E = {x : (x − e)ᵀ S⁻¹ (x − e) <= 1} around the
  geometry (`bounds`), with Q = [[−S⁻¹, S⁻¹e], [eᵀS⁻¹, 1 − eᵀS⁻¹e]] (so [x; 1]ᵀ Q [x; 1] >= 0
  exactly inside E), tr(P Q) = ∫ (1 − (x − e)ᵀ S⁻¹ (x − e)) dm >= 0. For the ellipsoid these two
  conditions are necessary and sufficient (their theorem): a non-negative density inside E with
  this mass, COM and inertia exists iff they hold. The geometry lies inside E, so for it they are
  necessary only: **False is exact** (no non-negative density inside the geometry has these
  values), True means "realizable inside the ellipsoid", not proven for the geometry itself.
  By the Schur complement P ⪰ 0 iff m > 0 and Σ_c ⪰ 0, the triangle test (same tolerance); the
  trace is evaluated in the ellipsoid's unit-ball coordinates as
  m (1 − |S^-½ (c − e)|²) − tr(S⁻¹ Σ_c), all terms of the order of m.

Tolerances (`tolerances.INERTIA_VALIDITY_RTOL` of the largest moment for the tensor tests and of
m for the trace, `tolerances.COM_INSIDE_RTOL` of the link's size for the hull) are round-off: a
valid tensor shifted and turned a few times stays valid (tested), while the defects found in
descriptions break a test by percent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from massprops.robot.doctor.bounds import Bounds
from massprops.tolerances import COM_INSIDE_RTOL, INERTIA_VALIDITY_RTOL

__all__ = ["TESTS", "Validity", "judge"]

TESTS = ("positive_definite", "triangle", "com_inside", "realizable")


@dataclass(frozen=True)
class Validity:
    """Each test True/False/None (see the module); ``problems``: one phrase per False test
    (and for an asymmetric or non-finite tensor)."""

    positive_definite: bool | None
    triangle: bool | None
    com_inside: bool | None
    realizable: bool | None
    problems: tuple[str, ...] = ()

    @property
    def ok(self) -> bool:
        """No test is False (None counts as not failed: nothing to judge against)."""
        return not self.problems

    def as_dict(self) -> dict:
        return {t: getattr(self, t) for t in TESTS}


def judge(mass: float, center_of_mass: np.ndarray, inertia: np.ndarray,
          bounds: Bounds | None) -> Validity:
    """The four tests of (mass kg, COM (3,) m, inertia (3, 3) kg·m² about the COM), link frame;
    ``bounds`` the link geometry's (None: com_inside and realizable are None)."""
    problems = []
    if not (math.isfinite(mass) and mass > 0):
        problems.append(f"mass {mass!r} is not positive")
    j = np.asarray(inertia, dtype=np.float64)
    c = np.asarray(center_of_mass, dtype=np.float64)
    if not np.isfinite(j).all() or not np.isfinite(c).all():
        return Validity(False, False, False if bounds else None, False if bounds else None,
                        (*problems, "inertia or centre of mass has non-finite entries"))
    scale = float(np.max(np.abs(j))) or 1.0
    if np.max(np.abs(j - j.T)) > INERTIA_VALIDITY_RTOL * scale:
        problems.append("inertia is not symmetric")
    j = 0.5 * (j + j.T)
    moments = np.linalg.eigvalsh(j)
    tol = INERTIA_VALIDITY_RTOL * max(float(np.max(np.abs(moments))), 0.0)
    positive = bool(moments[0] > tol) and mass > 0
    if moments[0] <= tol:
        problems.append(f"inertia is not positive definite (smallest principal moment "
                        f"{moments[0]:.6g} kg·m²)")
    triangle = bool(moments[2] <= moments[0] + moments[1] + tol)
    if not triangle:
        problems.append(f"principal moments {moments[0]:.6g}, {moments[1]:.6g}, "
                        f"{moments[2]:.6g} break the triangle inequality (the largest exceeds "
                        "the sum of the others)")
    if bounds is None:
        return Validity(positive, triangle, None, None, tuple(problems))
    out = bounds.outside(c)
    inside = out <= COM_INSIDE_RTOL * bounds.size
    if not inside:
        problems.append(f"centre of mass {out:.3g} m outside the convex hull of the geometry")
    realizable = triangle and mass > 0
    if realizable:
        chol = np.linalg.cholesky(bounds.shape)
        sigma_c = 0.5 * np.trace(j) * np.eye(3) - j
        unit = np.linalg.solve(chol, np.linalg.solve(chol, sigma_c).T)  # L⁻¹ Σ_c L⁻ᵀ
        delta = np.linalg.solve(chol, c - bounds.centre)
        trace = mass * (1.0 - float(delta @ delta)) - float(np.trace(unit))
        realizable = trace >= -INERTIA_VALIDITY_RTOL * mass
        if not realizable:
            problems.append(f"no non-negative density inside the geometry has this mass, "
                            f"centre of mass and inertia (Wensing's tr(PQ) = {trace:.3g} kg "
                            "< 0 for the ellipsoid around it)")
    elif mass > 0:
        problems.append("no density has this inertia (its pseudo-inertia is not positive "
                        "semidefinite)")
    return Validity(positive, triangle, bool(inside), bool(realizable), tuple(problems))
