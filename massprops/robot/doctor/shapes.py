"""Causes of another shape integrated: the stated inertial is what a tool computed from
something else than the link's geometry as massprops reads it. Each is recomputed per geometry,
placed as `combine` places it, and the link put together with the same masses:

- ``bounding_box``: each mesh replaced by the box around its vertices (its own axes), each
  primitive by its box (what exporters that "approximate by the bounding box" write);
- ``convex_hull``: each mesh by its convex hull (MuJoCo's ``inertia="convex"``, PhysX/Bullet);
- ``thin_shell``: each mesh's surface as a thin wall (`massprops.repair.shell` at a thickness
  of `tolerances.SHELL_LIMIT_THICKNESS` of the mesh's size: the mass on the surface, MuJoCo's
  ``inertia="shell"``);
- ``mujoco_legacy``: each mesh by MuJoCo's legacy rule (`combine.legacy_mesh_inertia`: every
  face's pyramid volume taken positive, which overcounts a non-convex mesh);
- ``other_geometry``: the link's other geometry set (visual instead of collision, or back),
  supplied by `massprops.robot.analyze`.
Primitives are unchanged except under ``bounding_box``; an alternative that changes nothing is
not tried.
"""

from __future__ import annotations

from typing import cast

import numpy as np

from massprops.errors import MassPropsError
from massprops.inertia import rotate_inertia
from massprops.robot.inertials.combine import (
    Part,
    combine,
    convex_hull,
    legacy_mesh_inertia,
)
from massprops.robot.inertials.primitives import PRIMITIVES, box
from massprops.tolerances import SHELL_LIMIT_THICKNESS

__all__ = ["SHAPES", "alternative_part"]

SHAPES = {
    "bounding_box": "the box around the geometry",
    "convex_hull": "the geometry's convex hull",
    "thin_shell": "the surface as a thin shell",
    "mujoco_legacy": "MuJoCo's legacy mesh rule (each face's pyramid volume taken positive)",
}
"""cause -> what the stated inertial is then the inertial of (for the diagnosis' detail)."""



def alternative_part(kind: str, geom, part: Part, meshes) -> Part | None:
    """``part`` (the geometry ``geom`` as integrated) recomputed as ``kind`` (a key of
    SHAPES), unit density, link frame; ``part`` itself when the kind does not change it, None
    when it cannot be computed."""
    a, t = geom.rotation, geom.translation
    if geom.kind != "mesh":
        if kind != "bounding_box" or geom.kind == "box":
            return part
        half = PRIMITIVES[geom.kind](*geom.dims).half_extents(np.eye(3))
        solid = box(*(2 * half))
        return Part(solid.volume, part.center, rotate_inertia(solid.inertia, a), part.lower,
                    part.upper, points=part.points)
    mesh = meshes.mesh(geom)
    v = mesh.vertices
    try:
        if kind == "bounding_box":
            lo, hi = v.min(axis=0), v.max(axis=0)
            solid = box(*(hi - lo))
            volume, com, inertia = solid.volume, (lo + hi) / 2, solid.inertia
        elif kind == "convex_hull":
            # deferred: inspection is what combine already loaded
            from massprops.inspection.file import inspect_mesh

            p = inspect_mesh(convex_hull(mesh), density=1.0).properties
            volume, com, inertia = p.volume, p.center_of_mass, p.inertia
        elif kind == "thin_shell":
            from massprops.repair.shell import shell_properties  # deferred: a repair module

            size = float(np.linalg.norm(v.max(axis=0) - v.min(axis=0)))
            p = shell_properties(mesh, SHELL_LIMIT_THICKNESS * size, density=1.0).properties
            volume, com, inertia = p.volume, p.center_of_mass, p.inertia
        else:
            volume, com, inertia = legacy_mesh_inertia(v, mesh.faces)
    except (MassPropsError, ValueError):
        return None
    if not (volume > 0 and np.isfinite(inertia).all()):
        return None
    return Part(volume, a @ com + t, rotate_inertia(inertia, a), part.lower, part.upper,
                points=part.points)


def shape_bases(geometries, parts, meshes, split) -> list:
    """`diagnose.Base` for each kind of SHAPES that changes the link: the geometries' parts
    recomputed, put together with ``split(parts) -> (masses, total)`` as the link was."""
    out: list[tuple] = []
    for kind, what in SHAPES.items():
        alt = [alternative_part(kind, g, p, meshes) for g, p in zip(geometries, parts)]
        if any(a is None for a in alt) or all(a is p for a, p in zip(alt, parts)):
            continue
        link = combine(cast(list[Part], alt), *split(alt))  # no None left (see above)
        out.append((((kind, {}, what),), link.mass, link.center_of_mass, link.inertia))
    return out
