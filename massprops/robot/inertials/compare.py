"""Stated against computed: how far a description's inertial is from the geometry's, and whether
the stated tensor is one a body can have.

What "differs by more than RTOL" means (``Comparison.worst``, what ``model --check`` tests):
- mass: |m_stated - m_computed| / m_computed;
- centre of mass: |c_stated - c_computed| / size, size the diagonal of the box around the
  link's geometry (a COM 1 cm off on a 1 m link is 1 %);
- inertia: ||J_stated - J_computed||₂ / ||J_computed||₂, the spectral norm (the largest change
  of the moment about any axis, relative to the largest principal moment): it sees wrong moments
  and wrongly turned axes alike, and stays defined where principal axes are not (a cylinder).
The angle between the principal frames is reported but not tested: it is meaningless where
moments (nearly) coincide. A stated inertial that is not physically valid (`doctor.validity`:
not positive definite, a moment larger than the sum of the other two, its COM outside the
geometry's hull, or no non-negative density inside the geometry can have it) fails the check
whatever RTOL.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from massprops.inertia import principal_axes
from massprops.robot.doctor.validity import Validity, judge
from massprops.robot.inertials.combine import LinkMass
from massprops.robot.model import StatedInertial
from massprops.tolerances import DEGENERATE_MOMENT_RTOL

__all__ = ["Comparison", "compare", "relative_difference", "validity_problems"]


@dataclass(frozen=True)
class Comparison:
    """mass_rel, com_offset (m), com_rel (of size), inertia_rel: as the module says.
    axes_angle : rad, the largest angle between matching principal axes whose computed moment
    stands apart from the others, or None when all three coincide (a sphere, a cube).
    problems : why the stated inertial is not physically valid ([] if it is).
    valid : the stated inertial's `doctor.validity` tests against the link's geometry."""

    mass_rel: float
    com_offset: float
    com_rel: float
    inertia_rel: float
    axes_angle: float | None
    problems: tuple[str, ...]
    valid: Validity | None = None

    @property
    def worst(self) -> float:
        return max(self.mass_rel, self.com_rel, self.inertia_rel)

    def passes(self, rtol: float) -> bool:
        return not self.problems and self.worst <= rtol

    def as_dict(self) -> dict:
        return {"mass_rel": self.mass_rel, "com_offset": self.com_offset,
                "com_rel": self.com_rel, "inertia_rel": self.inertia_rel,
                "axes_angle": self.axes_angle, "valid": not self.problems,
                "problems": list(self.problems)}


def validity_problems(mass: float, inertia: np.ndarray) -> tuple[str, ...]:
    """Why (mass, inertia about the COM) cannot belong to any body; () when it can (the tensor
    tests of `doctor.validity.judge`, without geometry)."""
    return judge(mass, np.zeros(3), inertia, None).problems


def relative_difference(mass_a: float, com_a: np.ndarray, inertia_a: np.ndarray, mass_b: float,
                        com_b: np.ndarray, inertia_b: np.ndarray, size: float) -> float:
    """max(mass, COM / size, inertia) relative difference of inertial a from inertial b (kg, m,
    kg·m² about each COM, one frame), as the module measures them: ``Comparison.worst``."""
    return max(abs(mass_a - mass_b) / abs(mass_b),
               float(np.linalg.norm(np.asarray(com_a) - com_b)) / size,
               float(np.linalg.norm(inertia_a - inertia_b, 2))
               / float(np.linalg.norm(inertia_b, 2)))


def compare(stated: StatedInertial, computed: LinkMass) -> Comparison:
    """Stated against computed, both about their own centres of mass in the link's axes."""
    valid = judge(stated.mass, stated.center_of_mass, stated.inertia, computed.bounds)
    offset = float(np.linalg.norm(stated.center_of_mass - computed.center_of_mass))
    norm = float(np.linalg.norm(computed.inertia, 2))
    return Comparison(
        mass_rel=abs(stated.mass - computed.mass) / computed.mass,
        com_offset=offset,
        com_rel=offset / computed.size,
        inertia_rel=float(np.linalg.norm(stated.inertia - computed.inertia, 2)) / norm,
        axes_angle=_axes_angle(stated.inertia, computed),
        problems=valid.problems,
        valid=valid,
    )


def _axes_angle(stated_inertia: np.ndarray, computed: LinkMass) -> float | None:
    moments = computed.principal_moments
    gap = DEGENERATE_MOMENT_RTOL * float(np.max(np.abs(moments)))
    j = np.asarray(stated_inertia, dtype=np.float64)
    if not np.isfinite(j).all():
        return None
    _, stated_axes = principal_axes(j)
    angles = []
    for i in range(3):
        others = np.delete(moments, i)
        if np.all(np.abs(others - moments[i]) > gap):
            a, b = computed.principal_axes[:, i], stated_axes[:, i]
            # atan2 of |a×b| and |a·b|: accurate for tiny angles, sign-blind (axes are lines)
            angles.append(math.atan2(float(np.linalg.norm(np.cross(a, b))), abs(float(a @ b))))
    return max(angles) if angles else None
