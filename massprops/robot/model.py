"""The neutral model every parser produces: links, their stated inertials and their geometry.

Frames: every vector and tensor here is in the *link frame* (URDF/SDF link, MJCF body), SI units.
A geometry's pose maps its own frame into the link frame: v_link = rotation @ v_geom + translation.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from massprops.robot.formats.xmltree import Node

__all__ = ["Geometry", "Link", "MassRules", "RobotModel", "StatedInertial", "pick_source"]


@dataclass(frozen=True, eq=False)
class StatedInertial:
    """What the file says about a link's mass distribution.

    mass : kg. center_of_mass : (3,) m, link frame. inertia : (3, 3) kg·m² about the centre of
    mass in the link's axes (the file's inertial frame already rotated in: J = A J' Aᵀ).
    node : the element it came from (for the line number and for write-back).
    """

    mass: float
    center_of_mass: np.ndarray
    inertia: np.ndarray
    node: Node


@dataclass(frozen=True, eq=False)
class Geometry:
    """One solid that makes up a link.

    kind : "mesh" or a key of ``primitives.PRIMITIVES``.
    dims : the primitive's dimensions (``primitives.Solid.dims``), () for a mesh.
    rotation : (3, 3), translation : (3,) m: the geometry frame in the link frame.
    path : the mesh file, resolved; None for primitives, or when it could not be resolved.
    uri : the mesh reference as written (for messages).
    scale : (3,) per-axis scale applied to the mesh's coordinates before the pose.
    density : kg/m³ the file gives this geometry (MJCF geom density), or None (URDF/SDF: the
        link is uniform). mass : kg the file gives this geometry (MJCF geom mass), or None.
    problem : why this geometry cannot be integrated (an unresolved URI, an unsupported kind), or
        None. A link with a problem is skipped and counted as an input error.
    vertices, faces : an inline mesh (MJCF ``<mesh vertex= face=>``), else None.
    warning : a remark about how a simulator treats it (not an error), or None.
    rule : how the simulator integrates this mesh (MJCF ``<mesh inertia>``): "exact" (the
        default elsewhere), "convex" (its hull: a mesh that is not a closed solid is then taken
        as its hull, with a warning, instead of being refused), "legacy" (MuJoCo's default: a
        mesh that is not closed is integrated by `combine.legacy_mesh_inertia`, what MuJoCo
        simulates, with a warning) or "shell" (the surface carries the mass: ``density`` is
        then per m², integrated by `massprops.repair.shell` in the thin-wall limit).
    node : the element it came from (line numbers).
    """

    kind: str
    node: Node
    rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    translation: np.ndarray = field(default_factory=lambda: np.zeros(3))
    dims: tuple[float, ...] = ()
    path: Path | None = None
    uri: str = ""
    scale: np.ndarray = field(default_factory=lambda: np.ones(3))
    density: float | None = None
    mass: float | None = None
    problem: str | None = None
    vertices: np.ndarray | None = None
    faces: np.ndarray | None = None
    warning: str | None = None
    rule: str = "exact"


@dataclass(frozen=True, eq=False)
class Link:
    """A URDF/SDF link or an MJCF body.

    name : as in the file (MJCF bodies without a name: ``body#k``, k MuJoCo's body id).
    node : its element. stated : its inertial, or None. geometries : what it is made of (the
    collision or visual set, as asked). warnings : remarks about the description (not errors).
    inertial_node : the element to replace on write-back (None: insert a new one).
    source : which geometry ``geometries`` is: "collision" or "visual" (with ``--from auto``, a
        link with no collision element falls back to its visual ones).
    auto_mass : kg, the mass an SDF ``<inertial auto="true">`` scales its collisions to, or None.
    A link whose every geometry has a ``density`` (MJCF, SDF auto) is computed from them.
    """

    name: str
    node: Node
    stated: StatedInertial | None
    geometries: tuple[Geometry, ...]
    inertial_node: Node | None = None
    warnings: tuple[str, ...] = ()
    source: str = "collision"
    auto_mass: float | None = None


@dataclass(frozen=True)
class MassRules:
    """How a simulator's compiler changes every body's inertial after reading it (MJCF
    ``<compiler>``): ``boundmass`` kg, the least mass of a body; ``boundinertia`` kg·m², the
    least principal moment; then ``settotalmass`` kg (or None) scales every mass and inertia so
    that they sum to it (MuJoCo 4.0: bounds first, then the scale; checked against its compiled
    ``body_mass``)."""

    boundmass: float = 0.0
    boundinertia: float = 0.0
    settotalmass: float | None = None

    @property
    def any(self) -> bool:
        return self.boundmass > 0 or self.boundinertia > 0 or self.settotalmass is not None


@dataclass(frozen=True, eq=False)
class RobotModel:
    """A parsed description: ``format`` is "urdf", "sdf" or "mjcf"; ``data`` the file's bytes
    (write-back edits them); ``warnings`` concern the whole model; ``rules`` the compiler's
    changes to every inertial (MJCF)."""

    path: Path
    format: str
    links: tuple[Link, ...]
    data: bytes
    warnings: tuple[str, ...] = ()
    rules: MassRules = field(default_factory=MassRules)


def pick_source(source: str, collisions: list, visuals: list) -> str:
    """Which geometry elements make a link: ``source`` "collision" or "visual" as asked; "auto"
    takes the collision elements, or the visual ones for a link that has no collision element
    (what a user means for a link drawn but never collided)."""
    if source != "auto":
        return source
    return "visual" if not collisions and visuals else "collision"
