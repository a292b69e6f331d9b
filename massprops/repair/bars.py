"""Error bars of a repair: where it may have put volume in the wrong place, and what that does to
each mass property (first order, like ``uncertainty.input``)."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from massprops.mesh.facesums import gamma
from massprops.mesh.integral import ErrorBars, MassProperties, Uncertainty


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


@dataclass(frozen=True)
class RegionSums:
    """Σ_k W_k, Σ_k W_k r_k (3,) and Σ_k W_k g(r_k) (3, 3), g_ii = r_j² + r_k², g_ij = r_i r_j,
    with r_k >= |x - c| per axis over region k's box: all the bars need from regions about a
    centre c (they add: regions can be summed block by block, never all held at once)."""

    volume: float = 0.0
    first: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    second: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros((3, 3)))

    def __add__(self, other: RegionSums) -> RegionSums:
        return RegionSums(self.volume + other.volume, self.first + other.first,
                          self.second + other.second)


def region_sums(volume: np.ndarray, lo: np.ndarray, hi: np.ndarray, centre: np.ndarray
                ) -> RegionSums:
    """The `RegionSums` of regions (k,) in boxes lo, hi (k, 3) about ``centre`` (3,)."""
    if volume.size == 0:
        return RegionSums()
    return reach_sums(volume, np.maximum(np.abs(hi - centre), np.abs(centre - lo)).T)


def reach_sums(volume: np.ndarray, reach: np.ndarray) -> RegionSums:
    """The `RegionSums` of regions (k,) whose points lie within ``reach`` (3, k) of the centre
    on each axis."""
    rows = np.empty((9, volume.size))  # r_i, r_j² + r_k², r_i r_j: one matrix-vector product
    rows[:3] = reach
    sq = reach * reach
    for i in range(3):
        j, k = (i + 1) % 3, (i + 2) % 3
        np.add(sq[j], sq[k], out=rows[3 + i])
        np.multiply(reach[i], reach[j], out=rows[6 + i])
    t = np.dot(rows, volume) * (1 + gamma(volume.size + 4))  # k non-negative terms, any order
    g = np.diag(t[3:6])
    for i in range(3):
        j = (i + 1) % 3
        g[i, j] = g[j, i] = t[6 + i]
    return RegionSums(float(volume.sum()) * (1 + gamma(volume.size)), t[:3], g)


def moment_bounds(regions: Regions | RegionSums, props: MassProperties, *,
                  mass_given: bool) -> Uncertainty:
    """The bars ``regions`` put on ``props`` (integrated after the repair), first order.

    With s = x - c about the centre of mass and r_i >= |s_i| over a box: |Δ volume| <= W,
    |Δ c_i| <= Σ W r_i / V, |Δ J_ii| <= ρ Σ W (r_j² + r_k²), |Δ J_ij| <= ρ Σ W r_i r_j (the COM's
    own move is second order in J because ∫ s dV = 0). A given mass fixes m, and the density
    ρ = m / V moves instead: |ΔJ| gains |J| W / V. The sums carry their rounding margin
    (`region_sums`); 1e-12 more covers adding up to 10³ blocks and the products here.
    """
    if isinstance(regions, Regions):
        regions = region_sums(regions.volume, regions.lo, regions.hi, props.center_of_mass)
    margin = 1 + 1e-12
    total = regions.volume * margin
    volume, rho = props.volume, props.density
    inertia = rho * regions.second * margin
    if mass_given:
        inertia = inertia + np.abs(props.inertia) * total / volume
    moments = np.full(3, np.linalg.norm(inertia, 2))
    return Uncertainty(total, 0.0 if mass_given else rho * total,
                       _ro(regions.first * margin / volume), _ro(inertia), _ro(moments))


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
