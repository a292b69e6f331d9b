"""One pass over a CAD shape's faces: their surface types and an upper bound of their area.

The area feeds only the ``input`` bar (modelling tolerance x area), which needs one or two
digits; integrating it with OpenCASCADE's Gauss rule cost more than the volume integral itself
(1.2-1.3x), so analytic faces take a closed form over their parameter box instead: the face's
trimmed domain lies inside the box of its boundary's parameters (``BRepTools::UVBounds``), so

    area = ∫∫_domain |S_u x S_v| du dv  <=  ∫∫_box |S_u x S_v| du dv,

exact for faces with natural bounds (a sphere, a torus, a drilled hole's wall) and at most a
few tens of per cent high on typical trimmed planes (a disc in its square: 4/π; the plate of
256 holes: 1.14). Free-form faces (B-spline, Bezier, revolution, extrusion, offset, other) have
no closed form: their area comes from our own rule where it integrates them, else from
OpenCASCADE's adaptive surface rule (`occ_area`).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterator
from types import SimpleNamespace
from typing import Any

from massprops.cad.occ import face_edges

__all__ = ["ANALYTIC_FACES", "basis_faces", "face_census", "fixed_rule_exact",
           "is_analytic", "occ_area"]

ANALYTIC_FACES = ("plane", "cylinder", "cone", "sphere", "torus")
"""Face types whose Gauss integration is exact to round-off."""

_GEOM_NAMES = {"Geom_Plane": "plane", "Geom_CylindricalSurface": "cylinder",
               "Geom_ConicalSurface": "cone", "Geom_SphericalSurface": "sphere",
               "Geom_ToroidalSurface": "torus", "Geom_BezierSurface": "bezier",
               "Geom_BSplineSurface": "bspline", "Geom_SurfaceOfRevolution": "revolution",
               "Geom_SurfaceOfLinearExtrusion": "extrusion", "Geom_OffsetSurface": "offset"}


@functools.cache
def _occ() -> SimpleNamespace:
    """The OpenCASCADE names used here, imported once (optional extra, loaded with the first
    CAD file; a per-call import costs as much as a small face's integral)."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepGProp import BRepGProp
    from OCP.BRepTools import BRepTools
    from OCP.collections import IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as ShapeMap
    from OCP.Geom import (
        Geom_Circle,
        Geom_Ellipse,
        Geom_Line,
        Geom_Plane,
        Geom_RectangularTrimmedSurface,
        Geom_TrimmedCurve,
    )
    from OCP.Geom2d import Geom2d_BSplineCurve, Geom2d_Line, Geom2d_TrimmedCurve
    from OCP.GProp import GProp_GProps
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
    from OCP.TopExp import TopExp, TopExp_Explorer
    from OCP.TopoDS import TopoDS

    return SimpleNamespace(BRep_Tool=BRep_Tool, BRepGProp=BRepGProp, BRepTools=BRepTools,
                           Trimmed=Geom_RectangularTrimmedSurface, GProp_GProps=GProp_GProps,
                           FACE=TopAbs_FACE, EDGE=TopAbs_EDGE, Explorer=TopExp_Explorer,
                           TopoDS=TopoDS, TrimmedCurve=Geom_TrimmedCurve,
                           Conics=(Geom_Line, Geom_Circle, Geom_Ellipse), Plane=Geom_Plane,
                           Line2d=Geom2d_Line, Trimmed2d=Geom2d_TrimmedCurve,
                           BSpline2d=Geom2d_BSplineCurve, Map=ShapeMap, TopExp=TopExp)


def basis_faces(shape: Any) -> Iterator[tuple[Any, Any]]:
    """(face, its surface with every rectangular trim taken off) for each face of ``shape``: the
    surface type decides how a face is integrated, the face's own bounds how far."""
    k = _occ()
    explorer = k.Explorer(shape, k.FACE)
    while explorer.More():
        face = k.TopoDS.Face(explorer.Current())
        surface = k.BRep_Tool.Surface_s(face)
        while isinstance(surface, k.Trimmed):
            surface = surface.BasisSurface()
        yield face, surface
        explorer.Next()


def face_census(shape: Any, free_area: bool = True) -> tuple[dict[str, int], float, list]:
    """({surface type: count}, an upper bound of the total face area, [free-form faces]) of
    ``shape``, lengths in its own unit; with ``free_area`` False the free-form faces' area is
    left out (the caller integrates them anyway: `massprops.cad.freeform`)."""
    k = _occ()
    faces: dict[str, int] = {}
    free = []
    area = 0.0
    for face, surface in basis_faces(shape):
        kind = _GEOM_NAMES.get(type(surface).__name__, "other")
        faces[kind] = faces.get(kind, 0) + 1
        if kind in ANALYTIC_FACES:
            area += _box_area(kind, surface, k.BRepTools.UVBounds_s(face))
        else:
            free.append(face)
            if free_area:
                area += occ_area([face])
    return faces, area, free


def occ_area(faces: list) -> float:
    """Σ |area| of the faces by OpenCASCADE's adaptive surface rule at 1e-6 (free-form faces:
    no closed form; its fixed rule leaves 0.16 % on a NURBS disc, the adaptive one ~1e-6, well
    inside the input bar's 1 % margin)."""
    k = _occ()
    total = 0.0
    for face in faces:
        props = k.GProp_GProps()
        k.BRepGProp.SurfaceProperties_s(face, props, 1e-6)
        total += abs(props.Mass())
    return total


def fixed_rule_exact(shape: Any, kinds: dict[str, int] | None = None) -> bool:
    """Whether OpenCASCADE's fixed Gauss rule integrates every face of ``shape`` to round-off:
    each face analytic, each edge a line, circle or ellipse (or degenerate), and each face
    other than a plane bounded by iso-lines of its parameters (its domain a union of
    rectangles). A plane bounded by a B-spline (an extruded spline profile's cap: 7.9e-7 off
    in inertia) or a cylinder's wall cut by an oblique plane (an ellipse, a sine in its
    parameters: 1.5e-9 off) it does not integrate exactly, and says nothing about it.
    kinds: the shape's face census when the caller has it (all planes: no face pass)."""
    k = _occ()
    edges = k.Map()
    k.TopExp.MapShapes_s(shape, k.EDGE, edges)   # each edge once (a box: 12, not 24 visits)
    for i in range(1, edges.Extent() + 1):
        curve = k.BRep_Tool.Curve_s(k.TopoDS.Edge(edges.FindKey(i)), 0.0, 0.0)
        if curve is None:   # a degenerate edge (a cone's apex, a sphere's pole): no curve
            continue
        while isinstance(curve, k.TrimmedCurve):
            curve = curve.BasisCurve()
        if not isinstance(curve, k.Conics):
            return False
    if kinds is not None and set(kinds) <= {"plane"}:
        return True
    for face, surface in basis_faces(shape):
        if isinstance(surface, k.Plane):
            continue
        if _GEOM_NAMES.get(type(surface).__name__) not in ANALYTIC_FACES:
            return False
        for edge in face_edges(face, degenerate=False):
            if not _iso_line(k, k.BRep_Tool.CurveOnSurface_s(edge, face, 0.0, 0.0)):
                return False
    return True


def _iso_line(k: SimpleNamespace, curve: Any) -> bool:
    """A parameter curve that is a segment of an iso-line, linearly parametrised: a line
    along u or v, or a degree-1 B-spline with its poles on one (as STEP stores a fillet's
    edge on its torus)."""
    while isinstance(curve, k.Trimmed2d):
        curve = curve.BasisCurve()
    if isinstance(curve, k.Line2d):
        direction = curve.Direction()
        return min(abs(direction.X()), abs(direction.Y())) <= 1e-12
    if isinstance(curve, k.BSpline2d) and curve.Degree() == 1 and not curve.IsRational():
        poles = [curve.Pole(i) for i in range(1, curve.NbPoles() + 1)]
        return (all(p.X() == poles[0].X() for p in poles)
                or all(p.Y() == poles[0].Y() for p in poles))
    return False


def is_analytic(face: Any) -> bool:
    """The face's surface is a plane, cylinder, cone, sphere or torus."""
    k = _occ()
    surface = k.BRep_Tool.Surface_s(face)
    while isinstance(surface, k.Trimmed):
        surface = surface.BasisSurface()
    return _GEOM_NAMES.get(type(surface).__name__, "other") in ANALYTIC_FACES


def _box_area(kind: str, surface: Any, bounds: tuple[float, float, float, float]) -> float:
    """∫∫ |S_u x S_v| du dv of an analytic surface over the parameter box (u1, u2, v1, v2)."""
    u1, u2, v1, v2 = bounds
    du, dv = u2 - u1, v2 - v1
    if kind == "plane":
        return du * dv
    if kind == "cylinder":
        return surface.Radius() * du * dv
    if kind == "sphere":   # |S_u x S_v| = r² cos v, v in [-π/2, π/2]
        return surface.Radius() ** 2 * du * abs(math.sin(v2) - math.sin(v1))
    if kind == "torus":    # r |R + r cos v|
        big, r = surface.MajorRadius(), surface.MinorRadius()
        if big >= r:
            return r * du * (big * dv + r * (math.sin(v2) - math.sin(v1)))
        return r * du * (abs(big) + r) * dv
    # cone: S = O + (R + v sin a)(cos u X + sin u Y) + v cos a Z, |S_u x S_v| = |R + v sin a|
    s = math.sin(surface.SemiAngle())
    f1, f2 = surface.RefRadius() + v1 * s, surface.RefRadius() + v2 * s
    if f1 * f2 >= 0:
        return du * abs(f1 + f2) / 2 * dv
    return du * (f1 * f1 + f2 * f2) / (2 * abs(s))
