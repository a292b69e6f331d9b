"""Mass properties of a closed triangle mesh: the exact integral, its error bars, principal axes.

Method. The solid is the signed sum of the tetrahedra (o, a, b, c) over the triangles (a, b, c)
about a local origin o; with primes meaning "minus o", d = det(a', b', c') and s = a' + b' + c':
  ∫1 = d/6,  ∫x_i = d s_i/24,  ∫x_i x_j = d (a'_i a'_j + b'_i b'_j + c'_i c'_j + s_i s_j)/120.
The totals about o are moved to the centre of mass by the parallel-axis theorem, so coordinates
far from the world origin cost nothing (the usual integral about (0, 0, 0) loses
(distance / size)² × 1e-16). The pass over the faces lives in ``massprops.mesh.facesums``: blocks
of faces, each total a numpy pairwise sum per block and math.fsum over the blocks.

The origin is the centre of a vertex sample's bounding box, or the estimated COM when Σ|d| shows
that the first choice sees much of the surface from outside (``_integrate``). Fast path:
d = a'·((b - a) × (c - a)), the edges taken from the stored vertices, with an error bound from
absolute products it already has. When that bound is not below ``_FAST_DET_TARGET`` of the
volume (tilted plates and needles: a', b', c' are nearly coplanar and float64 cannot resolve d)
the pass is redone with d in double-double, v - o carried exactly as a rounded value plus its
error: correct to ~1e-16 of each d.

Error bars. ``rounding`` bounds this computation's floating-point error against the exact values
of the stored vertices (first order, with margins; see ``det_error`` and ``_moments``).
``input`` is the first-order effect of float32 coordinates (binary STL) known to half an ulp, and
of vertices the health checks moved to close round-off cracks (``Mesh.vertex_displacement``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from massprops.errors import (
    DegenerateMeshError,
    MeshFormatError,
    NoVolumeError,
    UsageError,
    setting_ref,
)
from massprops.inertia import parallel_axis_to_com, principal_axes
from massprops.mesh.facesums import FaceSums, U, det_error, face_sums, gamma, reach_of, sum_depth
from massprops.mesh.value import Mesh
from massprops.tolerances import MIN_VOLUME_TO_ERROR

__all__ = ["ErrorBars", "MassProperties", "Uncertainty", "UnitMoments",
           "check_coordinate_scale", "coordinate_limit", "mass_properties",
           "properties_from_moments"]

_FAST_DET_TARGET = 1e-14
"""Fast determinants are kept when their error bound is below this fraction of |Σ d|."""

_TERM_BOUND = 2000.0
"""The largest term of the integral for coordinates |x| <= X, in units of X⁵: a face's second
moment d q (``facesums``) is at most 36√3 R⁵ ≈ 62.4 R⁵ for a reach |v_i - o_i| <= R, since
|d| <= (√3 R)³ and |q_ij| <= 3R² + (3R)² = 12 R²; the origin o lies in the bounding box, so
R <= 2X and d q <= 62.4 · 2⁵ X⁵ ≈ 1995 X⁵. Every partial sum over m faces is then at most
2000 m X⁵, and the volume (X³), the first moments (X⁴), the parallel-axis terms and the error
bars stay below it."""

_RECENTRE_RATIO = 8.0
"""When Σ|d| exceeds this multiple of |Σd| about the box centre, the pass is repeated about the
estimated centre of mass (for a convex body that makes every d >= 0, so nothing cancels)."""


@dataclass(frozen=True, eq=False)
class Uncertainty:
    """Absolute error bounds, in the units and shapes of the quantities they bound.

    volume : m³. mass : kg. center_of_mass : (3,) m. inertia : (3, 3) kg·m², per component.
    principal_moments : (3,) kg·m².
    """

    volume: float
    mass: float
    center_of_mass: np.ndarray
    inertia: np.ndarray
    principal_moments: np.ndarray

    def as_dict(self) -> dict:
        return {"volume": float(self.volume), "mass": float(self.mass),
                "center_of_mass": _floats(self.center_of_mass), "inertia": _floats(self.inertia),
                "principal_moments": _floats(self.principal_moments)}


@dataclass(frozen=True, eq=False)
class ErrorBars:
    """rounding : bounds of this computation's floating-point error against the exact values of
    the stored vertices. input : None unless the file stored float32 coordinates or vertices were
    welded across round-off cracks; then bounds of the change caused by every coordinate moving
    by half a float32 ulp (times the unit factor) plus the welding's largest move.
    repair : None unless a repair (``massprops.repair``) changed what was integrated; then bounds
    of what the repair leaves uncertain (a boolean's rounding, the choice of a hole's cap, the
    thin-wall model), reported under ``"repair"`` only then."""

    rounding: Uncertainty
    input: Uncertainty | None = None
    repair: Uncertainty | None = None

    def as_dict(self) -> dict:
        out = {"rounding": self.rounding.as_dict(),
               "input": None if self.input is None else self.input.as_dict()}
        if self.repair is not None:
            out["repair"] = self.repair.as_dict()
        return out


@dataclass(frozen=True, eq=False)
class MassProperties:
    """Mass properties of a solid of uniform density.

    volume : m³. mass : kg. density : kg/m³.
    center_of_mass : (3,) float64, m, in the mesh frame.
    inertia : (3, 3) float64, kg·m², about the centre of mass, in the mesh's axes
        (J_xx = ∫(y² + z²) dm, J_xy = -∫ x y dm).
    principal_moments : (3,) float64, kg·m², ascending.
    principal_axes : (3, 3) float64, proper rotation R whose columns are the principal axes in
        the mesh's axes: inertia = R diag(principal_moments) Rᵀ.
    uncertainty : its ``rounding`` and ``input`` error bars (see ErrorBars).
    """

    volume: float
    mass: float
    density: float
    center_of_mass: np.ndarray
    inertia: np.ndarray
    principal_moments: np.ndarray
    principal_axes: np.ndarray
    uncertainty: ErrorBars

    def as_dict(self) -> dict:
        """The contract's JSON keys (python floats, matrices as lists of rows) + "uncertainty"."""
        return {"volume": float(self.volume), "mass": float(self.mass),
                "density": float(self.density), "center_of_mass": _floats(self.center_of_mass),
                "inertia": _floats(self.inertia),
                "principal_moments": _floats(self.principal_moments),
                "principal_axes": _floats(self.principal_axes),
                "uncertainty": self.uncertainty.as_dict()}


def mass_properties(mesh: Mesh, *, density: float | None = None,
                    mass: float | None = None) -> MassProperties:
    """Volume, mass, centre of mass, inertia about it and principal axes of a closed mesh.

    mesh : closed, outward-wound (the health checks flip inside-out meshes before this).
    density : kg/m³, default 1.0. mass : kg; if given, density = mass / volume. Not both.
    Raises UsageError (both given, or not positive and finite), MeshFormatError (non-finite
    coordinates, bad indices), DegenerateMeshError (no resolvable volume, or inside out),
    MeshFormatError also for coordinates too large for float64 (`check_coordinate_scale`) and
    a density or mass that takes the results beyond it.
    """
    check_density_mass(density, mass)
    _check_faces(mesh)
    check_coordinate_scale(mesh)
    area = mesh.coordinate_dtype == np.float32 or mesh.vertex_displacement > 0
    origin, sums = _integrate(mesh, area)
    mo = _moments(sums, reach_of(sums), mesh.name)

    props = properties_from_moments(origin, mo, density=density, mass=mass, name=mesh.name)
    if not area:
        return props
    data_err = _input_uncertainty(mesh, origin + sums.lowest, origin + sums.highest, sums.area,
                                  mo.volume, props.center_of_mass, props.density, props.inertia,
                                  mass is not None)
    return dataclasses.replace(props, uncertainty=ErrorBars(props.uncertainty.rounding, data_err))


def properties_from_moments(origin: np.ndarray, mo: UnitMoments, *, density: float | None,
                            mass: float | None, name: str = "") -> MassProperties:
    """Mass properties from unit-density moments about ``origin`` (3,) m, with the rounding bars
    (``uncertainty.input`` None). Shared with solids that are not a closed mesh's interior (the
    thin wall of ``massprops.repair.shell``); ``density``/``mass`` as in `mass_properties`,
    already checked. MeshFormatError naming ``name`` when the density or mass takes the mass or
    the inertia beyond float64's range."""
    rho, rho_rel = (1.0 if density is None else float(density)), 0.0   # rho_rel: its error
    with np.errstate(over="ignore", invalid="ignore"):  # overflow is checked just below
        if mass is not None:
            rho, rho_rel = float(mass) / mo.volume, mo.volume_err / mo.volume + U
        inertia = rho * mo.inertia
        inertia_err = rho * mo.inertia_err + (rho_rel + 2 * U) * np.abs(inertia)
        total = float(mass) if mass is not None else rho * mo.volume
        total_err = 0.0 if mass is not None else rho * mo.volume_err + U * total
    if not (np.isfinite(inertia_err).all() and math.isfinite(total_err) and math.isfinite(rho)):
        raise MeshFormatError(
            f"{name}: mass properties beyond float64's range (1.8e308): {mo.volume:.3g} m³ at "
            f"{rho:.3g} kg/m³ gives an inertia of ~{_times(rho, np.abs(mo.inertia).max())} "
            "kg·m²; give a smaller density or mass, or rescale the mesh")
    moments, axes = principal_axes(inertia)
    # Weyl: an eigenvalue moves by at most ||ΔJ||_2 <= ||bound||_2 (the 2-norm is monotone on
    # non-negative matrices); LAPACK's backward error on a 3x3 symmetric problem is a few
    # u ||J||_2, 32 u leaves margin.
    moments_err = np.full(3, np.linalg.norm(inertia_err, 2) + 32 * U * np.abs(moments).max())
    com = origin + mo.com_local
    # o + c is rounded to nearest: half the spacing at the result, the unavoidable half-ulp
    com_err = mo.com_local_err + np.spacing(np.abs(com)) / 2
    rounding = Uncertainty(float(mo.volume_err), float(total_err), _frozen(com_err),
                           _frozen(inertia_err), _frozen(moments_err))
    return MassProperties(float(mo.volume), float(total), float(rho), _frozen(com),
                          _frozen(inertia), _frozen(moments), _frozen(axes), ErrorBars(rounding))


def _times(a: float, b: float) -> str:
    """a × b in words, also beyond float64 (``1e+300 * 1e+200`` -> ``1e+500``)."""
    if a == 0 or b == 0 or not (math.isfinite(a) and math.isfinite(b)):
        return f"{a * b:.3g}"
    exponent = math.log10(abs(a)) + math.log10(abs(b))
    whole = math.floor(exponent)
    return f"{10 ** (exponent - whole):.3g}e+{whole}"


def _integrate(mesh: Mesh, area: bool) -> tuple[np.ndarray, FaceSums]:
    """(origin (3,), face totals about it): about the centre of a sample's bounding box by the
    fast path; about the estimated COM when that origin sees much of the surface from outside (a
    tilted thin plate whose box centre is off its mid-plane: the tetrahedra cancel); in
    double-double when the fast determinants' bound misses ``_FAST_DET_TARGET``."""
    origin = _origin_estimate(mesh.vertices)
    sums = face_sums(mesh, origin, accurate=False, area=area)
    if 0 < _RECENTRE_RATIO * abs(sums.det) < sums.abs_det:
        centre = origin + sums.first / (4 * sums.det)
        if np.isfinite(centre).all():
            again = face_sums(mesh, centre, accurate=False, area=area)
            if again.abs_det * abs(sums.det) < sums.abs_det * abs(again.det):
                origin, sums = centre, again
    if det_error(sums, reach_of(sums)) > _FAST_DET_TARGET * abs(sums.det):
        sums = face_sums(mesh, origin, accurate=True, area=area)
    return origin, sums


# --- input checks --------------------------------------------------------------------------
def check_density_mass(density: float | None, mass: float | None) -> None:
    if density is not None and mass is not None:
        raise UsageError("give a density or a mass, not both (the other follows from the volume)")
    for name, value in (("density", density), ("mass", mass)):
        if value is not None and not (math.isfinite(value) and value > 0):
            raise UsageError(f"{name} must be a positive finite number, got {value!r}")


def coordinate_limit(faces: int) -> float:
    """The largest |coordinate| (m) whose mass properties float64 holds for a mesh of ``faces``
    triangles: the inertia integrates coordinates to the fifth power, so 2000 m X⁵ (see
    ``_TERM_BOUND``) must stay below float64's largest number, 1.8e308: X <= (1.8e308 / (2000
    m))^(1/5), 6e60 m for a cube's 12 triangles, 1.6e59 m for 10⁹."""
    return float((np.finfo(np.float64).max / (_TERM_BOUND * max(int(faces), 1))) ** 0.2)


def check_coordinate_scale(mesh: Mesh) -> None:
    """MeshFormatError (exit 1) naming the file, its largest coordinate and the limit when the
    coordinates are too large for float64 mass properties (`coordinate_limit`): checked before
    any product is formed, so no overflow (nor numpy's warning of it) happens downstream."""
    v = mesh.vertices
    if v.size == 0:
        return
    with np.errstate(invalid="ignore"):
        largest = max(float(v.max()), -float(v.min()))
    limit = coordinate_limit(mesh.faces.shape[0])
    if not largest > limit:  # NaN passes: the readers and the integral name it as such
        return
    i = int(np.argmax(np.abs(v).max(axis=1)))
    unit = "" if mesh.coordinate_scale == 1.0 else " (after the unit conversion)"
    raise MeshFormatError(
        f"{mesh.name}: coordinates too large for float64 mass properties: vertex {i + 1} has "
        f"|x| = {largest:.3g} m{unit}, but the inertia integrates coordinates to the fifth "
        f"power, finite only for |x| below {limit:.2g} m ({mesh.faces.shape[0]} triangles); "
        f"rescale the mesh or give the unit its coordinates are in ({setting_ref('unit')})")


def _check_faces(mesh: Mesh) -> None:
    v, f = mesh.vertices, mesh.faces
    if f.shape[0] == 0 or v.shape[0] == 0:
        raise NoVolumeError(f"{mesh.name}: encloses no volume (flat?): expected a closed "
                            "surface, got no triangles; check that the file holds a solid")
    if f.min() < 0 or f.max() >= v.shape[0]:
        raise MeshFormatError(f"{mesh.name}: face indices must lie in 0..{v.shape[0] - 1}, got "
                              f"{f.min()}..{f.max()}; the faces refer to missing vertices")


def _origin_estimate(vertices: np.ndarray) -> np.ndarray:
    """(3,) the centre of the bounding box of <= ~4096 evenly spread vertices. Any origin near
    the body serves (the pass measures its own reach); a full box would cost a pass over n."""
    sample = vertices[::max(1, vertices.shape[0] // 4096)]
    with np.errstate(invalid="ignore", over="ignore"):
        return (sample.min(axis=0) + sample.max(axis=0)) / 2


# --- from the sums to the moments about the centre of mass, with rounding bounds ------------------
class UnitMoments(NamedTuple):
    """Unit density: volume m³, com_local (3,) m from the origin, inertia (3, 3) m⁵ about the
    COM, each with its absolute rounding bound."""

    volume: float
    volume_err: float
    com_local: np.ndarray
    com_local_err: np.ndarray
    inertia: np.ndarray
    inertia_err: np.ndarray


def _moments(sums: FaceSums, reach: np.ndarray, name: str) -> UnitMoments:
    """Volume, COM and inertia about the COM from the face totals, with error bounds.

    Each summand is d times a factor bounded through the reach h: |s_i| <= 3 h_i, |f_i| <= 6 h_i²,
    |q_ij| <= 12 h_i h_j. So each total is off by at most that bound times
    omega = (determinant error) + γ_{depth+16} Σ|d|, where the 16 covers the factor's own
    roundings (primes, sums, products) and the product with d. The rest is first-order
    propagation through the divisions and the parallel-axis shift, each step adding its rounding.
    """
    det_err = det_error(sums, reach)
    depth = sum_depth(sums.count)
    omega = det_err + gamma(depth + 16) * sums.abs_det
    volume = sums.det / 6
    volume_err = (det_err + gamma(depth + 1) * sums.abs_det) / 6 + U * abs(volume)
    _check_volume(volume, volume_err, name)
    eps = omega / abs(sums.det)                          # < 0.2 after the check above
    com = sums.first / (4 * sums.det)
    com_err = (0.75 * reach + np.abs(com)) * eps / (1 - eps) + 2 * U * np.abs(com)

    m2 = sums.diag / 60                                  # ∫ x_i² about o
    m2_err = 0.1 * reach**2 * omega + U * np.abs(m2)
    m2x = sums.off / 120                                 # ∫ xy, ∫ yz, ∫ zx about o
    m2x_err = 0.1 * np.roll(reach, -1) * reach * omega + U * np.abs(m2x)
    j_o = _tensor(m2, -m2x)
    j_o_err = _tensor(m2_err, m2x_err) + np.diag(U * np.abs(np.diag(j_o)))
    inertia = parallel_axis_to_com(j_o, volume, com)

    # the shift V (|c|² I - c cᵀ), diagonal V (c_j² + c_k²): first-order error of each product
    ac = np.abs(com)
    shift = volume * np.outer(ac, ac)
    shift_err = (volume_err / volume + 3 * U) * shift + volume * (
        np.outer(ac, com_err) + np.outer(com_err, ac) + np.outer(com_err, com_err))
    sq, sq_err = com**2, 2 * ac * com_err + com_err**2
    other = np.roll(sq, 1) + np.roll(sq, 2)
    shift_err[np.diag_indices(3)] = ((volume_err + 4 * U * volume) * other
                                     + volume * (np.roll(sq_err, 1) + np.roll(sq_err, 2)))
    inertia_err = j_o_err + shift_err + U * np.abs(inertia)
    return UnitMoments(volume, volume_err, com, com_err, inertia, inertia_err)


def _tensor(second: np.ndarray, products: np.ndarray) -> np.ndarray:
    """(3, 3) with diagonal second_j + second_k and off-diagonals from (xy, yz, zx) products:
    the inertia from ∫x_i² and -∫x_i x_j, or its error bound from theirs."""
    xy, yz, zx = products
    t = np.array([[0.0, xy, zx], [xy, 0.0, yz], [zx, yz, 0.0]])
    t[np.diag_indices(3)] = np.roll(second, 1) + np.roll(second, 2)
    return t


def _check_volume(volume: float, volume_err: float, name: str) -> None:
    if volume == 0 or abs(volume) < MIN_VOLUME_TO_ERROR * volume_err:
        raise NoVolumeError(
            f"{name}: encloses no volume (flat?): expected a closed solid, got a volume of "
            f"{volume:.3g} m³, within {MIN_VOLUME_TO_ERROR:g}x its rounding error "
            f"{volume_err:.3g} m³; check that the file holds a solid, not a sheet")
    if volume < 0:
        raise DegenerateMeshError(
            f"{name}: is inside out: expected outward-facing triangles, got volume {volume:.6g} "
            "m³; reverse the winding of every face (the health check does this with a warning)")


# --- float32 coordinates -------------------------------------------------------------------------
def _input_uncertainty(mesh: Mesh, lo: np.ndarray, hi: np.ndarray, area: np.ndarray,
                       volume: float, com: np.ndarray, rho: float, inertia: np.ndarray,
                       mass_given: bool) -> Uncertainty:
    """First-order effect of every coordinate moving by up to η_i: half a float32 ulp of the
    largest |coordinate| on axis i in the file unit, times the unit factor (float32 sources),
    plus ``mesh.vertex_displacement`` (vertices moved to close round-off cracks).

    Moving the surface by δx changes ∫g dV by ∮ g (δx·n) dA, and |δx_i| <= η_i everywhere, so
    |δ∫g| <= max|g| Σ_i η_i A_i, A_i = Σ_f |area vector_i| (``area`` holds twice that). Volume:
    g = 1. COM: g = x - c over the volume. Inertia about the COM: g = |s|² I - s sᵀ (the COM's own
    move is second order there because ∫ s dV = 0). |s_i| <= reach_i from the bounding box.
    """
    scale = mesh.coordinate_scale
    eta = np.full(3, mesh.vertex_displacement)
    if mesh.coordinate_dtype == np.float32:
        # lo, hi come rounded from v - o: 8u more keeps them upper bounds of the file's |values|
        largest = (np.maximum(np.abs(lo), np.abs(hi)) * (1 + 8 * U) / scale).astype(np.float32)
        eta += np.spacing(largest).astype(np.float64) * (0.5 * scale * (1 + 2.0**-20))
    flux = 1.01 * float(eta @ area) / 2                  # 1 % for the second-order terms
    reach = np.maximum(hi - com, com - lo)
    g = np.outer(reach, reach)
    g[np.diag_indices(3)] = np.roll(reach**2, 1) + np.roll(reach**2, 2)
    d_inertia = rho * g * flux + (np.abs(inertia) * flux / volume if mass_given else 0.0)
    return Uncertainty(flux, 0.0 if mass_given else rho * flux, _frozen(reach * flux / volume),
                       _frozen(d_inertia), _frozen(np.full(3, np.linalg.norm(d_inertia))))


def _floats(a: np.ndarray) -> list:
    return np.asarray(a, dtype=np.float64).tolist()


def _frozen(a: np.ndarray) -> np.ndarray:
    out = np.array(a, dtype=np.float64)
    out.setflags(write=False)
    return out
