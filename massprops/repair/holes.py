"""``--fill-holes``: close each boundary loop of an open mesh with a cap that keeps its shape.

Loops. The rim is the chain of unbalanced directed edges (each boundary edge as the surface runs
it; the surface is first wound consistently). The cap runs the rim the other way round, so the
capped surface is a closed 2-cycle.

Caps. The rim is seen in its best-fit plane (Newell's normal): if that outline is simple it is
ear-clipped there (never a fan from a corner, which folds over a non-convex rim); otherwise the
triangulation of least area in space is taken (dynamic programming, rims of at most
``triangulate.MAX_DP_POINTS`` points); a larger self-crossing rim is refused.

How ill-defined the answer is. A hole's true surface is unknown; we take as reasonable every cap
that spans the rim inside the rim's convex hull (all its triangulations, flat or folded), and a
dome that continues the slope of the faces around the rim where they meet it at less than
``HOLE_CREASE_ANGLE_DEG`` (a hole in a curved surface; steeper faces are a crease, where the
surface turns, not continues). Two such caps differ by a volume inside the hull (its slab times
its projected area) or under the dome, itself under the cone over the hull whose height is what
the rim's steepest continuing face rises over the hole's radius (hull area × height / 3; a
spherical cap continuing a slope fills 3/4 of that cone). That volume, per hole, is its share
of the error bar (`massprops.repair.bars`): zero for a planar rim with square neighbours (the
cube missing a face is capped exactly).

Size. A loop whose cap is more than ``MAX_HOLE_AREA_FRACTION`` of the surface area is not a hole
but an opening: refused, naming its length and area (``max_hole`` raises the limit).
"""

from __future__ import annotations

import math
from collections import defaultdict
from dataclasses import dataclass, replace

import numpy as np

from massprops.errors import MeshTopologyError, setting_ref
from massprops.mesh import Mesh
from massprops.mesh.boundary import max_hole_for
from massprops.mesh.pieces import Welded
from massprops.mesh.topology import consistent_flips
from massprops.repair.bars import Regions
from massprops.repair.triangulate import (
    MAX_DP_POINTS,
    ear_clip,
    hull_area,
    is_simple,
    min_area,
    plane_frame,
)
from massprops.tolerances import HOLE_CREASE_ANGLE_DEG, MAX_HOLE_AREA_FRACTION


@dataclass(frozen=True)
class HoleRecord:
    """What ``--fill-holes`` did (the ``repairs.fill_holes`` JSON object).

    holes : loops capped. boundary_edges : edges on their rims. area : m², total cap area;
    area_fraction : of the surface area before capping; largest : m², the largest cap.
    cap_volume_spread : m³, the bound of how much the volume changes between reasonable caps
    (see the module docstring): the volume's share of the error bar. ear_clipped, min_area :
    caps made each way. left_open : loops left open (``allow_open`` only), with the reasons.
    """

    holes: int
    boundary_edges: int
    area: float
    area_fraction: float
    largest: float
    cap_volume_spread: float
    ear_clipped: int
    min_area: int
    left_open: tuple[str, ...]

    def as_dict(self) -> dict:
        return {"holes": self.holes, "boundary_edges": self.boundary_edges, "area": self.area,
                "area_fraction": self.area_fraction, "largest": self.largest,
                "cap_volume_spread": self.cap_volume_spread, "ear_clipped": self.ear_clipped,
                "min_area": self.min_area, "left_open": list(self.left_open)}


@dataclass(frozen=True, eq=False)
class HoleResult:
    """The capped mesh, the record, the error regions of the solid (one per hole), each cap's
    area (h,) m² and relative tilt spread (h,) (how much steeper than flat a reasonable cap may
    be: 2 (slab + rise) / radius, capped at 1), and warnings."""

    mesh: Mesh
    record: HoleRecord
    regions: Regions
    cap_areas: np.ndarray
    cap_tilts: np.ndarray
    warnings: tuple[str, ...]

    def wall_regions(self, thickness: float) -> Regions:
        """The error regions when the capped surface is a wall of ``thickness`` m (``--shell``
        after ``--fill-holes``): a cap's area is uncertain by its tilt spread, its wall volume
        by that times the thickness."""
        return Regions(thickness * self.cap_areas * self.cap_tilts, self.regions.lo,
                       self.regions.hi)


@dataclass(frozen=True, eq=False)
class _Loop:
    ids: np.ndarray    # (k,) welded ids, cap order
    faces: np.ndarray  # (k,) the surface triangle along each rim edge (cap edge i -> i+1)


def fill_holes(mesh: Mesh, *, max_fraction: float | None = None,
               allow_open: bool = False) -> HoleResult:
    """``mesh`` with every boundary loop capped (faces of a closed mesh are returned as they
    are). Raises MeshTopologyError for a loop too large to be a hole or one that cannot be
    capped, unless ``allow_open`` (then it is left open and named in ``left_open``)."""
    limit = MAX_HOLE_AREA_FRACTION if max_fraction is None else float(max_fraction)
    w, faces = _wound(mesh)
    loops = _loops(w, faces)
    surface = float(_areas(mesh.vertices, faces).sum())
    new, lines, regions = [], [], []
    counts = {"ear": 0, "dp": 0}
    areas, tilts, edges_capped = [], [], 0
    for n, loop in enumerate(loops):
        where = f"boundary loop {n + 1} of {len(loops)}"
        points = w.positions[loop.ids]
        tri, how = _cap(points)
        length = float(np.linalg.norm(points - np.roll(points, -1, axis=0), axis=1).sum())
        if tri is None:
            problem = (f"{where} ({loop.ids.size} edges, length {length:.6g} m) crosses itself "
                       f"seen from every side and has more than {MAX_DP_POINTS} points: no cap "
                       f"we could defend; use {setting_ref('shell')} THICKNESS for a "
                       f"thin-walled or open part, or {setting_ref('allow_open')} to compute "
                       "anyway")
        else:
            area = float(_areas(points, tri).sum())
            problem = None
            if area > limit * surface:
                needed = max_hole_for(area / surface)
                raise_it = ("no limit accepts it" if needed is None else
                            f"raise it with {setting_ref('max_hole')} {needed:g}")
                problem = (f"{where} ({loop.ids.size} edges, length {length:.6g} m) would need a "
                           f"cap of {area:.6g} m², {_percent(area, surface)} of the surface area: "
                           f"too large to be a hole (limit {limit:g} of the surface; {raise_it}, "
                           f"or use {setting_ref('shell')} for a thin-walled or open part)")
        if problem is not None:
            if not allow_open:
                raise MeshTopologyError(f"{mesh.name}: {problem}")
            lines.append(problem)
            continue
        counts[how] += 1
        areas.append(area)
        edges_capped += loop.ids.size
        new.append(w.reps[loop.ids[tri]])
        region, tilt = _spread(points, w, faces, loop)
        regions.append(region)
        tilts.append(tilt)
    closed = _with_caps(mesh, faces, new)
    spread = Regions.join(Regions.none(), *regions)
    record = HoleRecord(len(new), edges_capped, float(sum(areas)),
                        float(sum(areas)) / surface if surface > 0 else math.inf,
                        max(areas, default=0.0), spread.total, counts["ear"], counts["dp"],
                        tuple(lines))
    warnings = tuple(f"left open: {line}" for line in lines)
    return HoleResult(closed, record, spread, np.array(areas), np.array(tilts), warnings)


def _percent(part: float, whole: float) -> str:
    return f"{100 * part / whole:.3g}%" if whole > 0 else "an unbounded share"


# --- loops ----------------------------------------------------------------------------------------
def _wound(mesh: Mesh) -> tuple[Welded, np.ndarray]:
    """The welded mesh and its faces wound consistently (file faces reversed where needed)."""
    w = Welded.of(mesh)
    faces = mesh.faces
    e = w.edges
    if e.count.max(initial=0) <= 2 and not np.all(e.manifold | (e.count == 1)):
        flips = consistent_flips(w.tri[w.valid], w.reps.size)
        if flips is None:
            raise MeshTopologyError(f"{mesh.name}: the surface is one-sided (a Möbius strip): "
                                    f"its holes have no inside to close; fix the model")
        rows = np.flatnonzero(w.valid)[flips]
        faces = faces.copy()
        faces[rows] = faces[rows][:, ::-1]
        w = Welded(replace(mesh, faces=faces, polygon_sizes=None), w.tri.copy(), w.valid, w.reps)
        w.tri[rows] = w.tri[rows][:, ::-1]
    return w, faces


def _rim_edges(w: Welded) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The cap's edges a -> b (welded ids) and the surface triangle along each: one per excess
    use of an edge in one direction (the surface runs b -> a once too often)."""
    e = w.edges
    use_edge = np.repeat(np.arange(e.count.size), e.count)
    fwd = np.bincount(use_edge, weights=e.forward, minlength=e.count.size).astype(np.int64)
    imbalance = 2 * fwd - e.count  # forward minus backward uses
    open_ = np.flatnonzero(imbalance)
    excess = imbalance[open_] > 0
    # the surface runs u -> v when forward uses are in excess; the cap runs the other way
    a = np.where(excess, e.v[open_], e.u[open_])
    b = np.where(excess, e.u[open_], e.v[open_])
    # a use in the excess direction: the first such use of each open edge
    uses = np.flatnonzero((imbalance[use_edge] != 0)
                          & (e.forward == (imbalance[use_edge] > 0)))
    first = np.unique(use_edge[uses], return_index=True)[1]
    face = e.face[uses[first]]
    times = np.abs(imbalance[open_])
    return np.repeat(a, times), np.repeat(b, times), np.repeat(face, times)


def _loops(w: Welded, faces: np.ndarray) -> list[_Loop]:
    """The rims in cap order: the cap edges chained end to start."""
    a, b, face = _rim_edges(w)
    out_edges = defaultdict(list)
    for i, j, f in zip(a.tolist(), b.tolist(), face.tolist()):
        out_edges[i].append((j, f))
    loops = []
    for start in sorted(out_edges):
        while out_edges[start]:
            ids, owners, at = [], [], start
            while out_edges[at]:
                nxt, f = out_edges[at].pop()
                ids.append(at)
                owners.append(f)
                at = nxt
                if at == start:
                    break
            loops.append(_Loop(np.array(ids, dtype=np.int64), np.array(owners, dtype=np.int64)))
    return loops


# --- caps -----------------------------------------------------------------------------------------
def _cap(points: np.ndarray) -> tuple[np.ndarray | None, str]:
    """Triangles (k-2, 3) into the rim, and how they were made ("ear" or "dp")."""
    k = points.shape[0]
    if k == 3:
        return np.array([[0, 1, 2]]), "ear"
    centre, _, axes = plane_frame(points)
    xy = (points - centre) @ axes.T
    if is_simple(xy):
        tri = ear_clip(xy)
        if tri is not None:
            return tri, "ear"
    if k <= MAX_DP_POINTS:
        return min_area(points), "dp"
    return None, ""


def _spread(points: np.ndarray, w: Welded, faces: np.ndarray, loop: _Loop
            ) -> tuple[Regions, float]:
    """The region two reasonable caps of this rim can differ by (module docstring), and the
    caps' relative tilt spread (see `HoleResult`)."""
    centre, normal, axes = plane_frame(points)
    rel = points - centre
    height = rel @ normal
    xy = rel @ axes.T
    hull = hull_area(xy)
    slab = float(height.max() - height.min())
    radius = float(np.linalg.norm(xy, axis=1).max())
    v = w.mesh.vertices
    around = v[faces[loop.faces]]
    n = np.cross(around[:, 1] - around[:, 0], around[:, 2] - around[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    cos_tilt = np.clip(n @ normal, -1.0, 1.0)  # both wound like the cap: 1 for a flat neighbour
    tilt = np.arccos(cos_tilt)
    continuing = tilt < math.radians(HOLE_CREASE_ANGLE_DEG)
    slope = float(np.tan(tilt[continuing]).max(initial=0.0))
    rise = slope * radius
    # between two caps in the hull: at most the hull's slab; a dome continuing the slope stays
    # under the cone of height ``rise`` over the (convex) hull, of volume hull · rise / 3
    volume = hull * (slab + rise / 3) * (1 + 1e-9)  # margin for this bound's own rounding
    pad = slab + rise
    tilt = min(1.0, 2 * pad / radius) if radius > 0 else 1.0
    return Regions(np.array([volume]), (points.min(axis=0) - pad)[None],
                   (points.max(axis=0) + pad)[None]), tilt


def _areas(points: np.ndarray, tri: np.ndarray) -> np.ndarray:
    p = points[tri]
    return np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1) / 2


def _with_caps(mesh: Mesh, faces: np.ndarray, caps: list[np.ndarray]) -> Mesh:
    """The mesh's (consistently wound) faces followed by the caps' triangles; the file's polygon
    layout is kept for the old faces, each cap triangle a polygon of its own."""
    rewound = faces is not mesh.faces  # reversed triangles break the polygons' fans
    sizes = None if rewound else mesh.polygon_sizes
    if not caps:
        return mesh if not rewound else replace(mesh, faces=faces, polygon_sizes=None)
    added = np.concatenate(caps).astype(np.int64)
    if sizes is not None:
        sizes = np.concatenate([sizes, np.full(added.shape[0], 3, np.int64)])
    return replace(mesh, faces=np.concatenate([faces, added]), polygon_sizes=sizes)
