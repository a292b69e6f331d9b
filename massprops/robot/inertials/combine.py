"""From geometries to a link's mass properties: integrate each solid, place it, add them up.

Each geometry is integrated at unit density in its own frame (meshes by massprops' exact
integral after the health checks, primitives by their closed forms; an MJCF mesh under MuJoCo's
``shell`` rule, or under its ``legacy`` rule when it is not closed, by that rule:
`legacy_mesh_inertia`), then placed in the link frame: c_link = A c + t, J_link = A J Aᵀ
(`inertia.rotate_inertia`). Several solids add up by the parallel-axis theorem about the common
centre of mass (`inertia.parallel_axis`). Overlapping solids count twice, as in every simulator:
the description's geometry is taken as given.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import cast

import numpy as np

from massprops.errors import DegenerateMeshError, MeshTopologyError
from massprops.files import check_input_file
from massprops.inertia import parallel_axis, principal_axes, rotate_inertia
from massprops.inspection.file import inspect_mesh
from massprops.io import read_mesh
from massprops.mesh import Mesh
from massprops.robot.doctor.bounds import Bounds, bounds_of, primitive_points
from massprops.robot.inertials.primitives import PRIMITIVES
from massprops.robot.model import Geometry
from massprops.tolerances import SHELL_LIMIT_THICKNESS

__all__ = ["LinkMass", "Part", "combine", "integrate_geometry", "legacy_mesh_inertia"]


@dataclass(frozen=True, eq=False)
class Part:
    """One geometry at unit density, placed in the link frame.

    volume : m³. center : (3,) m, link frame. inertia : (3, 3) m⁵ (kg·m² per kg/m³) about
    ``center``, link axes. lower, upper : (3,) m, an axis-aligned box around it in the link
    frame: tight for primitives; for a mesh, the box around its own bounding box turned into
    the link frame (tight unless the pose turns it). warnings : what the health checks said.
    points : (k, 3) m, link frame, points whose convex hull contains the geometry (a mesh's hull
    vertices, a primitive's circumscribing polytope: `doctor.bounds`), or None.
    """

    volume: float
    center: np.ndarray
    inertia: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    warnings: tuple[str, ...] = ()
    repairs: dict | None = None
    points: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class LinkMass:
    """A link's computed mass properties, link frame, SI.

    mass : kg. volume : m³ (sum over its geometries). center_of_mass : (3,) m.
    inertia : (3, 3) kg·m² about the centre of mass, link axes. principal_moments (3,) ascending
    and principal_axes (3, 3) (columns) as `inertia.principal_axes`. size : m, the diagonal of
    the axis-aligned box around its geometry (the scale COM offsets are measured against).
    bounds : the geometry's convex hull and an ellipsoid around it (`doctor.bounds.Bounds`), or
    None (flat geometry); what `doctor.validity` judges the COM and realizability against.
    """

    mass: float
    volume: float
    center_of_mass: np.ndarray
    inertia: np.ndarray
    principal_moments: np.ndarray
    principal_axes: np.ndarray
    size: float
    bounds: Bounds | None = None

    def as_dict(self) -> dict:
        return {"mass": self.mass, "center_of_mass": self.center_of_mass.tolist(),
                "inertia": self.inertia.tolist(),
                "principal_moments": self.principal_moments.tolist(),
                "principal_axes": self.principal_axes.tolist(),
                "volume": self.volume, "size": self.size}


class MeshCache:
    """Meshes read once per file and scale (robot descriptions reuse meshes: left and right)."""

    def __init__(self, allow_open: bool = False, repairs=None) -> None:
        """repairs : a `massprops.repair.RepairOptions` applied to every mesh, or None."""
        self.allow_open = allow_open
        self.repairs = repairs
        self._store: dict[tuple, tuple] = {}
        self._hulls: dict[int, np.ndarray] = {}
        self._read: dict[tuple, Mesh] = {}

    def hull_points(self, mesh: Mesh) -> np.ndarray:
        """(k, 3) m: the vertices of ``mesh``'s convex hull (all of them if Qhull refuses)."""
        if id(mesh) not in self._hulls:
            from scipy.spatial import ConvexHull  # only for the doctor's bounds

            try:
                self._hulls[id(mesh)] = mesh.vertices[ConvexHull(mesh.vertices).vertices]
            except Exception:  # Qhull's error for flat or degenerate point sets
                self._hulls[id(mesh)] = mesh.vertices
        return self._hulls[id(mesh)]

    @staticmethod
    def _key(geom: Geometry) -> tuple:
        return (str(geom.path), tuple(geom.scale.tolist())) if geom.path is not None else (
            id(geom.vertices), tuple(geom.scale.tolist()))

    def get(self, geom: Geometry):
        """(mesh with the scale applied, its Inspection at unit density)."""
        key = self._key(geom)
        if key not in self._store:
            self._store[key] = self._load(geom)
        return self._store[key]

    def mesh(self, geom: Geometry) -> Mesh:
        """The mesh as read with the scale applied (no health checks)."""
        key = self._key(geom)
        if key not in self._read:
            self._read[key] = self._scaled(geom)
        return self._read[key]

    def _scaled(self, geom: Geometry) -> Mesh:
        if geom.vertices is not None and geom.faces is None:
            # MJCF vertex= without face=: MuJoCo's mesh is the convex hull of the points
            mesh = convex_hull(Mesh(np.ascontiguousarray(geom.vertices, dtype=np.float64),
                                    np.zeros((0, 3), dtype=np.int64), name=geom.uri))
        elif geom.vertices is not None:
            mesh = Mesh(np.ascontiguousarray(geom.vertices, dtype=np.float64),
                        np.ascontiguousarray(geom.faces, dtype=np.int64), name=geom.uri)
        else:  # a mesh file: resolved, since an unresolved one is skipped (Geometry.problem)
            # a missing file first: "no such file" says more than its extension would (romeo's
            # file:///usr/Romeo/.../Torso.mesh, a path on its author's machine)
            check_input_file(cast(Path, geom.path))
            mesh = read_mesh(Path(cast(Path, geom.path)), name=str(geom.path))
        scale = np.asarray(geom.scale, dtype=np.float64)
        if not np.all(scale != 0):
            raise DegenerateMeshError(f"{mesh.name}: scale {scale.tolist()} flattens the mesh; "
                                      "give non-zero scale factors")
        if np.any(scale != 1):
            mesh = mesh.with_vertices(mesh.vertices * scale)
            if np.prod(np.sign(scale)) < 0:  # a mirror turns the surface inside out
                mesh = mesh.with_faces(np.ascontiguousarray(mesh.faces[:, ::-1]))
        return mesh

    def _load(self, geom: Geometry):
        mesh = self.mesh(geom)
        try:
            return mesh, inspect_mesh(mesh, density=1.0, allow_open=self.allow_open,
                                      repairs=self.repairs)
        except MeshTopologyError as exc:
            if geom.rule != "convex":
                raise
            # the simulator integrates the hull anyway: that is the body it simulates
            hull = convex_hull(mesh)
            result = inspect_mesh(hull, density=1.0)
            note = (f"not a closed solid ({str(exc).split(': ', 1)[-1][:80]}...): its convex "
                    "hull is integrated, as MuJoCo does for this mesh's inertia mode")
            return hull, replace(result, health=replace(
                result.health, warnings=(*result.health.warnings, note)))


def integrate_geometry(geom: Geometry, meshes: MeshCache) -> Part:
    """The geometry at unit density in the link frame. Raises the mesh readers' and health
    checks' errors (MeshFileError, MeshTopologyError, ...) for a mesh that cannot be used."""
    a, t = geom.rotation, geom.translation
    if geom.kind == "mesh" and geom.rule in ("shell", "legacy"):
        special = _simulator_rule(geom, meshes)
        if special is not None:
            return special
    if geom.kind == "mesh":
        mesh, result = meshes.get(geom)
        p = result.properties
        # the box around the mesh's own bounding box turned into the link frame: 8 corners
        # instead of every vertex (a (n, 3) @ (3, 3) product costs more than the health checks)
        lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
        centre, half = a @ ((lo + hi) / 2) + t, np.abs(a) @ ((hi - lo) / 2)
        return Part(p.volume, a @ p.center_of_mass + t, rotate_inertia(p.inertia, a),
                    centre - half, centre + half, tuple(result.warnings),
                    result.repairs_as_dict(), meshes.hull_points(mesh) @ a.T + t)
    solid = PRIMITIVES[geom.kind](*geom.dims)
    half = solid.half_extents(a)
    return Part(solid.volume, np.asarray(t, dtype=np.float64), rotate_inertia(solid.inertia, a),
                t - half, t + half, points=primitive_points(geom.kind, solid.dims) @ a.T + t)


def _simulator_rule(geom: Geometry, meshes: MeshCache) -> Part | None:
    """A mesh under MuJoCo's ``inertia="shell"`` (always) or ``"legacy"`` (when it is not a
    closed solid, so that no exact integral exists: MuJoCo's own rule is what it simulates), at
    unit density in the link frame; None for a legacy mesh the exact integral accepts."""
    mesh = meshes.mesh(geom)
    a, t = geom.rotation, geom.translation
    if geom.rule == "legacy":
        try:
            meshes.get(geom)
            return None
        except MeshTopologyError as exc:
            volume, com, inertia = legacy_mesh_inertia(mesh.vertices, mesh.faces)
            note = (f"not a closed solid ({str(exc).split(': ', 1)[-1][:80]}...): integrated by "
                    "MuJoCo's legacy rule (each face's pyramid volume taken positive), what "
                    "MuJoCo simulates for this mesh")
            if not volume > 0:
                raise
    else:
        from massprops.repair.shell import shell_properties  # deferred: MJCF shell meshes only

        lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
        wall = SHELL_LIMIT_THICKNESS * float(np.linalg.norm(hi - lo))
        p = shell_properties(mesh, wall, density=1.0).properties
        # per unit *surface* density (MuJoCo's shell density is per m²): divide by the wall
        volume, com, inertia = p.volume / wall, p.center_of_mass, p.inertia / wall
        note = ("MuJoCo's inertia=\"shell\": the surface carries the mass (density per m²), "
                "integrated as a thin wall")
    lo, hi = mesh.vertices.min(axis=0), mesh.vertices.max(axis=0)
    centre, half = a @ ((lo + hi) / 2) + t, np.abs(a) @ ((hi - lo) / 2)
    return Part(volume, a @ com + t, rotate_inertia(inertia, a), centre - half, centre + half,
                (note,), None, meshes.hull_points(mesh) @ a.T + t)


def combine(parts: list[Part], masses: list[float], total: float | None = None) -> LinkMass:
    """The link made of ``parts`` with ``masses`` (kg each, uniform within a part).

    total : the link's mass to report (the stated mass kept exactly), default sum(masses).
    """
    m = np.asarray(masses, dtype=np.float64)
    whole = float(m.sum())
    com = sum(mi * p.center for mi, p in zip(m, parts)) / whole
    inertia = np.zeros((3, 3))
    for mi, p in zip(m, parts):
        inertia += parallel_axis(p.inertia * (mi / p.volume), float(mi), com - p.center)
    moments, axes = principal_axes(inertia)
    lower = np.min([p.lower for p in parts], axis=0)
    upper = np.max([p.upper for p in parts], axis=0)
    points = [p.points for p in parts if p.points is not None]
    bounds = bounds_of(np.concatenate(points)) if len(points) == len(parts) else None
    return LinkMass(whole if total is None else float(total), float(sum(p.volume for p in parts)),
                    com, inertia, moments, axes, float(np.linalg.norm(upper - lower)), bounds)


def convex_hull(mesh: Mesh) -> Mesh:
    """The convex hull of ``mesh``'s vertices as a closed mesh, faces turned outward (each
    facet's winding checked against Qhull's outward plane normal)."""
    from scipy.spatial import ConvexHull  # only for open MJCF meshes, which MuJoCo hulls

    try:
        hull = ConvexHull(mesh.vertices)
    except Exception as exc:  # Qhull's error for flat or degenerate point sets
        raise DegenerateMeshError(f"{mesh.name}: its points span no volume (no convex "
                                  "hull)") from exc
    faces = hull.simplices.astype(np.int64)
    v = mesh.vertices
    normal = np.cross(v[faces[:, 1]] - v[faces[:, 0]], v[faces[:, 2]] - v[faces[:, 0]])
    inward = np.einsum("ij,ij->i", normal, hull.equations[:, :3]) < 0
    faces[inward] = faces[inward][:, ::-1]
    used, inverse = np.unique(faces, return_inverse=True)
    return Mesh(np.ascontiguousarray(v[used]),
                np.ascontiguousarray(inverse.reshape(-1, 3).astype(np.int64)),
                name=f"{mesh.name} (convex hull)")


def legacy_mesh_inertia(vertices: np.ndarray, faces: np.ndarray
                        ) -> tuple[float, np.ndarray, np.ndarray]:
    """MuJoCo's ``inertia="legacy"`` mesh rule (the default of ``<mesh>``; user_mesh.cc), per
    unit density in the mesh frame: (volume m³, centre of mass (3,) m, inertia (3, 3) m⁵ about
    it).

    It integrates the mesh's own faces, not its hull: each face f spans a pyramid to a reference
    point, and the pyramid's volume is taken *positive*, |(c_f − p)·n_f| A_f / 3, whichever way
    the face points. The COM is the volume-weighted mean of the pyramids' centroids to p = the
    surface's area-weighted centroid; the volume and the second moments are then summed over the
    pyramids to that COM (tetrahedra (COM, a, b, c), ∫ x xᵀ dV = V/20 (Σ a aᵀ + s sᵀ), s = a+b+c),
    and the inertia is taken about the COM as it stands. For a convex mesh seen from inside the
    pyramids do not overlap and this is the exact integral; for a non-convex one a face seen
    from behind adds volume where the exact rule subtracts it, so it overcounts (more mass far
    out: larger moments)."""
    v = np.asarray(vertices, dtype=np.float64)
    tri = v[np.asarray(faces, dtype=np.int64)]
    a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
    cross = np.cross(b - a, c - a)          # 2 A n
    centre = (a + b + c) / 3
    area2 = np.linalg.norm(cross, axis=1)
    facecen = (area2 @ centre) / area2.sum()
    vol = np.abs(np.einsum("ij,ij->i", centre - facecen, cross)) / 6
    com = (vol @ (0.75 * centre + 0.25 * facecen)) / vol.sum()
    a, b, c = a - com, b - com, c - com
    vol = np.abs(np.einsum("ij,ij->i", (a + b + c) / 3, np.cross(b - a, c - a))) / 6
    s = a + b + c
    second = sum(np.einsum("i,ij,ik->jk", vol / 20, p, p) for p in (a, b, c, s))
    inertia = np.trace(second) * np.eye(3) - second
    return float(vol.sum()), com, inertia
