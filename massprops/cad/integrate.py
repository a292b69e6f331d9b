"""One CAD solid's unit-density moments about a local origin, with their error bars.

Method. The solid's GEOMETRY is translated (a copy: planes, axes and poles moved, not just a
location attached) so that the centre of its bounding box is the origin, and OpenCASCADE's
``BRepGProp`` integrates it there: every coordinate it sees is of the part's size, so the world
offset costs nothing (about the world origin a cylinder 1e7 sizes away comes out 11 % wrong).
The results are moved back in float64 (COM = origin + local COM; the inertia is already about
the COM) and converted to SI only now: scaling far-away coordinates first would round them.

Faces that are all analytic (plane, cylinder, cone, sphere, torus) are integrated by the fixed
Gauss rules, exact to round-off: ``integration`` is None. With any free-form face (B-spline,
Bezier, revolution, extrusion, offset, other), the adaptive rule runs at the nested tolerances
``CAD_ADAPTIVE_EPS``; the last result is reported and the bar is ``CAD_INTEGRATION_SAFETY``
times its difference from the level before (OpenCASCADE's own estimate is not trusted).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from massprops.errors import DegenerateMeshError
from massprops.mesh.facesums import U
from massprops.mesh.integral import UnitMoments
from massprops.tolerances import (
    CAD_ADAPTIVE_EPS,
    CAD_ADAPTIVE_FALLBACK_EPS,
    CAD_INTEGRATION_SAFETY,
    CAD_ROUNDING_ULPS,
    MIN_VOLUME_TO_ERROR,
)

__all__ = ["ANALYTIC_FACES", "SolidIntegral", "integrate_solid"]

ANALYTIC_FACES = ("plane", "cylinder", "cone", "sphere", "torus")
"""Face types whose Gauss integration is exact to round-off."""


@dataclass(frozen=True, eq=False)
class SolidIntegral:
    """Unit density, SI. origin : (3,) m, the local origin. moments : volume m³, COM from the
    origin m, inertia m⁵ about the COM (file axes), with rounding bounds. integration : None
    (all faces analytic) or (volume m³, com (3,) m, inertia (3, 3) m⁵) bounds of the
    quadrature's remaining error. tolerance : the largest modelling tolerance of its faces,
    edges and vertices, m. area : m². reach : (3,) m, the bounding box's half extents.
    faces : {type: count}. valid : OpenCASCADE's BRepCheck verdict for solids with free-form
    faces (None: not checked; for analytic solids the check would cost more than the
    integral). An invalid shape (seen: a torus converted to NURBS 1e11 sizes from the origin)
    can integrate to anything, and the nested levels may agree on it."""

    origin: np.ndarray
    moments: UnitMoments
    integration: tuple[float, np.ndarray, np.ndarray] | None
    tolerance: float
    area: float
    reach: np.ndarray
    faces: dict[str, int]
    valid: bool | None = None


def integrate_solid(shape: Any, scale: float, name: str, *, only_closed: bool = True
                    ) -> SolidIntegral:
    """Integrate one solid (an OCP TopoDS_Shape in the file unit; ``scale`` metres per unit).
    Raises DegenerateMeshError when it encloses no resolvable volume or is inside out."""
    # optional extra: OCP is imported only once a CAD file is read
    from OCP.Bnd import Bnd_Box
    from OCP.BRepBndLib import BRepBndLib
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
    from OCP.BRepGProp import BRepGProp
    from OCP.gp import gp_Trsf, gp_Vec
    from OCP.GProp import GProp_GProps
    from OCP.TopLoc import TopLoc_Location

    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box, False)   # the geometry's box, not padded by tolerances
    lo, hi = _corner(box.CornerMin()), _corner(box.CornerMax())
    origin = (lo + hi) / 2
    reach = (hi - lo) / 2
    if np.max(np.abs(origin)) <= np.max(reach):
        # the world origin is already within the part's own size of it: integrating there
        # loses at most a few ulps more, and the copy would cost as much as the integral
        origin = np.zeros(3)
        local = shape
    else:
        trsf = gp_Trsf()
        trsf.SetTranslation(gp_Vec(*(-origin)))
        # the placement goes INTO the geometry with the shift: left as a location, BRepGProp
        # would add it back to every point of geometry shifted by -origin (a far part: 20 %
        # wrong)
        placement = shape.Location()
        if not placement.IsIdentity():
            trsf = trsf.Multiplied(placement.Transformation())
            shape = shape.Located(TopLoc_Location())
        local = BRepBuilderAPI_Transform(shape, trsf, True).Shape()

    faces, tolerance = _faces_and_tolerance(local)
    free_form = any(kind not in ANALYTIC_FACES for kind in faces)
    surface = GProp_GProps()
    BRepGProp.SurfaceProperties_s(local, surface)
    area = surface.Mass()

    levels = []
    if not free_form:
        props = GProp_GProps()
        BRepGProp.VolumeProperties_s(local, props, only_closed)
        levels.append(_values(props))
    else:
        for eps in CAD_ADAPTIVE_EPS:
            props = GProp_GProps()
            BRepGProp.VolumeProperties_s(local, props, eps, only_closed)
            levels.append(_values(props))
        if levels[-1][0] == levels[-2][0]:
            props = GProp_GProps()
            BRepGProp.VolumeProperties_s(local, props, CAD_ADAPTIVE_FALLBACK_EPS, only_closed)
            levels.insert(0, _values(props))
    volume, com, inertia = levels[-1]

    n = sum(faces.values())
    k = CAD_ROUNDING_ULPS * max(n, 1) * U
    box_volume = float(np.prod(2 * reach))
    volume_err = k * box_volume
    if volume == 0 or abs(volume) < MIN_VOLUME_TO_ERROR * volume_err:
        raise DegenerateMeshError(f"{name}: encloses no volume we can resolve ({volume:.3g} "
                                  "file units³); check that it is a solid, not a sheet")
    if volume < 0:
        raise DegenerateMeshError(f"{name}: is inside out (volume {volume:.6g}); reverse the "
                                  "solid's orientation in the CAD tool")
    com_err = k * box_volume / volume * reach + 2 * U * np.abs(com)
    inertia_err = np.full((3, 3), k * box_volume * float(reach @ reach))

    integration, valid = None, None
    if free_form:
        integration = _integration_bar(levels)
        from OCP.BRepCheck import BRepCheck_Analyzer  # optional extra

        valid = bool(BRepCheck_Analyzer(local).IsValid())
    s = scale
    moments = UnitMoments(volume * s**3, volume_err * s**3, com * s, com_err * s,
                          inertia * s**5, inertia_err * s**5)
    if integration is not None:
        integration = (integration[0] * s**3, integration[1] * s, integration[2] * s**5)
    return SolidIntegral(origin * s, moments, integration, tolerance * s, area * s * s,
                         reach * s, faces, valid)


def _integration_bar(levels: list) -> tuple[float, np.ndarray, np.ndarray]:
    """CAD_INTEGRATION_SAFETY x the last difference between nested levels; a last difference
    of exactly zero (both at the rule's floor) falls back on the one before."""
    bars = []
    for (v0, c0, j0), (v1, c1, j1) in zip(levels[:-1], levels[1:]):
        bars.append((abs(v1 - v0), np.abs(c1 - c0), np.abs(j1 - j0)))
    volume, com, inertia = bars[-1]
    if volume == 0 and len(bars) > 1:
        volume, com, inertia = bars[-2]
    f = CAD_INTEGRATION_SAFETY
    # the results themselves carry round-off: a bar never below a few ulps of the value
    v_last, c_last, j_last = levels[-1]
    return (f * volume + 4 * U * abs(v_last), f * com + 4 * U * np.abs(c_last),
            f * inertia + 4 * U * np.abs(j_last))


def _values(props: Any) -> tuple[float, np.ndarray, np.ndarray]:
    """(volume, COM, inertia about the COM) of a GProp_GProps, unit density, file unit."""
    c = props.CentreOfMass()
    m = props.MatrixOfInertia()
    j = np.array([[m.Value(i, k) for k in (1, 2, 3)] for i in (1, 2, 3)])
    return props.Mass(), np.array([c.X(), c.Y(), c.Z()]), 0.5 * (j + j.T)


def _corner(p: Any) -> np.ndarray:
    return np.array([p.X(), p.Y(), p.Z()])


_SURFACE_NAMES = {"GeomAbs_Plane": "plane", "GeomAbs_Cylinder": "cylinder",
                  "GeomAbs_Cone": "cone", "GeomAbs_Sphere": "sphere", "GeomAbs_Torus": "torus",
                  "GeomAbs_BezierSurface": "bezier", "GeomAbs_BSplineSurface": "bspline",
                  "GeomAbs_SurfaceOfRevolution": "revolution",
                  "GeomAbs_SurfaceOfExtrusion": "extrusion", "GeomAbs_OffsetSurface": "offset"}


def face_types(shape: Any) -> dict[str, int]:
    """{surface type: number of faces} of a shape."""
    return _faces_and_tolerance(shape)[0]


def _faces_and_tolerance(shape: Any) -> tuple[dict[str, int], float]:
    """({surface type: count}, the largest face/edge/vertex tolerance) in the file unit."""
    from OCP.BRepAdaptor import BRepAdaptor_Surface  # optional extra
    from OCP.ShapeAnalysis import ShapeAnalysis_ShapeTolerance
    from OCP.TopAbs import TopAbs_FACE, TopAbs_SHAPE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    counts: dict[Any, int] = {}
    explorer = TopExp_Explorer(shape, TopAbs_FACE)
    while explorer.More():
        kind = BRepAdaptor_Surface(TopoDS.Face(explorer.Current()), False).GetType()
        counts[kind] = counts.get(kind, 0) + 1
        explorer.Next()
    faces: dict[str, int] = {}
    for kind, n in counts.items():
        name = _SURFACE_NAMES.get(kind.name, "other")
        faces[name] = faces.get(name, 0) + n
    tolerance = ShapeAnalysis_ShapeTolerance().Tolerance(shape, 1, TopAbs_SHAPE)  # 1: largest
    return faces, float(tolerance)
