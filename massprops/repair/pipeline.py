"""The repairs in their order (fill holes, unite, take as a wall), from a mesh as read to its
mass properties, health (with the warnings) and records."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import cast

from massprops.mesh import Mesh
from massprops.mesh.health import MeshHealth, check_mesh, close_cracks, prepare_mesh
from massprops.mesh.integral import MassProperties, check_density_mass, mass_properties
from massprops.repair import RepairOptions
from massprops.repair.bars import Regions, moment_bounds, with_repair_bar


@dataclass(frozen=True, eq=False)
class Repaired:
    """mesh : what was integrated (capped, united; for a shell, the mid-surface). health : of the
    mesh before the union (after capping; for a shell, as read, no repairs), its warnings those
    of the health check (none for a shell: a wall need not be closed) then the repairs'.
    properties : with ``uncertainty.repair``. repairs : {"fill_holes": ..., "union": ...,
    "shell": ...} records (``as_dict()`` each), only the modes that ran."""

    mesh: Mesh
    health: MeshHealth
    properties: MassProperties
    repairs: dict


def repair_and_integrate(mesh: Mesh, options: RepairOptions, *, density: float | None = None,
                         mass: float | None = None, allow_open: bool = False) -> Repaired:
    """Run the repairs ``options`` names on ``mesh`` and integrate the result."""
    check_density_mass(density, mass)  # a usage error before any expensive work
    records: dict = {}
    warnings: list[str] = []
    solid = Regions.none()
    holes = None
    crack_notes: list[str] = []
    if options.fill_holes:
        # deferred: each repair loads only when asked for
        from massprops.repair.holes import fill_holes

        # round-off cracks are welded, not capped: only the real holes are left to fill
        mesh, weld, crack_notes = close_cracks(mesh)
        if weld is not None:
            records["weld"] = weld
        holes = fill_holes(mesh, max_fraction=options.max_hole, allow_open=allow_open)
        mesh = holes.mesh
        records["fill_holes"] = holes.record
        solid = holes.regions
    union = None
    if options.union:
        # deferred: each repair loads only when asked for
        from massprops.repair.union import union_mesh

        fixed, health = prepare_mesh(mesh, allow_open=allow_open, unioned=True)
        union = union_mesh(fixed)
        mesh = union.mesh
        solid = Regions.join(solid, union.regions)
    elif options.shell is None:
        mesh, health = prepare_mesh(mesh, allow_open=allow_open)
    else:
        health = check_mesh(mesh)
    if options.shell is not None:
        # deferred: each repair loads only when asked for
        from massprops.repair.shell import shell_properties

        united = mass_properties(mesh).volume if options.union else None
        shell = shell_properties(mesh, options.shell, density=density, mass=mass)
        props = shell.properties
        if holes is not None:
            props = with_repair_bar(props, moment_bounds(holes.wall_regions(options.shell), props,
                                                         mass_given=mass is not None))
        records["shell"] = shell.record
        warnings += shell.warnings
        if options.union:
            warnings = list(health.warnings) + warnings
    else:
        props = mass_properties(mesh, density=density, mass=mass)
        if solid.volume.size:
            props = with_repair_bar(props, moment_bounds(solid, props, mass_given=mass is not None))
        warnings = list(health.warnings)
    if holes is not None:
        warnings += holes.warnings
    if union is not None:
        # deferred: each repair loads only when asked for
        from massprops.repair.union import finished

        # a union with a shell: united was measured (options.union)
        volume = cast(float, united) if options.shell is not None else props.volume
        records["union"] = finished(union.record, volume)
        warnings += union.warnings
    health = dataclasses.replace(health, warnings=tuple(crack_notes + warnings))
    return Repaired(mesh, health, props, {k: records[k] for k in
                                          ("weld", "fill_holes", "union", "shell") if k in records})
