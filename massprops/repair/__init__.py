"""Repairs: the solid (or wall) a user means when a mesh is not one clean, closed solid.

Three modes, each changing what is integrated and each with its share of the error bar
(``uncertainty.repair``) and a record for the ``repairs`` JSON object:

- ``fill_holes`` (`holes`): cap every boundary loop with a triangulation that keeps its shape;
  the bar covers every reasonable cap. Loops too large to be holes are refused.
- ``union`` (`union`): replace overlapping and nested pieces by the solid they occupy together
  (manifold3d); the bar covers the boolean's rounding, measured on its result.
- ``shell`` (`shell`): the surface as a wall of the given thickness (metres), open or closed;
  the bar covers the thin-wall model. It replaces the solid integral.

Combined, they run in that order: holes are capped first (a union needs closed pieces), then
the pieces are united, then the surface (capped, united) is taken as a wall. `pipeline` runs
them; `bars` turns "volume that may be misplaced, and where" into error bars; `topology` and
`triangulate` are what the modes share. Nothing here is imported on the default path.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class RepairOptions:
    """What to repair. union : unite pieces. shell : wall thickness in metres (None: a solid).
    fill_holes : cap holes. max_hole : with fill_holes, the largest cap accepted as a fraction
    of the surface area (None: ``tolerances.MAX_HOLE_AREA_FRACTION``)."""

    union: bool = False
    shell: float | None = None
    fill_holes: bool = False
    max_hole: float | None = None

    @property
    def any(self) -> bool:
        return self.union or self.shell is not None or self.fill_holes


__all__ = ["RepairOptions"]
