"""``--shell T``: the mass properties of a surface as a wall of thickness T (metres), open or
closed, flat or curved; density ρ in kg/m³, so the surface density is ρT.

Model. The surface is the wall's mid-surface: each triangle f is extruded by T/2 to both sides
along its normal n_f (a right prism), and neighbouring prisms are joined by a mitre. Integrated:
- each prism exactly: mass ρ T A_f, first moment ρ T ∫x dA, second moment
  ρ T ∫x xᵀ dA + ρ T³/12 A_f n_f n_fᵀ (the through-thickness term, which makes a flat plate exact);
  ∫ over a triangle: A (a+b+c)/3 and A/12 (a aᵀ + b bᵀ + c cᵀ + s sᵀ), s = a + b + c;
- each edge e where two faces turn by θ: the prisms leave a gap (a kite of area
  (T/2)² tan(θ/2) in the section across the edge) on the convex side and overlap by the mirror
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

from massprops.errors import DegenerateMeshError, UsageError
from massprops.facesums import U, gamma, pairwise_depth
from massprops.inertia import parallel_axis_to_com
from massprops.mass import (
    ErrorBars,
    MassProperties,
    Uncertainty,
    UnitMoments,
    check_density_mass,
    properties_from_moments,
)
from massprops.mesh import Mesh
from massprops.repair.bars import Regions, moment_bounds, with_repair_bar
from massprops.repair.topology import Welded
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
                                  f"distinct corners); --shell needs a surface")
    used = mesh.vertices[mesh.faces[rows]].reshape(-1, 3)
    origin = (used.min(axis=0) + used.max(axis=0)) / 2
    faces = _face_terms(mesh, rows, origin, thickness)
    if faces.area <= 0:
        raise DegenerateMeshError(f"{mesh.name}: the surface has no area (every triangle is a "
                                  f"line or a point); --shell needs a surface")
    joins = _joins(w, origin, thickness)
    corners = _corners(w, thickness, joins.turning)
    mo = _unit_moments(faces, joins, thickness)
    props = properties_from_moments(origin, mo, density=density, mass=mass)
    if mesh.coordinate_dtype == np.float32:
        props = _with_input_bar(props, mesh, faces, thickness, mass is not None)
    regions = Regions.join(joins.regions, corners)
    bar = moment_bounds(regions, props, mass_given=mass is not None)
    props = with_repair_bar(props, bar)
    record = ShellRecord(float(thickness), MODEL, faces.area, float(props.volume), joins.mitred,
                         joins.folded, joins.crowded, regions.total)
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
    p = mesh.vertices[mesh.faces[rows]].transpose(1, 2, 0)  # (corner, axis, face): rows contiguous
    x = p - origin[None, :, None]
    e1, e2 = p[1] - p[0], p[2] - p[0]
    j, k = [1, 2, 0], [2, 0, 1]
    plus, minus = e1[j] * e2[k], e1[k] * e2[j]
    n = plus - minus                                             # (3, m) twice the area vector
    n2 = np.sqrt((n * n).sum(axis=0))                            # twice the area
    big = np.sqrt(((np.abs(plus) + np.abs(minus)) ** 2).sum(axis=0))  # >= n2, its error scale
    s = x.sum(axis=0)
    sa = np.abs(x).sum(axis=0)
    half = n2 / 2
    terms = [half]
    bounds = [big / 2]
    for i in range(3):
        terms.append(half * s[i] / 3)
        bounds.append(big / 2 * sa[i] / 3)
    t2 = thickness * thickness / 12
    with np.errstate(invalid="ignore", divide="ignore"):
        inv = np.where(n2 > 0, 1 / np.where(n2 > 0, n2, 1), 0.0)
    for a, b in _PAIRS:
        q = x[:, a] * x[:, b]
        qa = np.abs(x[:, a]) * np.abs(x[:, b])
        terms.append(half / 12 * (q.sum(axis=0) + s[a] * s[b]) + t2 * n[a] * n[b] * inv / 2)
        bounds.append(big / 24 * (qa.sum(axis=0) + sa[a] * sa[b]) + t2 * big / 2)
    t = np.array(terms)
    b = np.array(bounds)
    totals = t.sum(axis=1)
    # per face: <= 24 roundings on top of the stored coordinates (differences, products, the
    # square root, the divisions); the pairwise sum adds its depth
    err = gamma(24 + pairwise_depth(rows.size) + 1) * b.sum(axis=1)
    second, second_err = np.empty((3, 3)), np.empty((3, 3))
    for idx, (a, c) in enumerate(_PAIRS):
        second[a, c] = second[c, a] = totals[4 + idx]
        second_err[a, c] = second_err[c, a] = err[4 + idx]
    edges = np.sqrt((e1 * e1).sum(axis=0)) + np.sqrt((e2 * e2).sum(axis=0))
    third = p[2] - p[1]
    perimeter = float((edges + np.sqrt((third * third).sum(axis=0))).sum())
    return _FaceTerms(float(totals[0]), float(err[0]), totals[1:4], err[1:4], second, second_err,
                      perimeter, x.min(axis=(0, 2)), x.max(axis=(0, 2)))


# --- the joins at edges ---------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class _Joins:
    """Mitre corrections per unit density (first (3,) m⁴, second (3, 3) m⁵ about the origin,
    with a bound of their rounding), the error regions, and counts."""

    first: np.ndarray
    second: np.ndarray
    err_first: np.ndarray
    err_second: np.ndarray
    regions: Regions
    mitred: int
    folded: int
    crowded: int
    turning: np.ndarray  # (e,) bool: the edge's faces are not all in one plane


def _unit_normals(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(unit normals (f, 3), twice the areas (f,)) of triangles p (f, 3 corners, 3)."""
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    n2 = np.linalg.norm(n, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(n2[:, None] > 0, n / n2[:, None], 0.0), n2


def _joins(w: Welded, origin: np.ndarray, thickness: float) -> _Joins:
    e = w.edges
    pos = w.positions
    half_t = thickness / 2
    pu, pv = pos[e.u], pos[e.v]
    length = np.linalg.norm(pv - pu, axis=1)
    two = np.flatnonzero(e.count == 2)
    f, g = e.face[e.start[two]], e.face[e.start[two] + 1]
    pf, pg = pos[w.tri[f]], pos[w.tri[g]]
    nf, af = _unit_normals(pf)
    ng, ag = _unit_normals(pg)
    same_way = e.forward[e.start[two]] == e.forward[e.start[two] + 1]
    ng = np.where(same_way[:, None], -ng, ng)  # wound against its neighbour: compare as one
    cross = np.linalg.norm(np.cross(nf, ng), axis=1)
    theta = np.arctan2(cross, np.einsum("ij,ij->i", nf, ng))
    lt = length[two]
    with np.errstate(invalid="ignore", divide="ignore"):
        hf, hg = af / lt, ag / lt  # heights over the edge: twice the area / the edge's length
    tan_half = np.tan(theta / 2)
    reach = half_t * tan_half            # how far the kite runs along each face from the edge
    fits = (reach <= np.minimum(hf, hg)) & (theta > 0)
    # the opposite corner of g: above f's plane means g turns toward n_f (concave on that side)
    opposite = pos[w.tri[g, (e.corner[e.start[two] + 1] + 2) % 3]]
    rise = np.einsum("ij,ij->i", opposite - pu[two], nf)
    side = -np.sign(rise)                # the gap is on the side g turns away from
    bis = nf + ng
    bis_norm = np.linalg.norm(bis, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        bis = np.where(bis_norm[:, None] > 0, bis / bis_norm[:, None], 0.0)
    cos_half = np.cos(theta / 2)
    kite = half_t * half_t * tan_half
    with np.errstate(invalid="ignore", divide="ignore"):
        depth = thickness / 6 * (cos_half + 1 / cos_half)
    y = np.where(fits[:, None], (side * kite * depth)[:, None] * bis, 0.0)  # ∫_kite y dy
    mid = (pu[two] + pv[two]) / 2 - origin
    first_e = 2 * lt[:, None] * y
    second_e = 2 * lt[:, None, None] * (mid[:, :, None] * y[:, None, :]
                                        + y[:, :, None] * mid[:, None, :])
    first = first_e.sum(axis=0)
    second = second_e.sum(axis=0)
    slack = gamma(40 + pairwise_depth(max(two.size, 1)))
    err_first = slack * np.abs(first_e).sum(axis=0)
    err_second = slack * np.abs(second_e).sum(axis=0)

    # regions: bends instead of mitres, folds that could not be mirrored, crowded edges
    with np.errstate(invalid="ignore", divide="ignore"):
        r_edge = np.where(fits, half_t / cos_half, np.hypot(half_t, np.maximum(hf, hg)))
    bend = np.where(fits, half_t * half_t * np.maximum(tan_half - theta / 2, 0.0),
                    2 * half_t * np.minimum(np.nan_to_num(reach, nan=np.inf, posinf=np.inf),
                                            np.maximum(hf, hg)))
    bend = np.where(theta > 0, bend, 0.0) * lt
    crowd = np.flatnonzero(e.count > 2)
    h_crowd = _longest_height(w, e, crowd)
    vol_crowd = e.count[crowd] * thickness * np.minimum(h_crowd, thickness) * length[crowd]
    ends_lo = np.minimum(pu, pv)
    ends_hi = np.maximum(pu, pv)
    lo = np.concatenate([ends_lo[two] - r_edge[:, None], ends_lo[crowd] - 1.5 * thickness])
    hi = np.concatenate([ends_hi[two] + r_edge[:, None], ends_hi[crowd] + 1.5 * thickness])
    volume = np.concatenate([bend, vol_crowd]) * (1 + 1e-9)
    keep = volume > 0
    regions = Regions(volume[keep], lo[keep], hi[keep])
    turning = e.count > 2
    turning[two] = theta > 0
    return _Joins(first, second, err_first, err_second, regions,
                  int(np.count_nonzero(fits)),
                  int(np.count_nonzero(~fits & (theta > 0))), int(crowd.size), turning)


def _longest_height(w: Welded, e, crowd: np.ndarray) -> np.ndarray:
    """(c,) the largest height over the edge of the triangles at each crowded edge, m."""
    out = np.zeros(crowd.size)
    for i, k in enumerate(crowd):
        faces = e.face[e.start[k]:e.start[k] + e.count[k]]
        _, n2 = _unit_normals(w.positions[w.tri[faces]])
        edge = np.linalg.norm(w.positions[e.v[k]] - w.positions[e.u[k]])
        out[i] = n2.max() / edge if edge > 0 else 0.0
    return out


# --- the corners --------------------------------------------------------------------------------
def _corners(w: Welded, thickness: float, turning: np.ndarray) -> Regions:
    """One region per vertex whose faces are not all parallel (module docstring). The wall's
    layers there are at most as many as the planes meeting at the vertex, and those are at most
    one more than its turning edges: that count is the multiplicity (``deg`` in the docstring)."""
    rows = np.flatnonzero(w.valid)
    tri = w.tri[rows]
    p = w.positions[tri]
    n, n2 = _unit_normals(p)
    ids = tri.ravel()
    k = w.reps.size
    mean = np.zeros((k, 3))
    np.add.at(mean, ids, np.repeat(n * n2[:, None], 3, axis=0))
    size = np.linalg.norm(mean, axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(size[:, None] > 0, mean / size[:, None], 0.0)
    cos_b = np.ones(k)
    np.minimum.at(cos_b, ids, np.abs(np.einsum("ij,ij->i", np.repeat(n, 3, axis=0), mean[ids])))
    cos_b = np.clip(cos_b, 0.0, 1.0)
    e = w.edges
    deg = 1 + np.bincount(e.u[turning], minlength=k) + np.bincount(e.v[turning], minlength=k)
    deg[np.bincount(ids, minlength=k) == 0] = 0
    longest = np.zeros(k)
    length = np.linalg.norm(w.positions[e.v] - w.positions[e.u], axis=1)
    np.maximum.at(longest, e.u, length)
    np.maximum.at(longest, e.v, length)
    half_t = thickness / 2
    with np.errstate(divide="ignore"):
        radius = np.minimum(half_t / cos_b, half_t + longest)
    volume = deg * (4 * np.pi / 3) * radius**3 * np.minimum(1.0, 1.0 - cos_b)
    # 1 - cos β from a rounded cosine: a flat vertex computes ~1e-16, not 0; harmless (tiny)
    keep = np.flatnonzero((volume > 0) & (deg > 0))
    centre = w.positions[keep]
    r = radius[keep, None]
    return Regions(volume[keep] * (1 + 1e-9), centre - r, centre + r)


# --- totals to moments ----------------------------------------------------------------------------
def _unit_moments(faces: _FaceTerms, joins: _Joins, thickness: float) -> UnitMoments:
    """Volume, COM (from the origin) and inertia about the COM per unit density, with their
    rounding bounds (first-order propagation, as in ``massprops.mass``)."""
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
