"""``inspect --write-physics OUT``: a copy of a glTF asset with the ``KHR_physics_rigid_bodies``
motion (mass, centre of mass, principal moments and their orientation) on each mesh node.

Each node's motion is its mesh's mass properties in the mesh's own coordinates, which are the
node's space (the spec: the centre of mass "in node space"; the inertia rotated into it), so a
mesh several nodes share gives each the same motion. Nodes are independent bodies: a mesh node
below another gets its own motion, as the spec treats nested motions. A scaled mesh node (its
own or an ancestor's scale, or a matrix with scale or shear) is refused: the spec leaves open
whether a body's mass and inertia scale with its node, and the physical mesh would no longer be
the one whose volume was integrated. Density as ``inspect``: ``density`` for every mesh, or
``mass``, the asset's total, shared by volume (each node counted, as ``inspect`` of the whole
file counts each instance). A motion already on a node keeps its other keys (velocities,
``isKinematic``, ``gravityFactor``); its four mass keys are replaced. Every other byte of a GLB
after its JSON chunk is kept; relative URIs are rewritten when OUT is in another folder.
"""

from __future__ import annotations

import copy
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from massprops.errors import MeshFormatError, UsageError, setting_ref
from massprops.inspection.file import Inspection, inspect_mesh
from massprops.io.atomic import OutputKind, atomic_write, check_output
from massprops.io.gltf import asset_bytes, asset_mesh, mesh_nodes, read_asset, relocated_uris
from massprops.robot.write.elements import gltf_motion_object
from massprops.tolerances import GLTF_UNSCALED_ATOL

__all__ = ["EXTENSION", "NodeMotion", "physics_output", "write_physics"]

EXTENSION = "KHR_physics_rigid_bodies"
_GLTF = (".glb", ".gltf")


@dataclass(frozen=True)
class NodeMotion:
    """One mesh node's motion as written: ``node`` and ``mesh`` indices, the node's ``name``
    (None without one), ``motion`` (the four keys of `gltf_motion_object`: kg, m, kg·m², node
    space), the mesh inspection's ``warnings`` (on the first node of each mesh only)."""

    node: int
    mesh: int
    name: str | None
    motion: dict
    warnings: tuple[str, ...] = field(default=())

    def as_dict(self) -> dict:
        return {"node": self.node, "name": self.name, "mesh": self.mesh, "motion": self.motion}


def physics_output(source: str | os.PathLike[str]) -> OutputKind:
    """The output rule's `OutputKind` for ``--write-physics`` of ``source``: its own extension
    (.glb -> .glb, .gltf -> .gltf); UsageError if ``source`` is no glTF asset."""
    own = Path(os.fspath(source)).suffix.lower()
    if own not in _GLTF:
        raise UsageError(f"{source}: {setting_ref('write_physics')} writes a copy of a glTF "
                         f"asset (.glb or .gltf); this input is {own or 'without an extension'}")
    return OutputKind("a copy of the glTF asset", (own,), "write_physics")


def write_physics(source: str | os.PathLike[str], out: str | os.PathLike[str], *,
                  density: float | None = None, mass: float | None = None,
                  allow_open: bool = False, repairs=None,
                  force: bool = False) -> list[NodeMotion]:
    """Write ``out``: the asset at ``source`` with a motion on each mesh node (module
    docstring); the motions written, in node order. ``out`` passes the output rule first
    (`massprops.io.atomic`; never ``source``), then the asset is read and every mesh inspected
    (`inspect_mesh`: health, repairs, ``allow_open``); any failure writes nothing."""
    if density is not None and mass is not None:
        raise UsageError(f"give {setting_ref('density')} or {setting_ref('mass')}, not both")
    source, target = Path(os.fspath(source)), Path(os.fspath(out))
    check_output(target, physics_output(source), force=force, protect=[source])
    asset = read_asset(source)
    nodes = asset.list_of("nodes")
    found = mesh_nodes(asset)
    if not found:
        raise MeshFormatError(f"{source}: no node has a mesh; nothing to give a motion")
    for index, _, linear in found:  # every node's transform before any mesh is read
        _require_unscaled(source, index, nodes[index], linear)
        if "skin" in nodes[index]:
            raise MeshFormatError(f"{source}: node {index}{_named(nodes[index])} is skinned (its "
                                  "shape follows its joints); a rigid body cannot be")
    inspected: dict[int, Inspection] = {}
    for _, mesh_index, _ in found:
        if mesh_index not in inspected:
            name = f"{source}: mesh {mesh_index}{_named(asset.list_of('meshes')[mesh_index])}"
            inspected[mesh_index] = inspect_mesh(
                asset_mesh(asset, mesh_index, name), density=density, allow_open=allow_open,
                repairs=repairs)
    scale = 1.0
    if mass is not None:  # one density for all: the total over every node, instances counted
        scale = mass / sum(inspected[m].mass for _, m, _ in found)
    motions: list[NodeMotion] = []
    document = copy.deepcopy(asset.document)
    for index, mesh_index, _ in found:
        done = inspected[mesh_index]
        motion = gltf_motion_object(done.mass * scale, done.center_of_mass,
                                    np.asarray(done.inertia) * scale)
        node = document["nodes"][index]
        extensions = node.setdefault("extensions", {})
        physics = extensions.setdefault(EXTENSION, {})
        physics["motion"] = {**physics.get("motion", {}), **motion}
        name = node.get("name")
        first = all(m.mesh != mesh_index for m in motions)  # a mesh's warnings said once
        motions.append(NodeMotion(index, mesh_index, name if isinstance(name, str) else None,
                                  motion, done.warnings if first else ()))
    used = document.setdefault("extensionsUsed", [])
    if EXTENSION not in used:
        used.append(EXTENSION)
    document = relocated_uris(document, source.parent, target.parent)
    data = asset_bytes(asset, document)
    atomic_write(target, lambda stream: stream.write(data), overwrite=force)
    return motions


def _named(item: object) -> str:
    name = item.get("name") if isinstance(item, dict) else None
    return f" {name!r}" if isinstance(name, str) and name else ""


def _require_unscaled(source: Path, index: int, node: dict, linear: np.ndarray) -> None:
    gram = linear.T @ linear
    if np.all(np.isfinite(gram)) and np.abs(gram - np.eye(3)).max() <= GLTF_UNSCALED_ATOL:
        return
    scale = ", ".join(f"{s:.6g}" for s in np.sqrt(np.abs(np.diag(gram))))
    raise MeshFormatError(
        f"{source}: node {index}{_named(node)} is scaled (axes × {scale}, by its own transform "
        f"or an ancestor's); {EXTENSION} states a motion in node space and leaves scaled "
        "bodies undefined; apply the scale to the mesh's vertices first")
