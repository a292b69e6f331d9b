"""One CAD solid's unit-density moments about a local origin, with their error bars.

Method. The solid's GEOMETRY is translated (a copy: planes, axes and poles moved, not just a
location attached) so that the centre of its bounding box is the origin, and OpenCASCADE's
``BRepGProp`` integrates it there: every coordinate it sees is of the part's size, so the world
offset costs nothing (about the world origin a cylinder 1e7 sizes away comes out 11 % wrong).
The results are moved back in float64 (COM = origin + local COM; the inertia is already about
the COM) and converted to SI only now: scaling far-away coordinates first would round them.

Faces that are all analytic (plane, cylinder, cone, sphere, torus), with edges that are all
lines and conics and curved faces bounded by their parameter lines
(`massprops.cad.faces.fixed_rule_exact`), are integrated by the fixed Gauss rules, exact to
round-off: ``integration`` is None. Otherwise see `massprops.cad.freeform`: B-spline, Bezier,
revolution and extrusion faces whose domain is their parameter rectangle by our own
Gauss-Legendre rule per knot span, planes (and flat splines) by ours along their edges
(Green's theorem), each to round-off with a bar from two orders; the rest by OpenCASCADE's
adaptive rule at nested tolerances, with a bar from two levels (OpenCASCADE's own estimate is
never the bar).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import numpy as np

from massprops.cad.faces import ANALYTIC_FACES, face_census, fixed_rule_exact
from massprops.cad.freeform import integrate_free_form, occ_levels
from massprops.errors import DegenerateMeshError
from massprops.mesh.facesums import U
from massprops.mesh.integral import UnitMoments
from massprops.tolerances import CAD_ROUNDING_ULPS, MIN_VOLUME_TO_ERROR

__all__ = ["ANALYTIC_FACES", "SolidIntegral", "face_types", "integrate_solid", "localise"]


@dataclass(frozen=True, eq=False)
class SolidIntegral:
    """Unit density, SI. origin : (3,) m, the local origin. moments : volume m³, COM from the
    origin m, inertia m⁵ about the COM (file axes), with rounding bounds. integration : None
    (all faces analytic) or (volume m³, com (3,) m, inertia (3, 3) m⁵) bounds of the
    quadrature's remaining error. tolerance : the largest modelling tolerance of its faces,
    edges and vertices, m. area : m², an upper bound (see `massprops.cad.faces`). reach : (3,)
    m, the bounding box's half extents. faces : {type: count}. valid : OpenCASCADE's BRepCheck
    verdict for solids with free-form faces (None: not checked; for analytic solids the check
    would cost more than the integral). An invalid shape (seen: a torus converted to NURBS 1e11
    sizes from the origin) can integrate to anything, and the nested levels may agree on it.
    anchor : (3,) the local origin in the FILE unit, as the float the geometry was shifted by
    (``origin`` is that times the scale, rounded: a far part's COM is exact only as anchor +
    local COM, which `massprops.cad.write` moves by in two steps)."""

    origin: np.ndarray
    moments: UnitMoments
    integration: tuple[float, np.ndarray, np.ndarray] | None
    tolerance: float
    area: float
    reach: np.ndarray
    faces: dict[str, int]
    valid: bool | None = None
    method: str = "gauss"
    anchor: np.ndarray | None = None


def integrate_solid(shape: Any, scale: float, name: str, *, only_closed: bool = True
                    ) -> SolidIntegral:
    """Integrate one solid (an OCP TopoDS_Shape in the file unit; ``scale`` metres per unit).
    Raises DegenerateMeshError when it encloses no resolvable volume or is inside out."""
    k = _occ()
    local, origin, centre, half = localise(shape)
    reach = np.array(half)

    faces, area, free = face_census(local, free_area=False)
    tolerance = float(k.ShapeTolerance().Tolerance(local, 1, k.SHAPE))  # 1: the largest
    # analytic faces with a free-form edge, or curved ones trimmed off their parameter lines,
    # are not exact by the fixed rule either
    free_form = bool(free) or not fixed_rule_exact(local, faces)

    n = sum(faces.values())
    box_volume = 8 * half[0] * half[1] * half[2]
    integration, method = None, "gauss"
    if not free_form:
        volume, com, inertia = occ_levels(local, only_closed, True)[0]
    else:
        (volume, com, inertia), integration, method, free_area = integrate_free_form(
            local, only_closed, centre if not origin.any() else (0.0, 0.0, 0.0))
        area += free_area

    ulps = CAD_ROUNDING_ULPS * max(n, 1) * U
    volume_err = ulps * box_volume
    if volume == 0 or abs(volume) < MIN_VOLUME_TO_ERROR * volume_err:
        raise DegenerateMeshError(f"{name}: encloses no volume we can resolve ({volume:.3g} "
                                  "file units³); check that it is a solid, not a sheet")
    if volume < 0:
        raise DegenerateMeshError(f"{name}: is inside out (volume {volume:.6g}); reverse the "
                                  "solid's orientation in the CAD tool")
    com_err = ulps * box_volume / volume * reach + 2 * U * np.abs(com)
    inertia_err = np.full((3, 3), ulps * box_volume * (half[0]**2 + half[1]**2 + half[2]**2))

    valid = None
    if free_form:
        valid = bool(k.BRepCheck_Analyzer(local).IsValid())
    s = scale
    moments = UnitMoments(volume * s**3, volume_err * s**3, com * s, com_err * s,
                          inertia * s**5, inertia_err * s**5)
    if integration is not None:
        integration = (integration[0] * s**3, integration[1] * s, integration[2] * s**5)
    return SolidIntegral(origin * s, moments, integration, tolerance * s, area * s * s,
                         reach * s, faces, valid, method, origin)


def localise(shape: Any) -> tuple[Any, np.ndarray, tuple, tuple]:
    """(the shape with its geometry translated so that its bounding box's centre is the origin
    (the shape itself when the world origin is already within its own size), the origin (3,),
    the box's centre and half extents), all in the file frame and unit."""
    k = _occ()
    box = k.Bnd_Box()
    k.BRepBndLib.Add_s(shape, box, False)   # the geometry's box, not padded by tolerances
    # plain floats: numpy's per-call cost on 3-vectors adds up to a tenth of a small part's
    # integral
    lo, hi = box.CornerMin(), box.CornerMax()
    x0, y0, z0, x1, y1, z1 = lo.X(), lo.Y(), lo.Z(), hi.X(), hi.Y(), hi.Z()
    centre = ((x0 + x1) / 2, (y0 + y1) / 2, (z0 + z1) / 2)
    half = ((x1 - x0) / 2, (y1 - y0) / 2, (z1 - z0) / 2)
    if max(map(abs, centre)) <= max(half):
        # the world origin is already within the part's own size of it: integrating there
        # loses at most a few ulps more, and the copy would cost as much as the integral
        return shape, np.zeros(3), centre, half
    trsf = k.gp_Trsf()
    trsf.SetTranslation(k.gp_Vec(-centre[0], -centre[1], -centre[2]))
    # the placement goes INTO the geometry with the shift: left as a location, BRepGProp
    # would add it back to every point of geometry shifted by -origin (a far part: 20 %
    # wrong)
    placement = shape.Location()
    if not placement.IsIdentity():
        trsf = trsf.Multiplied(placement.Transformation())
        shape = shape.Located(k.TopLoc_Location())
    local = k.BRepBuilderAPI_Transform(shape, trsf, True).Shape()
    return local, np.array(centre), centre, half


def face_types(shape: Any) -> dict[str, int]:
    """{surface type: number of faces} of a shape."""
    return face_census(shape)[0]


@functools.cache
def _occ() -> SimpleNamespace:
    """The OpenCASCADE names used here, imported once (optional extra, loaded with the first
    CAD file; importing them on every call cost ~0.1 ms, a third of a small part's integral)."""
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
    from OCP.BRepCheck import BRepCheck_Analyzer
    from OCP.gp import gp_Trsf, gp_Vec
    from OCP.ShapeAnalysis import ShapeAnalysis_ShapeTolerance
    from OCP.TopAbs import TopAbs_SHAPE
    from OCP.TopLoc import TopLoc_Location

    return SimpleNamespace(Bnd_Box=Bnd_Box, BRepBndLib=BRepBndLib,
                           BRepBuilderAPI_Transform=BRepBuilderAPI_Transform,
                           BRepCheck_Analyzer=BRepCheck_Analyzer,
                           gp_Trsf=gp_Trsf, gp_Vec=gp_Vec,
                           ShapeTolerance=ShapeAnalysis_ShapeTolerance, SHAPE=TopAbs_SHAPE,
                           TopLoc_Location=TopLoc_Location)
