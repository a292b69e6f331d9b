"""Error bars of a repair: where it may have put volume in the wrong place, and what that does to
each mass property (first order, like ``uncertainty.input``)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from massprops.mass import ErrorBars, MassProperties, Uncertainty


@dataclass(frozen=True, eq=False)
class Regions:
    """Volumes a repair may have misplaced: |Δ∫g dV| <= Σ_k volume_k · max over box_k of |g| for
    every integrand g, the repair's change of the solid being a signed set of measure at most
    volume_k inside box k.

    volume : (k,) m³, non-negative. lo, hi : (k, 3) m, corners of a box holding region k.
    """

    volume: np.ndarray
    lo: np.ndarray
    hi: np.ndarray

    @classmethod
    def none(cls) -> Regions:
        return cls(np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)))

    @classmethod
    def join(cls, *parts: Regions) -> Regions:
        return cls(np.concatenate([p.volume for p in parts]),
                   np.concatenate([p.lo for p in parts]), np.concatenate([p.hi for p in parts]))

    @property
    def total(self) -> float:
        """Σ volume_k, m³: the bound of the volume's change."""
        return float(self.volume.sum())


def moment_bounds(regions: Regions, props: MassProperties, *, mass_given: bool) -> Uncertainty:
    """The bars ``regions`` put on ``props`` (integrated after the repair), first order.

    With s = x - c about the centre of mass and r_i >= |s_i| over a box: |Δ volume| <= W,
    |Δ c_i| <= Σ W r_i / V, |Δ J_ii| <= ρ Σ W (r_j² + r_k²), |Δ J_ij| <= ρ Σ W r_i r_j (the COM's
    own move is second order in J because ∫ s dV = 0). A given mass fixes m, and the density
    ρ = m / V moves instead: |ΔJ| gains |J| W / V.
    """
    w = regions.volume
    c = props.center_of_mass
    reach = np.maximum(np.abs(regions.hi - c), np.abs(c - regions.lo))  # (k, 3)
    total = float(w.sum()) * (1 + 1e-12)  # the bound of a rounded sum of non-negative terms
    volume, rho = props.volume, props.density
    wr = w @ reach if w.size else np.zeros(3)
    sq = reach**2
    g = np.empty((3, 3))
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        g[i, i] = w @ (sq[:, j] + sq[:, k]) if w.size else 0.0
        g[i, j] = g[j, i] = w @ (reach[:, i] * reach[:, j]) if w.size else 0.0
    inertia = rho * g * (1 + 1e-12)
    if mass_given:
        inertia = inertia + np.abs(props.inertia) * total / volume
    moments = np.full(3, np.linalg.norm(inertia, 2))
    return Uncertainty(total, 0.0 if mass_given else rho * total, _ro(wr * (1 + 1e-12) / volume),
                       _ro(inertia), _ro(moments))


def plus(a: Uncertainty | None, b: Uncertainty | None) -> Uncertainty | None:
    """Component-wise sum of two bars (None is zero)."""
    if a is None or b is None:
        return a if b is None else b
    return Uncertainty(a.volume + b.volume, a.mass + b.mass,
                       _ro(a.center_of_mass + b.center_of_mass), _ro(a.inertia + b.inertia),
                       _ro(a.principal_moments + b.principal_moments))


def with_repair_bar(props: MassProperties, bar: Uncertainty | None) -> MassProperties:
    """``props`` with ``bar`` added to its ``uncertainty.repair``."""
    u = props.uncertainty
    return dataclasses.replace(props, uncertainty=ErrorBars(u.rounding, u.input,
                                                            plus(u.repair, bar)))


def _ro(a: np.ndarray) -> np.ndarray:
    out = np.array(a, dtype=np.float64)
    out.setflags(write=False)
    return out
