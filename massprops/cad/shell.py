"""``--shell T`` on CAD surfaces: the faces as the mid-surface of a wall of thickness T.

The model is the mesh path's (`massprops.repair.shell`, decision 0010) on the exact surface:
every surface element extruded T/2 to each side along its normal, so per unit density

    V = T A,   ∫x dV = T ∫x dA,   ∫x xᵀ dV = T ∫x xᵀ dA + T³/12 ∫n nᵀ dA,

with A, ∫x dA, ∫x xᵀ dA from OpenCASCADE's surface Gauss rule (exact to round-off on analytic
faces) about the local origin, and ∫n nᵀ dA exact for planes (A n nᵀ), spheres (n = (x-c)/R)
and cylinders (n = P(x-c)/r, P the projection across the axis); on cones and tori it is bounded
(0 <= ∫n_i² <= A, |∫n_i n_j| <= A/2) and the bound joins the model bar.

The model bar (``uncertainty.repair``) holds what the model cannot know, against the wall
whose points lie within T/2 of the surface along its normal:
- curvature: there the volume element is (1 - 2Hs + Ks²) ds dA, not ds dA; with κ the face's
  largest principal curvature (|H| <= κ, |K| <= κ²) and the odd terms in s cancelling, per
  moment: volume κ² T³/12 A, first moments T³/12 A (2κ + κ² r), second moments
  T³/12 A (4κ r + κ² r²) + κ² T⁵/80 A, r the reach from the origin plus T;
- joins: where two faces meet at an angle θ (sampled along the edge), the prisms leave a gap on
  one side and overlap on the other, two kites of width (T/2) tan(θ/2) (at most T: a fold)
  along the edge's length L, volume 2 (T/2) w L each at distance <= r; free edges are cut
  square (a sheet's rim), seams and tangent joins cost nothing. A mitred wall (the mesh path)
  would correct the moments there; here the whole region goes to the bar.
Free-form faces have no closed-form curvature bound: refused (tessellate them first).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

import numpy as np

from massprops.cad.faces import basis_faces, face_census
from massprops.cad.integrate import SolidIntegral, localise
from massprops.errors import DegenerateMeshError, UsageError, setting_ref
from massprops.mesh.facesums import U
from massprops.mesh.integral import Uncertainty, UnitMoments
from massprops.tolerances import CAD_ROUNDING_ULPS

__all__ = ["ShellIntegral", "integrate_shell", "shell_solid"]

MODEL = "mid-surface wall, faces extruded by T/2 each side along their normal"


@dataclass(frozen=True, eq=False)
class ShellIntegral:
    """Per unit density, file unit (the caller scales): volume, first (3,) ∫x dV, second
    (3, 3) ∫x xᵀ dV about the local origin; their model bars; area; the count of joins that
    turn (with a kite region) and of folds (θ so sharp the kite is capped)."""

    volume: float
    first: np.ndarray
    second: np.ndarray
    bar_volume: float
    bar_first: np.ndarray
    bar_second: np.ndarray
    area: float
    turning_edges: int
    folded_edges: int


@functools.cache
def _occ() -> SimpleNamespace:
    """OpenCASCADE names used here (optional extra, imported once with the first CAD file)."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Curve2d, BRepAdaptor_Surface
    from OCP.BRepGProp import BRepGProp
    from OCP.BRepLProp import BRepLProp_SLProps
    from OCP.BRepTools import BRepTools
    from OCP.collections import (
        IndexedDataMap_TopoDS_Shape_List_TopoDS_Shape_TopTools_ShapeMapHasher as EdgeFaces,
    )
    from OCP.GCPnts import GCPnts_AbscissaPoint
    from OCP.Geom import Geom_RectangularTrimmedSurface
    from OCP.GProp import GProp_GProps
    from OCP.ShapeAnalysis import ShapeAnalysis_ShapeTolerance
    from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_REVERSED, TopAbs_SHAPE
    from OCP.TopExp import TopExp, TopExp_Explorer
    from OCP.TopoDS import TopoDS

    return SimpleNamespace(
        BRep_Tool=BRep_Tool, BRepAdaptor_Curve=BRepAdaptor_Curve,
        BRepAdaptor_Curve2d=BRepAdaptor_Curve2d, BRepAdaptor_Surface=BRepAdaptor_Surface,
        BRepGProp=BRepGProp, BRepLProp_SLProps=BRepLProp_SLProps, BRepTools=BRepTools,
        GCPnts_AbscissaPoint=GCPnts_AbscissaPoint,
        Geom_RectangularTrimmedSurface=Geom_RectangularTrimmedSurface, GProp_GProps=GProp_GProps,
        TopAbs_EDGE=TopAbs_EDGE, TopAbs_FACE=TopAbs_FACE, TopAbs_REVERSED=TopAbs_REVERSED,
        TopAbs_SHAPE=TopAbs_SHAPE, ShapeTolerance=ShapeAnalysis_ShapeTolerance,
        TopExp=TopExp, TopExp_Explorer=TopExp_Explorer, TopoDS=TopoDS,
        EdgeFaces=EdgeFaces)


def integrate_shell(local: Any, thickness: float, name: str) -> ShellIntegral:
    """The wall of ``thickness`` (file unit) on the faces of ``local`` (file unit, about its
    own origin). Raises UsageError for a free-form face."""
    k = _occ()
    t = thickness
    area, first, second, nn = 0.0, np.zeros(3), np.zeros((3, 3)), np.zeros((3, 3))
    nn_bar = 0.0
    curvature = np.zeros(2)   # Σ A κ², Σ A κ
    for face, surface in basis_faces(local):
        kind = type(surface).__name__
        props = k.GProp_GProps()
        k.BRepGProp.SurfaceProperties_s(face, props)
        a = props.Mass()
        c = props.CentreOfMass()
        c = np.array([c.X(), c.Y(), c.Z()])
        m = props.MatrixOfInertia()
        j = np.array([[m.Value(i, q) for q in (1, 2, 3)] for i in (1, 2, 3)])
        q_c = np.trace(j) / 2 * np.eye(3) - j               # ∫(x-c)(x-c)ᵀ dA
        area += a
        first += a * c
        second += q_c + a * np.outer(c, c)
        kappa, face_nn, bounded = _normals(kind, surface, face, a, c, q_c, t)
        if face_nn is None:
            raise UsageError(f"{name}: {setting_ref('shell')} on CAD faces takes planes, "
                             f"cylinders, cones, spheres and tori; this part has a "
                             f"{kind.removeprefix('Geom_')} face: tessellate it first "
                             "(massprops align IN.step OUT.stl, then inspect OUT.stl with "
                             f"{setting_ref('shell')})")
        nn += face_nn
        nn_bar += a if bounded else 0.0
        curvature += a * np.array([kappa * kappa, kappa])
    joins, turning, folded = _joins(local, t)
    return ShellIntegral(t * area, t * first, t * second + t**3 / 12 * nn,
                         *_model_bar(local, t, curvature, nn_bar, joins), area, turning,
                         folded)


def _normals(kind: str, surface: Any, face: Any, a: float, c: np.ndarray, q_c: np.ndarray,
             t: float) -> tuple[float, np.ndarray | None, bool]:
    """(largest principal curvature, ∫n nᵀ dA or None (free-form), whether that is only a
    bound (A/3 I, the bar taking A))."""
    if kind == "Geom_Plane":
        d = surface.Axis().Direction()
        n = np.array([d.X(), d.Y(), d.Z()])
        return 0.0, a * np.outer(n, n), False
    if kind == "Geom_SphericalSurface":
        p = surface.Location()
        d = c - np.array([p.X(), p.Y(), p.Z()])
        r = surface.Radius()
        return 1 / r, (q_c + a * np.outer(d, d)) / (r * r), False
    if kind == "Geom_CylindricalSurface":
        axis = surface.Axis()
        p, e = axis.Location(), axis.Direction()
        e = np.array([e.X(), e.Y(), e.Z()])
        d = c - np.array([p.X(), p.Y(), p.Z()])
        across = np.eye(3) - np.outer(e, e)
        r = surface.Radius()
        return 1 / r, across @ (q_c + a * np.outer(d, d)) @ across / (r * r), False
    if kind == "Geom_ToroidalSurface":
        big, r = surface.MajorRadius(), surface.MinorRadius()
        return max(1 / r, 1 / max(big - r, t / 2)), a / 3 * np.eye(3), True
    if kind == "Geom_ConicalSurface":
        u1, u2, v1, v2 = _occ().BRepTools.UVBounds_s(face)
        s = math.sin(surface.SemiAngle())
        rho = min(abs(surface.RefRadius() + v * s) for v in (v1, v2))
        # a face reaching the apex: within T/2 of it the curvature bound is taken at T/2
        return math.cos(surface.SemiAngle()) / max(rho, t / 2), a / 3 * np.eye(3), True
    return 0.0, None, False


def _joins(local: Any, t: float) -> tuple[float, int, int]:
    """(Σ 2 (T/2) w L over edges of two faces that turn, the number of such edges, of folds)."""
    k = _occ()
    ancestors = k.EdgeFaces()
    k.TopExp.MapShapesAndAncestors_s(local, k.TopAbs_EDGE, k.TopAbs_FACE, ancestors)
    volume, turning, folded = 0.0, 0, 0
    for i in range(1, ancestors.Extent() + 1):
        edge = k.TopoDS.Edge(ancestors.FindKey(i))
        faces = list(ancestors.FindFromIndex(i))
        if len(faces) < 2 or k.BRep_Tool.Degenerated_s(edge):
            continue   # a free edge is a rim, cut square
        f1, f2 = k.TopoDS.Face(faces[0]), k.TopoDS.Face(faces[1])
        if f1.IsSame(f2):
            continue   # a seam
        tan_half = max(_tan_half(edge, f1, f2, x) for x in (0.0, 0.25, 0.5, 0.75, 1.0))
        if tan_half <= 1e-12:
            continue   # a tangent join: the prisms meet
        width = 0.5 * t * tan_half
        if width > t or len(faces) > 2:
            width = t
            folded += 1
        length = k.GCPnts_AbscissaPoint.Length_s(k.BRepAdaptor_Curve(edge))
        volume += 2 * (t / 2) * width * length
        turning += 1
    return volume, turning, folded


def _tan_half(edge: Any, f1: Any, f2: Any, x: float) -> float:
    """tan(θ/2), θ the angle between the two faces' outward normals at the fraction x of the
    edge."""
    n1 = _normal(edge, f1, x)
    n2 = _normal(edge, f2, x)
    cos = float(np.clip(n1 @ n2, -1.0, 1.0))
    sin = float(np.linalg.norm(np.cross(n1, n2)))
    return sin / (1 + cos) if cos > -1 + 1e-12 else math.inf


def _normal(edge: Any, face: Any, x: float) -> np.ndarray:
    k = _occ()
    curve = k.BRepAdaptor_Curve2d(edge, face)
    a, b = curve.FirstParameter(), curve.LastParameter()
    uv = curve.Value(a + (b - a) * x)
    props = k.BRepLProp_SLProps(k.BRepAdaptor_Surface(face), uv.X(), uv.Y(), 1, 1e-12)
    if not props.IsNormalDefined():
        return np.zeros(3)
    d = props.Normal()
    n = np.array([d.X(), d.Y(), d.Z()])
    return -n if face.Orientation() == k.TopAbs_REVERSED else n


def _model_bar(local: Any, t: float, curvature: np.ndarray, nn_bar: float, joins: float
               ) -> tuple[float, np.ndarray, np.ndarray]:
    """Bars of volume, ∫x dV (3,), ∫x xᵀ dV (3, 3) from the curvature, the bounded ∫n nᵀ and
    the joins (see the module docstring)."""
    from OCP.Bnd import Bnd_Box  # optional extra, with the rest of this module's
    from OCP.BRepBndLib import BRepBndLib

    box = Bnd_Box()
    BRepBndLib.Add_s(local, box, False)
    lo, hi = box.CornerMin(), box.CornerMax()
    r = max(abs(v) for v in (lo.X(), lo.Y(), lo.Z(), hi.X(), hi.Y(), hi.Z())) * math.sqrt(3) \
        + t
    a_k2, a_k = curvature
    c3 = t**3 / 12
    volume = c3 * a_k2 + joins
    first = c3 * (2 * a_k + a_k2 * r) + joins * r
    second = c3 * (4 * a_k * r + a_k2 * r * r) + t**5 / 80 * a_k2 + joins * r * r \
        + c3 * nn_bar * (2 / 3)
    return volume, np.full(3, first), np.full((3, 3), second)


def shell_solid(shape: Any, scale: float, name: str, thickness: float
                ) -> tuple[SolidIntegral, Uncertainty, dict]:
    """One piece of a CAD file as a wall of ``thickness`` metres: (its integral per unit
    density in SI, like `integrate_solid`'s; the model bar per unit density; the
    ``repairs.shell`` record). Raises UsageError (a free-form face), DegenerateMeshError (no
    area)."""
    k = _occ()
    local, origin, _, half = localise(shape)
    faces, _, _ = face_census(local)
    shell = integrate_shell(local, thickness / scale, name)
    if not shell.area > 0:
        raise DegenerateMeshError(f"{name}: the surface has no area; {setting_ref('shell')} "
                                  "needs a surface")
    s = scale
    volume = shell.volume
    com = shell.first / volume
    second = shell.second - volume * np.outer(com, com)
    inertia = np.trace(second) * np.eye(3) - second
    reach = np.array(half) + thickness / scale
    ulps = CAD_ROUNDING_ULPS * max(sum(faces.values()), 1) * U
    moments = UnitMoments(volume * s**3, ulps * volume * s**3, com * s,
                          (ulps * reach + 2 * U * np.abs(com)) * s, inertia * s**5,
                          np.full((3, 3), ulps * volume * float(reach @ reach)) * s**5)
    tolerance = float(k.ShapeTolerance().Tolerance(local, 1, k.TopAbs_SHAPE))
    integral = SolidIntegral(origin * s, moments, None, tolerance * s, shell.area * s * s,
                             np.array(half) * s, faces, None, "shell", np.asarray(origin))
    # first order, as `massprops.repair.bars`: the COM moves by (Δ∫x + |c| ΔV) / V, and the
    # inertia about it by Δ(∫x xᵀ) (twice on the diagonal) and the shift V c cᵀ's change
    dv = shell.bar_volume
    ac = np.abs(com)
    dc = (shell.bar_first + ac * dv) / volume
    d_outer = volume * (np.outer(ac, dc) + np.outer(dc, ac)) + np.outer(ac, ac) * dv
    d_second = shell.bar_second + d_outer
    d_inertia = (np.trace(d_second) * np.eye(3) + d_second) * s**5
    bar = Uncertainty(dv * s**3, dv * s**3, dc * s, d_inertia,
                      np.full(3, np.linalg.norm(d_inertia, 2)))
    record = {"thickness": thickness, "model": MODEL, "area": float(shell.area * s * s),
              "wall_volume": float(volume * s**3), "turning_edges": shell.turning_edges,
              "folded_edges": shell.folded_edges, "model_volume_bound": float(dv * s**3)}
    return integral, bar, record
