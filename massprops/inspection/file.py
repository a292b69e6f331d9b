"""One mesh from file to mass properties: read, check health, integrate. The CLI's single entry."""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, BinaryIO, cast

# numpy first, before the readers' package: imported from inside massprops.io's initialisation
# under the CLI, numpy's own typing modules took ~13 ms longer and `python -m massprops inspect`
# ~30 ms longer (measured, docs/performance.md; the cause inside numpy was not found)
import numpy  # noqa: F401

from massprops.errors import MassPropsError
from massprops.io import read_mesh
from massprops.mesh import Mesh
from massprops.mesh.health import MeshHealth, prepare_mesh
from massprops.mesh.integral import MassProperties, check_coordinate_scale, mass_properties
from massprops.parallel import in_background

if TYPE_CHECKING:
    from massprops.repair import RepairOptions

OVERLAP_TRIANGLES = 1 << 15
"""From this many triangles on, the integral starts on a second thread beside the health checks:
most meshes pass them unchanged, and then its result is the one a later call would give."""


@dataclass(frozen=True, eq=False)
class Inspection:
    """What `massprops inspect` reports for one mesh.

    mesh : the mesh that was integrated (flipped or re-wound where health said so; capped or
        united by a repair; for ``--shell``, the wall's mid-surface).
    health : topology report of the mesh as read (see `massprops.repair.pipeline` for what a
        repair reports), with its warnings.
    properties : mass properties about the centre of mass, mesh axes, SI units.
    repairs : None unless a repair ran: {"fill_holes" | "union" | "shell": record}, each record
        with ``as_dict()`` (the ``repairs`` JSON object).
    """

    mesh: Mesh
    health: MeshHealth
    properties: MassProperties
    repairs: dict | None = None

    @property
    def warnings(self) -> tuple[str, ...]:
        return tuple(self.health.warnings)

    # the numbers, read straight off the result (units and frames: `MassProperties`)
    volume = property(lambda self: self.properties.volume, doc="m³")
    mass = property(lambda self: self.properties.mass, doc="kg")
    density = property(lambda self: self.properties.density, doc="kg/m³")
    center_of_mass = property(lambda self: self.properties.center_of_mass, doc="(3,) m, mesh frame")
    inertia = property(lambda self: self.properties.inertia,
                       doc="(3, 3) kg·m², about the centre of mass, mesh axes")
    principal_moments = property(lambda self: self.properties.principal_moments,
                                 doc="(3,) kg·m², ascending")
    principal_axes = property(lambda self: self.properties.principal_axes,
                              doc="(3, 3): columns, a proper rotation, J = R diag(moments) Rᵀ")
    uncertainty = property(lambda self: self.properties.uncertainty,
                           doc="the error bars (rounding, input, repair)")

    def repairs_as_dict(self) -> dict | None:
        """The contract's ``repairs`` object: the health check's weld of round-off cracks and
        the repairs asked for, each by its name; None when nothing was repaired."""
        repairs = {} if self.health.weld is None else {"weld": self.health.weld}
        repairs.update(self.repairs or {})
        return {key: record.as_dict() for key, record in repairs.items()} or None

    def as_dict(self) -> dict:
        """The contract's JSON object for `inspect --json`."""
        out: dict[str, Any] = {"file": self.mesh.name}
        out.update(self.properties.as_dict())
        out["mesh"] = self.health.as_dict()
        repairs = self.repairs_as_dict()
        if repairs is not None:
            out["repairs"] = repairs
        out["warnings"] = list(self.warnings)
        return out


def inspect_mesh(mesh: Mesh, *, density: float | None = None, mass: float | None = None,
                 allow_open: bool = False, repairs: RepairOptions | None = None) -> Inspection:
    """Health-check ``mesh`` and integrate its mass properties (density default 1 kg/m³).

    Coordinates too large for float64 mass properties are refused first (before any product
    overflows); then the errors of the health checks; the integral's own errors (a usage error
    in density or mass, a degenerate volume) only for a mesh that passed them. ``repairs``: what
    to repair first (`massprops.repair`); none asked, the repair code is never imported.
    """
    check_coordinate_scale(mesh)
    if repairs is not None and repairs.any:
        from massprops.repair.pipeline import repair_and_integrate  # deferred: repairs only

        done = repair_and_integrate(mesh, repairs, density=density, mass=mass,
                                    allow_open=allow_open)
        return Inspection(done.mesh, done.health, done.properties, done.repairs)
    if mesh.faces.shape[0] < OVERLAP_TRIANGLES:
        fixed, health = prepare_mesh(mesh, allow_open=allow_open)
        return Inspection(fixed, health, mass_properties(fixed, density=density, mass=mass))
    early = in_background(_outcome, mesh, density, mass)
    try:
        fixed, health = prepare_mesh(mesh, allow_open=allow_open)
    finally:
        properties, error = early()  # also on failure: no thread outlives the call
    if fixed is not mesh:  # flipped or re-wound: the early integral is of the wrong surface
        properties, error = _outcome(fixed, density, mass)
    if error is not None:
        raise error
    # _outcome gives the properties whenever it gives no error
    return Inspection(fixed, health, cast(MassProperties, properties))


def inspect_file(source: str | os.PathLike | BinaryIO, *, format: str | None = None,
                 unit: str = "m", name: str | None = None, density: float | None = None,
                 mass: float | None = None, allow_open: bool = False,
                 repairs: RepairOptions | None = None) -> Inspection:
    """Read a mesh file (or binary stream, with ``format``) and inspect it; see `inspect_mesh`."""
    mesh = read_mesh(source, format=format, unit=unit, name=name)
    return inspect_mesh(mesh, density=density, mass=mass, allow_open=allow_open, repairs=repairs)


def _outcome(mesh: Mesh, density: float | None, mass: float | None
             ) -> tuple[MassProperties | None, MassPropsError | None]:
    """(mass_properties(mesh), None), or (None, the library error it raised) to raise later."""
    try:
        return mass_properties(mesh, density=density, mass=mass), None
    except MassPropsError as exc:
        return None, exc
