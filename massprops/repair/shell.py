"""``--shell T``: the mass properties of a surface as a wall of thickness T (metres), open or
closed, flat or curved; density ρ in kg/m³, so the surface density is ρT.

Model. The surface is the wall's mid-surface: each triangle f is extruded by T/2 to both sides
along its normal n_f (a right prism), and neighbouring prisms are joined by a mitre. Integrated:
- each prism exactly: mass ρ T A_f, first moment ρ T ∫x dA, second moment
  ρ T ∫x xᵀ dA + ρ T³/12 A_f n_f n_fᵀ (the through-thickness term, which makes a flat plate exact);
  ∫ over a triangle: A (a+b+c)/3 and A/12 (a aᵀ + b bᵀ + c cᵀ + s sᵀ), s = a + b + c;
- each edge e where two faces turn by θ (evaluated in `massprops.repair.joins`): the prisms
  leave a gap (a kite of area (T/2)² tan(θ/2) in the section across the edge) on the convex
  side and overlap by the mirror
  image of that kite on the concave side. A mitred wall fills the gap once and holds the overlap
  once: the change ∫_gap g − ∫_overlap g = 2 L Dg(midpoint)[∫_kite y dy] is exact for the
  polynomials g of the moments (the kites are point reflections of each other through the edge)
  and zero for the mass. It is added.
A free edge is cut square (a sheet's rim). The result is exact for flat plates and polygonal
plates meeting at mitred edges, apart from the corners.

Error bar of the model (``uncertainty.repair``, regions as in `massprops.repair.bars`):
- a bent rather than mitred join fills a circular sector instead of the kite: per edge a volume
  (T/2)² (tan(θ/2) − θ/2) L within (T/2)/cos(θ/2) of the edge;
- a kite wider than its faces (a sharp fold against small facets) cannot be mirrored: no
  correction, and both kites' volume, 2 (T/2) min((T/2) tan(θ/2), h) L, goes to the bar;
- an edge of more than two faces (a rib on a plate): k T min(h, T) L, within 1.5 T;
- at a vertex whose face normals lie within β of their mean n̄, the joins of the edges meeting
  there overlap or leave gaps inside the double cone of half-angle β about ±n̄ and radius
  r = (T/2)/cos β (at most T/2 + the longest edge there): volume <= m (4π/3) r³ (1 − cos β),
  m = 1 + the turning edges at the vertex (a bound of the layers of wall that meet there).
For a smooth surface of curvature radius R tessellated finely, these are O((T/R)²) relative (the
mid-surface model's own error is of that order: for a sphere it misses 5/12 (T/R)² of the
moment of inertia, which the vertex terms cover).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from massprops.errors import DegenerateMeshError, MeshFormatError, UsageError, setting_ref
from massprops.inertia import parallel_axis_to_com
from massprops.mesh import Mesh
from massprops.mesh.facesums import BLOCK, U, gamma
from massprops.mesh.integral import (
    ErrorBars,
    MassProperties,
    Uncertainty,
    UnitMoments,
    check_density_mass,
    properties_from_moments,
)
from massprops.mesh.pieces import Welded
from massprops.repair.bars import moment_bounds, with_repair_bar
from massprops.repair.joins import Joins, joins, unit_normals
from massprops.tolerances import SHELL_WARN_FRACTION

MODEL = "mid-surface wall, faces extruded by T/2 each side, joined by mitres"


@dataclass(frozen=True)
class ShellRecord:
    """What ``--shell`` did (the ``repairs.shell`` JSON object).

    thickness : m. model : the wall model in words. area : m², of the mid-surface.
    wall_volume : m³ (area × thickness). mitred_edges : edges where a mitre was added;
    folded_edges : joins the model could not mirror; crowded_edges : edges of more than two
    faces. model_volume_bound : m³, the total volume of the model's error regions.
    """

    thickness: float
    model: str
    area: float
    wall_volume: float
    mitred_edges: int
    folded_edges: int
    crowded_edges: int
    model_volume_bound: float

    def as_dict(self) -> dict:
        return {"thickness": self.thickness, "model": self.model, "area": self.area,
                "wall_volume": self.wall_volume, "mitred_edges": self.mitred_edges,
                "folded_edges": self.folded_edges, "crowded_edges": self.crowded_edges,
                "model_volume_bound": self.model_volume_bound}


@dataclass(frozen=True, eq=False)
class ShellResult:
    properties: MassProperties
    record: ShellRecord
    warnings: tuple[str, ...]


def shell_properties(mesh: Mesh, thickness: float, *, density: float | None = None,
                     mass: float | None = None) -> ShellResult:
    """Mass properties of ``mesh`` as a wall of ``thickness`` m (see the module docstring):
    volume is the wall's, mass ρ × volume (or ``mass``, then ρ = mass / volume), COM and inertia
    about it in the mesh's axes. Raises UsageError for a bad thickness, density or mass, and
    DegenerateMeshError when the surface has no area."""
    check_density_mass(density, mass)
    if not (math.isfinite(thickness) and thickness > 0):
        raise UsageError(f"the shell thickness must be a positive finite number of metres, got "
                         f"{thickness!r}")
    w = Welded.of(mesh)
    rows = np.flatnonzero(w.valid)
    if rows.size == 0:
        raise DegenerateMeshError(f"{mesh.name}: the surface has no area (no triangle with three "
                                  f"distinct corners); {setting_ref('shell')} needs a surface")
    used = mesh.vertices[mesh.faces[rows]].reshape(-1, 3)
    if not np.isfinite(used).all():
        raise MeshFormatError(f"{mesh.name}: expected finite vertex coordinates, got NaN or "
                              f"infinity; fix or re-export the file")
    origin = (used.min(axis=0) + used.max(axis=0)) / 2
    faces = _face_terms(mesh, rows, origin, thickness)
    if faces.area <= 0:
        raise DegenerateMeshError(f"{mesh.name}: the surface has no area (every triangle is a "
                                  f"line or a point); {setting_ref('shell')} needs a surface")
    normals, doubled = unit_normals(w.positions[w.tri])  # every face's, once
    met = joins(w, normals, doubled, origin, thickness)
    mo = _unit_moments(faces, met, thickness)
    props = properties_from_moments(origin, mo, density=density, mass=mass, name=mesh.name)
    if mesh.coordinate_dtype == np.float32:
        props = _with_input_bar(props, mesh, faces, thickness, mass is not None)
    bar = moment_bounds(met.regions.sums(w.positions, props.center_of_mass), props,
                        mass_given=mass is not None)
    props = with_repair_bar(props, bar)
    record = ShellRecord(float(thickness), MODEL, faces.area, float(props.volume), met.mitred,
                         met.folded, met.crowded, met.regions.total)
    return ShellResult(props, record, tuple(_warnings(props, bar, thickness)))


def _warnings(props: MassProperties, bar: Uncertainty, thickness: float) -> list[str]:
    worst = max(bar.volume / props.volume,
                float(np.max(bar.principal_moments / np.maximum(props.principal_moments,
                                                                 1e-300))))
    if worst <= SHELL_WARN_FRACTION:
        return []
    return [f"the thin-wall model is uncertain by up to {100 * worst:.3g}% (mass or a principal "
            f"moment): a {thickness:g} m wall is thick against this surface's curvature or facets "
            f"(the thickness is in metres, whatever --unit says)"]


# --- the faces ----------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class _FaceTerms:
    """Totals over the faces about the origin, per unit area density: area m², first (3,) m³
    (∫x dA), second (3, 3) m⁴ (∫x xᵀ dA + T²/12 Σ A n nᵀ), each with a rounding bound; perimeter
    m (Σ of the triangles' perimeters); lo, hi (3,) m the extremes of x - o."""

    area: float
    area_err: float
    first: np.ndarray
    first_err: np.ndarray
    second: np.ndarray
    second_err: np.ndarray
    perimeter: float
    lo: np.ndarray
    hi: np.ndarray


_PAIRS = ((0, 0), (1, 1), (2, 2), (0, 1), (1, 2), (2, 0))


def _face_terms(mesh: Mesh, rows: np.ndarray, origin: np.ndarray, thickness: float) -> _FaceTerms:
    """One pass over the faces in blocks of ``facesums.BLOCK`` (cache-sized; each block total a
    pairwise sum, the blocks added by math.fsum, as ``massprops.mesh.facesums`` does)."""
    t2 = thickness * thickness / 12
    totals, lo, hi = [], np.full(3, np.inf), np.full(3, -np.inf)
    for start in range(0, rows.size, BLOCK):
        p = np.ascontiguousarray(mesh.vertices[mesh.faces[rows[start:start + BLOCK]]]
                                 .transpose(1, 2, 0))  # (corner, axis, face)
        x = p - origin[None, :, None]
        lo = np.minimum(lo, x.min(axis=(0, 2)))
        hi = np.maximum(hi, x.max(axis=(0, 2)))
        totals.append(_block_terms(p, x, t2))
    t = np.array([math.fsum(col) for col in np.array(totals).T])
    # per face: <= 24 roundings on top of the stored coordinates (differences, products, the
    # square root, the divisions); a block's dot products add at most one rounding per face
    # (whatever order BLAS sums in), fsum one more
    err = gamma(24 + min(rows.size, BLOCK) + 1) * t[10:20]
    second, second_err = np.empty((3, 3)), np.empty((3, 3))
    for idx, (a, c) in enumerate(_PAIRS):
        second[a, c] = second[c, a] = t[4 + idx]
        second_err[a, c] = second_err[c, a] = err[4 + idx]
    return _FaceTerms(float(t[0]), float(err[0]), t[1:4], err[1:4], second, second_err,
                      float(t[20]), lo, hi)


def _block_terms(p: np.ndarray, x: np.ndarray, t2: float) -> np.ndarray:
    """(21,) block totals: area, ∫x_i dA (3), ∫x_a x_b dA + T²/12 A n_a n_b (6, ``_PAIRS``); the
    same ten with absolute values (the rounding bounds' weights); the perimeters."""
    e1, e2 = p[1] - p[0], p[2] - p[0]
    j, k = [1, 2, 0], [2, 0, 1]
    plus, minus = e1[j] * e2[k], e1[k] * e2[j]
    n = plus - minus                                             # (3, f) twice the area vector
    n2 = np.sqrt(np.einsum("if,if->f", n, n))                    # twice the area
    np.abs(plus, out=plus)
    np.abs(minus, out=minus)
    plus += minus
    big = np.sqrt(np.einsum("if,if->f", plus, plus))             # >= n2, its error scale
    s = x.sum(axis=0)
    ax = np.abs(x)
    sa = ax.sum(axis=0)
    half, half_big = n2 / 2, big / 2
    out = np.empty(21)
    out[0], out[10] = half.sum(), half_big.sum()
    out[1:4] = s @ half / 3
    out[11:14] = sa @ half_big / 3
    with np.errstate(invalid="ignore", divide="ignore"):
        inv = np.where(n2 > 0, 1 / np.where(n2 > 0, n2, 1), 0.0)
    thick = t2 * inv / 2
    for idx, (a, b) in enumerate(_PAIRS):
        q = np.einsum("cf,cf->f", x[:, a], x[:, b]) + s[a] * s[b]
        qa = np.einsum("cf,cf->f", ax[:, a], ax[:, b]) + sa[a] * sa[b]
        out[4 + idx] = (half / 12) @ q + (n[a] * n[b]) @ thick
        out[14 + idx] = (half_big / 12) @ qa + t2 * half_big.sum()
    third = p[2] - p[1]
    out[20] = (np.sqrt(np.einsum("if,if->f", e1, e1)) + np.sqrt(np.einsum("if,if->f", e2, e2))
               + np.sqrt(np.einsum("if,if->f", third, third))).sum()
    return out


# --- totals to moments ----------------------------------------------------------------------------
def _unit_moments(faces: _FaceTerms, joins: Joins, thickness: float) -> UnitMoments:
    """Volume, COM (from the origin) and inertia about the COM per unit density, with their
    rounding bounds (first-order propagation, as in ``massprops.mesh.integral``)."""
    t = thickness
    volume = t * faces.area
    volume_err = t * faces.area_err + U * volume
    first = t * faces.first + joins.first
    first_err = t * faces.first_err + joins.err_first + 2 * U * np.abs(first)
    second = t * faces.second + joins.second
    second_err = t * faces.second_err + joins.err_second + 2 * U * np.abs(second)
    com = first / volume
    com_err = (first_err + np.abs(com) * volume_err) / volume + 2 * U * np.abs(com)
    j_o = np.trace(second) * np.eye(3) - second
    j_o_err = np.trace(second_err) * np.eye(3) + second_err * (1 - np.eye(3)) - np.diag(
        np.diag(second_err)) + 3 * U * np.abs(j_o)
    inertia = parallel_axis_to_com(j_o, volume, com)
    ac = np.abs(com)
    shift_err = (volume_err / volume + 4 * U) * volume * (np.outer(ac, ac) + np.sum(ac**2)
                                                            * np.eye(3))
    shift_err += volume * (2 * np.outer(ac + com_err, com_err) + 2 * np.sum((ac + com_err)
                                                                             * com_err) * np.eye(3))
    inertia_err = j_o_err + shift_err + U * np.abs(inertia)
    return UnitMoments(volume, volume_err, com, com_err, inertia, inertia_err)


def _with_input_bar(props: MassProperties, mesh: Mesh, faces: _FaceTerms, thickness: float,
                    mass_given: bool) -> MassProperties:
    """float32 coordinates: every point may move by |η| (half a float32 ulp per axis): the area
    changes by at most |η| Σ perimeter / 2, and ∫g dA by that times max|g| plus A max|Dg| |η|."""
    scale = mesh.coordinate_scale
    largest = (np.maximum(np.abs(mesh.vertices.min(axis=0)), np.abs(mesh.vertices.max(axis=0)))
               * (1 + 8 * U) / scale).astype(np.float32)
    eta = float(np.linalg.norm(np.spacing(largest).astype(np.float64) * 0.5 * scale)) * 1.01
    d_area = eta * faces.perimeter / 2
    c = props.center_of_mass
    box = np.array([mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)])
    reach = np.maximum(np.abs(box[1] - c), np.abs(c - box[0])) + eta
    rho, t, a = props.density, thickness, faces.area
    g = np.outer(reach, reach)
    g[np.diag_indices(3)] = np.roll(reach**2, 1) + np.roll(reach**2, 2)
    volume = t * d_area
    d_inertia = rho * t * (d_area * (g + t * t / 6) + 4 * a * float(np.linalg.norm(reach)) * eta)
    if mass_given:
        d_inertia = d_inertia + np.abs(props.inertia) * volume / props.volume
    data = Uncertainty(volume, 0.0 if mass_given else rho * volume,
                       (d_area * reach + a * eta) * t / props.volume, d_inertia,
                       np.full(3, np.linalg.norm(d_inertia, 2)))
    u = props.uncertainty
    return dataclasses.replace(props, uncertainty=ErrorBars(u.rounding, data, u.repair))
