"""One mesh from file to mass properties: read, check health, integrate. The CLI's single entry."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import BinaryIO

from massprops.health import MeshHealth, prepare_mesh
from massprops.io import read_mesh
from massprops.mass import MassProperties, mass_properties
from massprops.mesh import Mesh


@dataclass(frozen=True, eq=False)
class Inspection:
    """What `massprops inspect` reports for one mesh.

    mesh : the mesh that was integrated (flipped or re-wound where health said so).
    health : topology report of the mesh as read, with its warnings.
    properties : mass properties about the centre of mass, mesh axes, SI units.
    """

    mesh: Mesh
    health: MeshHealth
    properties: MassProperties

    @property
    def warnings(self) -> tuple[str, ...]:
        return tuple(self.health.warnings)

    def as_dict(self) -> dict:
        """The contract's JSON object for `inspect --json`."""
        out = {"file": self.mesh.name}
        out.update(self.properties.as_dict())
        out["mesh"] = self.health.as_dict()
        out["warnings"] = list(self.warnings)
        return out


def inspect_mesh(mesh: Mesh, *, density: float | None = None, mass: float | None = None,
                 allow_open: bool = False) -> Inspection:
    """Health-check ``mesh`` and integrate its mass properties (density default 1 kg/m³)."""
    fixed, health = prepare_mesh(mesh, allow_open=allow_open)
    return Inspection(fixed, health, mass_properties(fixed, density=density, mass=mass))


def inspect_file(source: str | os.PathLike | BinaryIO, *, format: str | None = None,
                 unit: str = "m", name: str | None = None, density: float | None = None,
                 mass: float | None = None, allow_open: bool = False) -> Inspection:
    """Read a mesh file (or binary stream, with ``format``) and inspect it; see `inspect_mesh`."""
    mesh = read_mesh(source, format=format, unit=unit, name=name)
    return inspect_mesh(mesh, density=density, mass=mass, allow_open=allow_open)
