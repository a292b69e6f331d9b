"""Mesh health: is the surface the closed, consistently oriented boundary of a solid?

The divergence-theorem integral is exact iff the triangles form a closed 2-cycle: every directed
edge a→b is balanced by as many b→a, with vertices identified by their COORDINATES (indexed
formats split vertices at UV seams; STL is unwelded soup). What has one right answer is repaired
(whole mesh inside out, an inverted part, inconsistent winding); what has none (holes, one-sided
surfaces) is refused, or computed with warnings under ``allow_open``. The kernels are in
`massprops.mesh.weld`, `massprops.mesh.topology`, `massprops.mesh.geometry` and
`massprops.mesh.nesting`; this module decides and explains.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from functools import cached_property
from typing import TYPE_CHECKING, cast

import numpy as np

from massprops.errors import MeshFormatError, MeshTopologyError, NoVolumeError, setting_ref
from massprops.mesh.geometry import area_vector_sums, exactly_flat, signed_volumes6
from massprops.mesh.topology import Edges, connected_components, consistent_flips, edges, is_soup
from massprops.mesh.value import Mesh
from massprops.mesh.weld import near_groups, weld
from massprops.tolerances import EPS, EPS32, MAX_HOLE_AREA_FRACTION, NEAR_WELD_ULPS

LOOSE_CAVITY = "is partly outside every solid part"
"""The warning's words for an inward-facing piece not wholly inside a solid: the part outside
is integrated with negative density (`massprops.robot.analyze` names it when the link's
computed inertial then fails a validity test)."""
OPEN_SURFACE = "an open surface encloses no defined volume"
"""The warning's words for a mesh integrated open (``allow_open``)."""

if TYPE_CHECKING:  # imported where a repair needs it: most meshes never do
    from massprops.mesh.nesting import Plan


@dataclass(frozen=True)
class CrackWeld:
    """Vertices moved to close round-off cracks (`tolerances.NEAR_WELD_ULPS`).

    vertices : distinct positions moved onto another. max_distance : m, the farthest move
    (Euclidean). tolerance : m, the per-axis bound a move had to respect.
    """

    vertices: int
    max_distance: float
    tolerance: float

    def as_dict(self) -> dict:
        return {"vertices": self.vertices, "max_distance": self.max_distance,
                "tolerance": self.tolerance}


@dataclass(frozen=True)
class MeshHealth:
    """Topology of a mesh as read, and the repairs `prepare_mesh` made (python scalars only).

    vertices, faces : counts as in the file (faces = file polygons, ``Mesh.n_faces``).
    triangles : rows of ``Mesh.faces`` (the fan triangulation of the polygons).
    unique_vertices : distinct positions; duplicate_vertices = vertices - unique_vertices.
    unreferenced_vertices : distinct positions that no triangle with three distinct corners uses.
    degenerate_faces : triangles of exactly zero area, including repeated vertices.
    closed : every directed edge is balanced by a reverse one (boundary_edges == 0).
    boundary_edges : undirected edges whose two directions are used unequally often.
    manifold : every undirected edge is used by exactly two triangles.
    nonmanifold_edges : undirected edges used by more than two triangles.
    oriented : no edge is used twice more in one direction than the other (neighbours agree).
    components : connected pieces (a shared vertex position connects).
    component_volumes : signed volume of each piece, m³, of the mesh as integrated (after the
        repairs), in order of each piece's first triangle; negative entries are cavities.
    cavities : pieces with negative volume (inward-facing shells inside a solid part).
    flipped : the whole mesh was inside out and every face was reversed.
    rewound_faces : file faces reversed to agree with their neighbours.
    warnings : one line each: what is odd and what it means for the result.
    weld : the round-off cracks welded shut (`CrackWeld`), or None; reported under
        ``repairs`` rather than in the ``"mesh"`` object.
    """

    vertices: int
    faces: int
    triangles: int
    unique_vertices: int
    duplicate_vertices: int
    unreferenced_vertices: int
    degenerate_faces: int
    closed: bool
    boundary_edges: int
    manifold: bool
    nonmanifold_edges: int
    oriented: bool
    components: int
    component_volumes: tuple[float, ...]
    cavities: int
    flipped: bool
    rewound_faces: int
    warnings: tuple[str, ...]
    weld: CrackWeld | None = None

    def as_dict(self) -> dict:
        """The JSON ``"mesh"`` object: every field but ``warnings`` and ``weld`` (reported beside
        it)."""
        out = {f.name: getattr(self, f.name) for f in fields(self)
               if f.name not in ("warnings", "weld")}
        out["component_volumes"] = list(self.component_volumes)
        return out


@dataclass(frozen=True, eq=False)
class _Analysis:
    """What the kernels found in one mesh (m triangles, u welded ids).

    tri (m, 3): welded ids; valid (m,): three distinct ids; reps (u,): a file vertex per id;
    face_comp (m,): component of each triangle, numbered by first triangle (-1: a degenerate
    triangle touching no component); det6 (m,): 6 × signed volume about ``origin``; flat (m,):
    zero area; used (u,): ids used by valid triangles. soup: the faces are the STL layout.
    """

    tri: np.ndarray
    valid: np.ndarray
    reps: np.ndarray
    edges: Edges
    face_comp: np.ndarray
    n_comp: int
    det6: np.ndarray
    flat: np.ndarray
    used: np.ndarray
    origin: np.ndarray
    soup: bool

    @cached_property
    def closed(self) -> bool:
        return self.edges.count("unbalanced") == 0

    @cached_property
    def oriented(self) -> bool:
        return self.edges.count("conflicting") == 0


def _number_components(labels: np.ndarray, tri: np.ndarray, valid: np.ndarray
                       ) -> tuple[np.ndarray, int]:
    """Component index (m,) of each triangle, numbered by first valid triangle, and their count."""
    if not np.any(valid):
        return np.full(tri.shape[0], -1), 0
    if not labels.any():  # every id under id 0: one component holds every triangle
        return np.zeros(tri.shape[0], np.int8), 1
    lab = labels[tri[:, 0]]
    one = lab == lab[np.argmax(valid)]
    if np.all(one):
        return np.zeros(tri.shape[0], np.int8), 1
    if np.all(one[valid]):
        return np.where(one, 0, -1), 1
    uniq, first = np.unique(lab[valid], return_index=True)
    rank = np.empty(uniq.size, np.int64)
    rank[np.argsort(first)] = np.arange(uniq.size)
    pos = np.minimum(np.searchsorted(uniq, lab), uniq.size - 1)
    return np.where(uniq[pos] == lab, rank[pos], -1), int(uniq.size)


def _analyse(mesh: Mesh, flat_out: np.ndarray | None = None) -> _Analysis:
    """The kernels' findings; ``flat_out`` (m,) bool marks triangles known to have exactly zero
    area (`exactly_flat`), left out of the topology like those with a repeated corner."""
    v, faces = mesh.vertices, mesh.faces
    n, m = v.shape[0], faces.shape[0]
    soup = is_soup(faces, n)  # then every index is in range, and every vertex is used
    if not soup and m and (faces.min() < 0 or faces.max() >= n):
        raise MeshFormatError(f"{mesh.name}: face vertex indices must lie in 0..{n - 1}, got "
                              f"{faces.min()}..{faces.max()}; the faces refer to missing vertices")
    origin = v[faces[0, 0]] if m else np.zeros(3)  # a point on the mesh: round-off scales with size
    scratch = np.empty(max(n, 3 * m), np.uint64)  # the sort keys of both passes, in turn
    inv, reps = weld(v, scratch=scratch)
    tri = inv.reshape(-1, 3) if soup else inv[faces]
    valid = (tri[:, 0] != tri[:, 1]) & (tri[:, 1] != tri[:, 2]) & (tri[:, 2] != tri[:, 0])
    if flat_out is not None:
        valid &= ~flat_out
    all_valid = bool(np.all(valid))
    e = edges(tri if all_valid else tri[valid], reps.size, scratch=scratch)
    del scratch
    face_comp, n_comp = _number_components(connected_components(reps.size, e.u, e.v), tri, valid)
    det6, flat = signed_volumes6(v, None if soup else faces, origin)
    if flat_out is not None:
        flat = flat_out | ~valid
    used = np.ones(reps.size, bool)
    if not (soup and all_valid):
        used[:] = False
        used[e.u] = True
        used[e.v] = True
    return _Analysis(tri, valid, reps, e, face_comp, n_comp, det6, flat, used, origin, soup)


def _component_volumes(a: _Analysis, det6: np.ndarray) -> np.ndarray:
    """(K,) signed volume of each component, m³."""
    if a.n_comp == 1 and a.face_comp.dtype == np.int8:  # every triangle in component 0
        return np.array([det6.sum() / 6])
    keep = a.valid & (a.face_comp >= 0)
    return np.bincount(a.face_comp[keep], weights=det6[keep], minlength=a.n_comp) / 6


# --- reports --------------------------------------------------------------------------------------
def _boundary_length(mesh: Mesh, a: _Analysis) -> float:
    """Total length of the unbalanced edges, m."""
    bad = np.flatnonzero(a.edges.imbalance)
    p, q = mesh.vertices[a.reps[a.edges.u[bad]]], mesh.vertices[a.reps[a.edges.v[bad]]]
    return float(np.linalg.norm(p - q, axis=1).sum())


def _box_centre(mesh: Mesh, a: _Analysis) -> np.ndarray:
    box = mesh.vertices[a.reps[a.used]]
    return (box.min(axis=0) + box.max(axis=0)) / 2


def _open_warnings(mesh: Mesh, a: _Analysis, volume: float) -> list[str]:
    """How large the gap is, and what an integral over an open surface means (``volume``: the
    signed volume about the bounding-box centre, m³)."""
    n_open = a.edges.count("unbalanced")
    hole, area = area_vector_sums(mesh.vertices, mesh.faces)
    box = mesh.vertices[a.reps[a.used]]
    spread = float(np.linalg.norm(hole)) * float(np.linalg.norm(np.ptp(box, axis=0))) / 3
    out = [f"mesh is not closed: {n_open} boundary edges (total length "
           f"{_boundary_length(mesh, a):.6g} m); open area |Σ face area vectors| = "
           f"{np.linalg.norm(hole):.3g} m², {_percent(np.linalg.norm(hole), area)} of the surface "
           f"area (0 for a closed surface)",
           f"{OPEN_SURFACE}: the result is the volume closed off by "
           f"cones from the integration origin to each hole's rim; moving that origin across the "
           f"bounding box changes it by up to {spread:.3g} m³ ({_percent(spread, abs(volume))} of "
           f"the {volume:.6g} m³ computed about the box centre)"]
    if not a.oriented:
        out.append(_disagreement(a))
    return out


def _disagreement(a: _Analysis) -> str:
    n = a.edges.count("conflicting")
    return f"neighbouring faces disagree on winding at {_count(n, 'edge')}"


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def _percent(part: float | np.floating, whole: float) -> str:
    return f"{100 * part / whole:.3g}%" if whole > 0 else "an unbounded share"


def _shape_notes(a: _Analysis) -> list[str]:
    """Non-manifold but balanced: fine for the integral, worth saying."""
    n_bad = a.edges.count("nonmanifold")
    if not a.closed or not a.n_comp:
        return []
    if n_bad:
        return [f"{_count(n_bad, 'edge')} shared by more than two faces (solids touching along "
                f"an edge); the integral is still exact"]
    # A closed orientable 2-manifold has Euler characteristic V - E + F = 2 - 2·genus: even and
    # at most 2. Anything else means solids touching at a vertex (a non-manifold vertex).
    chi = _euler_characteristics(a)
    odd = np.flatnonzero((chi % 2 == 1) | (chi > 2))
    if not odd.size:
        return []
    which = f"component {', '.join(str(k + 1) for k in odd)} " if a.n_comp > 1 else ""
    return [f"{which}touches itself or another solid at a vertex (Euler characteristic "
            f"{int(chi[odd[0]])}, expected even and at most 2); the integral is still exact"]


def _euler_characteristics(a: _Analysis) -> np.ndarray:
    """(K,) V - E + F of each component, over the valid triangles and the ids they use."""
    keep = a.valid & (a.face_comp >= 0)
    if a.n_comp == 1:
        return np.array([np.count_nonzero(a.used) - a.edges.u.size + np.count_nonzero(keep)])
    comp_of_id = np.zeros(a.reps.size, np.int64)
    comp_of_id[a.tri[keep].ravel()] = np.repeat(a.face_comp[keep], 3)
    k = a.n_comp
    return (np.bincount(comp_of_id[a.used], minlength=k)
            - np.bincount(comp_of_id[a.edges.u], minlength=k)
            + np.bincount(a.face_comp[keep], minlength=k))


def _health(mesh: Mesh, a: _Analysis, volumes: np.ndarray, *, flipped: bool = False,
            rewound: int = 0, warnings: list[str] | tuple[str, ...] = (),
            weld: CrackWeld | None = None) -> MeshHealth:
    n_ids = a.reps.size
    return MeshHealth(
        vertices=mesh.n_vertices, faces=mesh.n_faces, triangles=int(mesh.faces.shape[0]),
        unique_vertices=n_ids, duplicate_vertices=mesh.n_vertices - n_ids,
        unreferenced_vertices=n_ids - int(np.count_nonzero(a.used)),
        degenerate_faces=int(np.count_nonzero(a.flat)),
        closed=a.closed, boundary_edges=a.edges.count("unbalanced"),
        manifold=a.edges.count("open") + a.edges.count("nonmanifold") == 0,
        nonmanifold_edges=a.edges.count("nonmanifold"),
        oriented=a.oriented, components=a.n_comp,
        component_volumes=tuple(float(x) for x in volumes),
        cavities=int(np.count_nonzero(volumes < 0)), flipped=flipped, rewound_faces=rewound,
        warnings=(*mesh.notes, *warnings), weld=weld)


# --- orientation of the pieces ------------------------------------------------------------------
def _plan_warnings(plan: Plan, volumes: np.ndarray, quiet: np.ndarray, unioned: bool = False
                   ) -> list[str]:
    """Warnings for the plan, at most 5 of a kind; components in ``quiet`` were re-wound and are
    reported as such; overlaps are not warned about when the caller unites the pieces."""
    k = volumes.size
    out = []
    if plan.whole and not np.all(quiet):
        out.append("faces pointed inward; flipped")
    elif not plan.whole:
        out += _first_five([f"component {c + 1} of {k} (signed volume {volumes[c]:.6g} m³) "
                            f"faced inward but lies inside no solid part; flipped it"
                            for c in np.flatnonzero(plan.flip & ~quiet)])
    out += _first_five([f"components {o + 1} and {i + 1} overlap or nest (a vertex of {i + 1} "
                        f"lies inside {o + 1}): the volume they share is counted twice"
                        for o, i in ([] if unioned else plan.overlaps)])
    out += _first_five([f"components {a + 1} and {b + 1} overlap (their surfaces cross: a point "
                        f"lies inside both): the volume they share is counted twice"
                        for a, b in ([] if unioned else plan.crossings)])
    out += _first_five([f"component {c + 1} (a cavity: faces inward) {LOOSE_CAVITY}: that part "
                        f"is subtracted from nothing" for c in plan.loose])
    return out


def _first_five(lines: list[str]) -> list[str]:
    return lines if len(lines) <= 5 else lines[:5] + [f"... and {len(lines) - 5} more like it"]


# --- reversing faces ------------------------------------------------------------------------------
def _polygon_of_triangle(mesh: Mesh) -> np.ndarray:
    if mesh.polygon_sizes is None:
        return np.arange(mesh.faces.shape[0])
    return np.repeat(np.arange(mesh.polygon_sizes.size), mesh.polygon_sizes - 2)


def _reverse(mesh: Mesh, flip: np.ndarray) -> Mesh:
    """The mesh with the flagged triangles reversed, keeping the fan layout valid.

    Reversing polygon (v0, v1, ..., vk) as (v0, vk, ..., v1) keeps the apex v0, so its fan is the
    same triangles (same surface for a non-planar polygon), each reversed as (v0, v[i+1], v[i]),
    in reverse row order. A polygon whose triangles disagree (only possible if the file's polygon
    is itself inconsistent) leaves the mesh as plain triangles.
    """
    faces = mesh.faces
    sizes = mesh.polygon_sizes
    if sizes is not None:
        poly = _polygon_of_triangle(mesh)
        n_flip = np.bincount(poly, weights=flip, minlength=sizes.size)
        if np.all((n_flip == 0) | (n_flip == sizes - 2)):
            start = np.concatenate(([0], np.cumsum(sizes - 2)[:-1]))
            rows = np.arange(faces.shape[0])
            src = np.where(flip, 2 * start[poly] + (sizes - 2)[poly] - 1 - rows, rows)
            out = faces[src]
            out[flip] = out[flip][:, [0, 2, 1]]
            return mesh.with_faces(out)
    out = faces.copy()
    out[flip] = faces[flip][:, ::-1]
    return replace(mesh, faces=out, polygon_sizes=None)


# --- round-off cracks ----------------------------------------------------------------------------
def close_cracks(mesh: Mesh) -> tuple[Mesh, CrackWeld | None, list[str]]:
    """``mesh`` with its round-off cracks welded and zero-area faces' edges set aside wherever
    that removes open edges, even if real holes remain (for ``--fill-holes``, which then caps only
    the real holes); the weld's report and the warnings. A closed mesh comes back as it is."""
    a = _analyse(mesh)
    if not a.edges.count("open"):
        return mesh, None, []
    welded, _, report, notes = _close_cracks(mesh, a, partial=True)
    return welded, report, notes


def _close_cracks(mesh: Mesh, a: _Analysis, *, partial: bool = False
                  ) -> tuple[Mesh, _Analysis, CrackWeld | None, list[str]]:
    """A mesh whose open edges are round-off only, closed: first exactly zero-area faces left out
    of the topology (a collinear sliver adds edges no face balances, and encloses nothing), then
    the two sides of round-off cracks welded (`tolerances.NEAR_WELD_ULPS`). Each step is kept only
    if it leaves no open edge; otherwise (a real gap) the mesh and analysis come back unchanged.
    ``partial``: the weld is kept if it leaves fewer open edges (the slivers' own edges are then
    left to the caller, as tiny loops)."""
    def fewer_open(b: _Analysis, than: _Analysis) -> bool:
        left = b.edges.count("open")
        return left == 0 or (partial and left < than.edges.count("open"))

    b, flat = a, _exactly_flat(mesh, a)
    if flat.any():
        trial = _analyse(mesh, flat)
        if trial.edges.count("open") == 0:
            return mesh, trial, None, [_flat_note(flat)]
        if partial:
            b = trial
    welded, weld_report = _weld_cracks(mesh, b)
    if welded is None:
        return mesh, a, None, []
    weld_report = cast(CrackWeld, weld_report)  # given with every welded mesh
    flat = _exactly_flat(welded, _analyse(welded))
    c = _analyse(welded, flat)
    if not fewer_open(c, b):
        return mesh, a, None, []
    moved = _count(weld_report.vertices, "vertex position")
    notes = [f"closed round-off cracks: welded {moved} onto copies at most "
             f"{weld_report.max_distance:.3g} m away (tolerance {weld_report.tolerance:.3g} m, "
             f"{NEAR_WELD_ULPS} ulps of the largest coordinate); the input error bar covers the "
             f"move"]
    if flat.any() and not partial:
        notes.append(_flat_note(flat))
    return welded, c, weld_report, notes


def _flat_note(flat: np.ndarray) -> str:
    return (f"left {_count(int(np.count_nonzero(flat)), 'zero-area face')} (corners on one line) "
            f"out of the topology: they enclose nothing")


def _exactly_flat(mesh: Mesh, a: _Analysis) -> np.ndarray:
    """(m,) bool: triangles with three distinct corners and exactly zero area."""
    out = np.zeros(mesh.faces.shape[0], bool)
    out[a.valid] = exactly_flat(mesh.vertices, mesh.faces[a.valid])
    return out


def _weld_cracks(mesh: Mesh, a: _Analysis) -> tuple[Mesh, CrackWeld] | tuple[None, None]:
    """The mesh with the positions at its unbalanced edges welded within the round-off tolerance
    (each group onto its first position in file order), or (None, None) if none are that close."""
    bad = a.edges.imbalance != 0
    ends = np.unique(np.concatenate((a.edges.u[bad], a.edges.v[bad])))
    points = mesh.vertices[a.reps[ends]]
    eps = EPS32 if mesh.coordinate_dtype == np.float32 else EPS
    tol = NEAR_WELD_ULPS * eps * float(np.abs(mesh.vertices).max())
    target = near_groups(points, tol) if tol > 0 else np.arange(ends.size)
    moved = np.flatnonzero(target != np.arange(ends.size))
    if not moved.size:
        return None, None
    shift = points[target[moved]] - points[moved]
    position = mesh.vertices[a.reps].copy()
    position[ends[moved]] = points[target[moved]]
    corners = a.tri.reshape(-1)
    hit = np.isin(corners, ends[moved])
    vertices = mesh.vertices.copy()
    vertices[mesh.faces.reshape(-1)[hit]] = position[corners[hit]]
    report = CrackWeld(int(moved.size), float(np.linalg.norm(shift, axis=1).max()), tol)
    return replace(mesh, vertices=vertices,
                   vertex_displacement=max(mesh.vertex_displacement,
                                           float(np.abs(shift).max()))), report


# --- public -------------------------------------------------------------------------------------
def check_mesh(mesh: Mesh) -> MeshHealth:
    """The health of ``mesh`` as it is: counts, topology, signed component volumes; no repairs,
    and no overlap test (see `prepare_mesh`). Raises MeshFormatError for out-of-range indices."""
    a = _analyse(mesh)
    volumes = _component_volumes(a, a.det6)
    warnings = []
    if not a.closed:
        warnings.append(f"mesh is not closed: {a.edges.count('unbalanced')} boundary edges "
                        f"(total length {_boundary_length(mesh, a):.6g} m)")
    if not a.oriented:
        warnings.append(_disagreement(a))
    elif a.closed and volumes.sum() < 0:
        warnings.append(f"faces point inward (total signed volume {volumes.sum():.6g} m³)")
    return _health(mesh, a, volumes, warnings=warnings + _shape_notes(a))


def _open_fixes(holes) -> str:
    """What works on an open mesh: --fill-holes, with the --max-hole its largest loop needs
    when that is above the default; --shell where no cap can be accepted (and for a part that
    is open by design); or --allow-open."""
    from massprops.mesh.boundary import max_hole_for  # the error path only

    fill = f"use {setting_ref('fill_holes')}"
    if holes is not None and holes.largest > MAX_HOLE_AREA_FRACTION:
        needed = max_hole_for(holes.largest)
        shell = (f"{setting_ref('shell')} THICKNESS for a thin-walled or open part, or "
                 f"{setting_ref('allow_open')} to compute anyway")
        if needed is None:
            return f"no cap can close the largest loop: use {shell}"
        return (f"{fill} with {setting_ref('max_hole')} {needed:g} to cap them (the largest "
                f"is above the default limit {MAX_HOLE_AREA_FRACTION:g}), {shell}")
    return f"{fill} to cap them, or {setting_ref('allow_open')} to compute anyway"


def prepare_mesh(mesh: Mesh, *, allow_open: bool = False, unioned: bool = False
                 ) -> tuple[Mesh, MeshHealth]:
    """The mesh to integrate, and its health (topology as read; volumes and repairs as returned).

    Closed and outward: returned unchanged (the same object). Inside out: flipped. An inverted
    part: flipped. Inconsistent winding on a 2-manifold: re-wound. Overlapping parts: warned.
    ``unioned``: the caller replaces the pieces by their union (``massprops.repair.union``), so
    overlaps are neither warned about nor measured.
    Raises MeshTopologyError if the mesh has no faces, is one-sided, or is open (boundary edges,
    or non-manifold edges used unequally each way) unless ``allow_open``; DegenerateMeshError if
    its faces use fewer than 4 distinct positions; MeshFormatError for out-of-range indices.
    """
    if mesh.faces.shape[0] == 0:
        raise MeshTopologyError(f"{mesh.name}: mesh has no faces; expected a closed surface of "
                                f"at least 4 triangles; check that the file holds faces")
    a = _analyse(mesh)
    cracks: CrackWeld | None = None
    crack_notes: list[str] = []
    if a.edges.count("open"):
        mesh, a, cracks, crack_notes = _close_cracks(mesh, a)
    if np.count_nonzero(a.used) < 4:
        raise NoVolumeError(f"{mesh.name}: the faces span only {np.count_nonzero(a.used)} "
                                  f"distinct vertex positions (zero-area faces aside); a solid "
                                  f"needs at least 4")
    volumes = _component_volumes(a, a.det6)
    if a.closed and a.n_comp == 1 and volumes[0] > 0:  # the fast path: nothing to repair
        return mesh, _health(mesh, a, volumes, warnings=crack_notes + _shape_notes(a),
                             weld=cracks)
    # deferred: only meshes of several pieces or with open edges get here
    from massprops.mesh.nesting import Plan, orientation_plan, sample_windings
    rewind = np.zeros(mesh.faces.shape[0], bool)
    if not a.oriented and int(a.edges.uses.max()) <= 2:
        flips = consistent_flips(a.tri[a.valid], a.reps.size)
        if flips is None:
            raise MeshTopologyError(f"{mesh.name}: the surface is one-sided (a Möbius strip or "
                                    f"Klein bottle): no winding makes neighbouring faces agree, "
                                    f"so it bounds no solid; fix the model")
        rewind[a.valid] = flips
    det6 = np.where(rewind, -a.det6, a.det6)
    closed = a.closed or (bool(rewind.any()) and bool(np.all(a.edges.uses == 2)))
    volumes = _component_volumes(a, det6)
    warnings = list(crack_notes)
    if not closed:
        if not allow_open:
            n_open = a.edges.count("open" if rewind.any() else "unbalanced")
            from massprops.mesh.boundary import describe_holes  # the error path only

            holes = describe_holes(a.edges, mesh.vertices[a.reps],
                                   area_vector_sums(mesh.vertices, mesh.faces)[1],
                                   open_only=bool(rewind.any()))
            raise MeshTopologyError(f"{mesh.name}: mesh is not closed: "
                                    f"{n_open} boundary edges (total length "
                                    f"{_boundary_length(mesh, a):.6g} m"
                                    f"{'' if holes is None else ' in ' + holes.text}); "
                                    f"{_open_fixes(holes)}")
        # Volumes of an open surface depend on the origin: take them about the box centre.
        centre = _box_centre(mesh, a)
        det6 = np.where(rewind, -1.0, 1.0) * signed_volumes6(
            mesh.vertices, None if a.soup else mesh.faces, centre)[0]
        volumes = _component_volumes(a, det6)
        warnings += _open_warnings(mesh, a, volumes.sum())
        whole = bool(a.oriented and volumes.sum() < 0)
        plan = Plan(np.full(a.n_comp, whole), whole, [], [])
    elif a.n_comp == 1:
        plan = Plan(volumes < 0, bool(volumes[0] < 0), [], [])
    else:
        piece = np.where(a.valid, a.face_comp, -1)
        plan = orientation_plan(volumes, sample_windings(mesh.vertices, mesh.faces, a.tri, piece,
                                                         a.n_comp))
    touched = np.bincount(a.face_comp[rewind], minlength=a.n_comp) > 0
    warnings += _plan_warnings(plan, volumes, touched, unioned)
    flip = rewind ^ np.append(plan.flip, False)[a.face_comp]  # face_comp -1: no component
    fixed = _reverse(mesh, flip) if flip.any() else mesh
    if (plan.overlaps or plan.crossings) and not unioned:  # measured; lazily: rare, costly
        # deferred: only meshes of several pieces or with open edges get here
        from massprops.mesh.overlap import overlap_warning

        warnings.append(overlap_warning(fixed, volumes * np.where(plan.flip, -1.0, 1.0),
                                        plan.overlaps + plan.crossings))
    poly = _polygon_of_triangle(mesh)
    changed = np.bincount(poly, weights=flip, minlength=mesh.n_faces) > 0
    in_touched = np.bincount(poly, weights=np.append(touched, False)[a.face_comp],
                             minlength=mesh.n_faces) > 0
    rewound = int(np.count_nonzero(changed & in_touched))
    if rewound:
        warnings.insert(0, f"re-wound {rewound} faces to a consistent orientation")
    volumes = volumes * np.where(plan.flip, -1.0, 1.0)
    return fixed, _health(mesh, a, volumes, flipped=bool(plan.whole and not np.all(touched)),
                          rewound=rewound, warnings=warnings + _shape_notes(a), weld=cracks)
