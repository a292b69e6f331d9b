"""Planar faces by Green's theorem along their edges: our own rule, with its bar.

Why. OpenCASCADE's fixed Gauss rule integrates a plane through its boundary's parameter
curves with a number of points set by their degree and knots; on a plane bounded by a B-spline
(the caps of an extruded spline profile) it is not exact and says nothing about it (a periodic
cubic profile's prism: COM 9.6e-9, inertia 7.9e-7 off, with a bar of 3.3e-13 claimed), and its
adaptive rule was 3.6e-3 off in volume on the same prism.

Method. In the plane's own axes (origin O, the apex P's foot on the plane, so O = P + h n,
axes e1, e2, n = e1 x e2 the parametrisation's normal) a point is O + x e1 + y e2, d = S - P =
h n + x e1 + y e2 and d·N = h on the whole face (N = n dA, signed: the face's edges, explored
with the face's orientation, run counter-clockwise about n when n points out). The face's
cone then needs the area moments A, ∫x, ∫y, ∫x², ∫xy, ∫y² only, and Green's theorem turns each
into a line integral over the edges (∫∫ xᵃ yᵇ dA = ∮ xᵃ⁺¹ yᵇ / (a+1) dy). Each edge's 3D curve
(its location applied, projected into the plane: the curve lies in it within the tolerance)
is cut at its own continuity breaks (a B-spline's knots) and integrated by Gauss-Legendre on
each piece: exact for a polynomial curve of degree p from 2p points (the integrands have
degree 4p - 1), converging geometrically on conics and rational curves; the order rises by
``NURBS_ORDER_STEP`` until two orders agree to ``NURBS_AGREEMENT`` of the face's scale (on
edges that are not polynomial, twice in a row: the first agreement's difference still holds
the lower order's error), and the bar is ``CAD_INTEGRATION_SAFETY`` x their last difference
(ValueError by ``NURBS_MAX_ORDER``). A B-spline or Bezier face whose poles are coplanar (a NURBS
conversion's flat faces) is taken as their plane, its poles' distance from it in its bar.
"""

from __future__ import annotations

import functools
from types import SimpleNamespace
from typing import Any, cast

import numpy as np

from massprops.cad.nurbs import cone_moments
from massprops.cad.occ import curve_breaks, face_edges
from massprops.tolerances import (
    CAD_FLAT_RTOL,
    CAD_INTEGRATION_SAFETY,
    NURBS_AGREEMENT,
    NURBS_MAX_ORDER,
    NURBS_ORDER_STEP,
)

__all__ = ["plane_face", "plane_frame"]


@functools.cache
def _occ() -> SimpleNamespace:
    """OpenCASCADE names used here (optional extra, imported once with the first CAD file)."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Curve
    from OCP.BRepTools import BRepTools
    from OCP.Geom import (
        Geom_BezierSurface,
        Geom_BSplineSurface,
        Geom_Plane,
        Geom_RectangularTrimmedSurface,
    )
    from OCP.GeomAbs import GeomAbs_BezierCurve, GeomAbs_BSplineCurve, GeomAbs_Line
    from OCP.gp import gp_Pnt, gp_Vec
    from OCP.TopAbs import TopAbs_REVERSED

    return SimpleNamespace(BRep_Tool=BRep_Tool, Curve=BRepAdaptor_Curve, Plane=Geom_Plane,
                           Trimmed=Geom_RectangularTrimmedSurface,
                           Spline=(Geom_BSplineSurface, Geom_BezierSurface), BRepTools=BRepTools,
                           BEZIER=GeomAbs_BezierCurve, BSPLINE=GeomAbs_BSplineCurve,
                           LINE=GeomAbs_Line, gp_Pnt=gp_Pnt, gp_Vec=gp_Vec,
                           REVERSED=TopAbs_REVERSED)


def plane_frame(face: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, float] | None:
    """(a point, e1, e2, flatness) of the face's plane, e1 x e2 along the surface's own
    normal S_u x S_v (the side its edges run counter-clockwise about), when the face is a plane
    or a B-spline or Bezier surface whose poles lie in one plane within ``CAD_FLAT_RTOL`` of
    their extent (the caps and flat faces of NURBS conversions); flatness: the poles' largest
    distance from that plane (the surface, a convex combination of them, is no farther);
    else None."""
    k = _occ()
    surface = k.BRep_Tool.Surface_s(face)   # with the face's location
    while isinstance(surface, k.Trimmed):
        surface = surface.BasisSurface()
    if isinstance(surface, k.Plane):
        axes = surface.Position()
        return (np.array(axes.Location().Coord()), np.array(axes.XDirection().Coord()),
                np.array(axes.YDirection().Coord()), 0.0)
    if not isinstance(surface, k.Spline):
        return None
    poles = np.array([surface.Pole(i, j).Coord() for i in range(1, surface.NbUPoles() + 1)
                      for j in range(1, surface.NbVPoles() + 1)])
    centre = poles.mean(axis=0)
    spread = poles - centre
    extent = float(np.abs(spread).max())
    if extent == 0:
        return None
    normal = np.linalg.svd(spread)[2][2]
    flatness = float(np.abs(spread @ normal).max())
    if flatness > CAD_FLAT_RTOL * extent:
        return None
    u1, u2, v1, v2 = k.BRepTools.UVBounds_s(face)
    point, du, dv = k.gp_Pnt(), k.gp_Vec(), k.gp_Vec()
    surface.D1((u1 + u2) / 2, (v1 + v2) / 2, point, du, dv)
    if np.cross(du.Coord(), dv.Coord()) @ normal < 0:
        normal = -normal
    e1 = spread[np.argmax(np.linalg.norm(spread, axis=1))]
    e1 = e1 - (e1 @ normal) * normal
    e1 /= np.linalg.norm(e1)
    return centre, e1, np.cross(normal, e1), flatness


def plane_face(face: Any, apex: np.ndarray, frame: tuple | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
    """(values, bar): values = [V, ∫d (3), ∫d dᵀ (9), area] of the cone from ``apex`` over the
    planar face, about the apex (d = x - apex, file unit; ``frame`` from `plane_frame`), bar
    the first 13's quadrature bound
    plus, for a flat spline, what its flatness δ can move: δ A on the flux, times the reach
    on the moments. ValueError when the rule does not settle."""
    # only planar faces come here: plane_frame is not None for them
    o0, e1, e2, flatness = cast(tuple, plane_frame(face)) if frame is None else frame
    n = np.cross(e1, e2)
    p = np.asarray(apex, dtype=float)
    h = float(n @ (o0 - p))
    origin = p + h * n
    pieces = _pieces(face)
    polynomial = all(q for _, _, _, q in pieces)
    order = max(4, 2 * max((q or 4 for _, _, _, q in pieces), default=1))
    previous, agreed = None, False
    while True:
        line = _line_sums(pieces, order, origin, e1, e2)
        values, scale = _cone(line, h, n, e1, e2)
        if not np.all(np.isfinite(values)):
            raise ValueError("the plane's edges do not evaluate")
        if previous is not None:
            diff = np.abs(values[:13] - previous[:13])
            # two agreements in a row: the first difference, on a conic or rational edge,
            # still holds the lower order's error (a drilled plate's hole: 1e-13 of its
            # second moments, 100x the error); one order more costs a few hundred points
            # and leaves the difference at round-off
            settled = agreed or polynomial   # polynomial edges: exact from the first order
            agreed = bool(np.all(diff <= NURBS_AGREEMENT * scale))
            if agreed and settled:
                bar = CAD_INTEGRATION_SAFETY * diff
                if flatness:
                    # the surface within δ of the plane: ∫g dV moves by at most max|g| δ A
                    reach = abs(h) + line[12]
                    flux = flatness * line[6]
                    bar[0] += flux
                    bar[1:4] += flux * reach
                    bar[4:13] += flux * reach * reach
                return values, bar
            if order >= NURBS_MAX_ORDER:
                raise ValueError("the Gauss rule did not settle on this plane's edges")
        previous = values
        order += NURBS_ORDER_STEP


def _pieces(face: Any) -> list[tuple[Any, float, float, int]]:
    """(curve adaptor, t0, t1, degree or 0) for each smooth piece of each edge of the face, t0
    to t1 the way the edge runs in the face (its orientation), degenerate edges left out;
    degree is the polynomial degree of a non-rational B-spline, Bezier or line piece (0:
    not a polynomial: the orders start at 8, and two agreements in a row are asked)."""
    k = _occ()
    out: list[tuple[Any, float, float, int]] = []
    for edge in face_edges(face, degenerate=False):
        curve = k.Curve(edge)
        kind = curve.GetType()
        degree = 0
        if kind == k.LINE:
            degree = 1
        elif kind in (k.BSPLINE, k.BEZIER) and not curve.IsRational():
            degree = curve.Degree()
        breaks = curve_breaks(curve)
        if edge.Orientation() == k.REVERSED:
            spans = [(b, a) for a, b in zip(breaks[:-1], breaks[1:])][::-1]
        else:
            spans = list(zip(breaks[:-1], breaks[1:]))
        out.extend((curve, a, b, degree) for a, b in spans)
    return out


@functools.cache
def _gauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.polynomial.legendre.leggauss(n)


def _line_sums(pieces: list, order: int, origin: np.ndarray, e1: np.ndarray, e2: np.ndarray
               ) -> np.ndarray:
    """∮ over the edges of [x dy, x²/2 dy, x y dy, x³/3 dy, x² y/2 dy, x y² dy] (the area
    moments A, ∫x, ∫y, ∫x², ∫xy, ∫y² by Green's theorem), then the same of the absolute
    integrands and the largest |(x, y)| met, in the plane's axes about ``origin``."""
    k = _occ()
    x_nodes, weights = _gauss(order)
    point, tangent = k.gp_Pnt(), k.gp_Vec()
    xs, ys, dys, ws = [], [], [], []
    for curve, a, b, _ in pieces:
        half = (b - a) / 2
        for t, w in zip((a + b) / 2 + half * x_nodes, half * weights):
            curve.D1(float(t), point, tangent)
            r = np.array(point.Coord()) - origin
            dr = np.array(tangent.Coord())
            xs.append(r @ e1)
            ys.append(r @ e2)
            dys.append(dr @ e2)
            ws.append(w)
    x, y, dy, w = map(np.asarray, (xs, ys, dys, ws))
    terms = np.array([x, x * x / 2, x * y, x**3 / 3, x * x * y / 2, x * y * y]) * (w * dy)
    reach = float(np.max(np.hypot(x, y))) if len(x) else 0.0
    return np.concatenate((terms.sum(axis=1), np.abs(terms).sum(axis=1), [reach]))


def _cone(line: np.ndarray, h: float, n: np.ndarray, e1: np.ndarray, e2: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray]:
    """The cone's [V, ∫d, ∫d dᵀ, area] about its apex from the area moments (d = h n + x e1 +
    y e2 and d·N = h dA), and the scale of each of the 13 that agreement is judged against."""
    a, mx, my, mxx, mxy, myy = line[:6]
    first = h * n * a + e1 * mx + e2 * my                                     # ∫ d dA
    cross = np.outer(n, e1 * mx + e2 * my)
    second = (h * h * a * np.outer(n, n) + h * (cross + cross.T) + mxx * np.outer(e1, e1)
              + mxy * (np.outer(e1, e2) + np.outer(e2, e1)) + myy * np.outer(e2, e2))
    values = np.empty(14)
    values[:13] = cone_moments(h * a, h * first, h * second)
    values[13] = abs(a)
    # the natural size of each moment, as the surface rule's Σ |w d·N| r^k / 3: d·N = h, the
    # line sums' absolute area, r the reach from the apex
    size = abs(h) + line[12]
    flux = abs(h) * line[6] / 3
    scale = np.empty(13)
    scale[0] = flux
    scale[1:4] = flux * size
    scale[4:13] = flux * size * size
    return values, scale
