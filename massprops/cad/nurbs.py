"""B-spline and Bezier faces whose domain is a parameter rectangle, integrated by our own rule.

Why. OpenCASCADE's adaptive rule (``BRepGProp_Gauss``, the ``Eps`` overloads) stalls near 1e-10
(volume) and 4e-8 (inertia) on NURBS forms of analytic solids whatever ``Eps`` it is given,
while its estimate says 2e-16. Reading its source: (1) the error it refines on is the MASS's
only (the n-point against the 2n/3-point Gauss rule on each subinterval), so the inertia
integrals are never checked; (2) each direction gets at most 32 subintervals, and when that
budget is spent it stops, reporting the last estimate rather than failing; (3) every face with
a wire (every face of a B-rep, even an untrimmed one) is integrated through its boundary, the
inner integral running from the surface's bound to each boundary point, so the rational
integrand is cut at the pcurves' Gauss points rather than at its own knots. Most free-form
faces of real exports and of converted analytic solids are not trimmed at all: their domain is
the rectangle of their parameters (a NURBS sphere, torus, a cylinder's wall). There the
integral is a plain tensor-product one, and Gauss-Legendre per knot span in u and in v
converges geometrically on every moment (each span's integrand is analytic, its poles away
from the span).

Method. Each face's share is the cone from an apex P over it (over a closed surface the cones
add up to the solid whatever P; OpenCASCADE takes P = the mean of the shape's vertices, and
faces integrated here use its P when the rest go there, so that the two parts add up). With
d = S - P and N = S_u x S_v (outward for a FORWARD face), points P + t d, dV = t² dt d·N:

    V = 1/3 ∫∫ d·N du dv,   ∫ x dV = ∫∫ (P/3 + d/4) d·N,
    ∫ x xᵀ dV = ∫∫ (P Pᵀ/3 + (P dᵀ + d Pᵀ)/4 + d dᵀ/5) d·N.

The surface is evaluated from its own poles, weights and knots (vectorised, homogeneous
coordinates, the quotient rule for derivatives), n Gauss points per knot span in each
direction, n rising by ``NURBS_ORDER_STEP`` from the order that integrates the polynomial case
exactly until two orders agree to ``NURBS_AGREEMENT`` of the face's scale; the last result is
kept and the bar is ``CAD_INTEGRATION_SAFETY`` x the last difference.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any, cast

import numpy as np

from massprops.cad.occ import face_edges
from massprops.tolerances import (
    CAD_INTEGRATION_SAFETY,
    NURBS_AGREEMENT,
    NURBS_MAX_ORDER,
    NURBS_ORDER_STEP,
    NURBS_RATIONAL_START,
)

__all__ = ["RawMoments", "cone_moments", "rectangle", "rectangle_face", "spline_evaluator"]


@dataclass(frozen=True)
class RawMoments:
    """∫dV, ∫d dV (3,), ∫d dᵀ dV (3, 3), d = x - about, about the point ``about`` (file unit),
    each with a bound of the quadrature's remaining error; area: ∫dA of the faces."""

    volume: float
    first: np.ndarray
    second: np.ndarray
    volume_err: float
    first_err: np.ndarray
    second_err: np.ndarray
    area: float
    about: np.ndarray


@functools.cache
def _occ() -> SimpleNamespace:
    """OpenCASCADE names used here (optional extra, imported once with the first CAD file)."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Curve2d
    from OCP.BRepTools import BRepTools
    from OCP.Geom import (
        Geom_BezierCurve,
        Geom_BezierSurface,
        Geom_BSplineCurve,
        Geom_BSplineSurface,
        Geom_Circle,
        Geom_Ellipse,
        Geom_Hyperbola,
        Geom_Line,
        Geom_Parabola,
        Geom_RectangularTrimmedSurface,
        Geom_SurfaceOfLinearExtrusion,
        Geom_SurfaceOfRevolution,
        Geom_TrimmedCurve,
    )
    from OCP.GeomConvert import GeomConvert
    from OCP.TopAbs import TopAbs_REVERSED, TopAbs_WIRE
    from OCP.TopExp import TopExp_Explorer

    return SimpleNamespace(BRep_Tool=BRep_Tool, Curve2d=BRepAdaptor_Curve2d,
                           BRepTools=BRepTools, Bezier=Geom_BezierSurface,
                           BSpline=Geom_BSplineSurface, Trimmed=Geom_RectangularTrimmedSurface,
                           Swept=(Geom_SurfaceOfRevolution, Geom_SurfaceOfLinearExtrusion),
                           ExactCurves=(Geom_Line, Geom_Circle, Geom_Ellipse, Geom_Parabola,
                                        Geom_Hyperbola, Geom_BSplineCurve, Geom_BezierCurve),
                           TrimmedCurve=Geom_TrimmedCurve, RectTrim=Geom_RectangularTrimmedSurface,
                           GeomConvert=GeomConvert, WIRE=TopAbs_WIRE,
                           REVERSED=TopAbs_REVERSED, Explorer=TopExp_Explorer)


def rectangle(face: Any) -> tuple[float, float, float, float] | None:
    """(u1, u2, v1, v2) when the face's domain is that parameter rectangle (one wire, every
    boundary curve on one side of it) and its surface is a B-spline or Bezier surface, or a
    surface of revolution or linear extrusion of a curve that is exactly a (rational)
    B-spline (a line, conic, B-spline or Bezier curve: `_surface_data` converts the patch
    exactly), else None."""
    k = _occ()
    surface = _bare(k, face)
    if not (isinstance(surface, (k.BSpline, k.Bezier)) or _exact_sweep(k, surface)):
        return None
    wires = k.Explorer(face, k.WIRE)
    wires.Next()
    if wires.More():      # a second wire: a hole
        return None
    u1, u2, v1, v2 = k.BRepTools.UVBounds_s(face)
    tol = 1e-9 * max(u2 - u1, v2 - v1)
    for edge in face_edges(face):
        curve = k.Curve2d(edge, face)
        a, b = curve.FirstParameter(), curve.LastParameter()
        points = [curve.Value(a + (b - a) * t) for t in (0.0, 0.25, 0.5, 0.75, 1.0)]
        us = np.array([p.X() for p in points])
        vs = np.array([p.Y() for p in points])
        if not any(np.all(np.abs(x - side) <= tol)
                   for x, side in ((us, u1), (us, u2), (vs, v1), (vs, v2))):
            return None
    if not isinstance(surface, (k.BSpline, k.Bezier)):
        return u1, u2, v1, v2   # the converted patch is the rectangle itself
    # the rectangle must lie in the surface's own parameter range (a periodic surface's face
    # may sit a period further on): what the knots describe
    lo_u, hi_u, lo_v, hi_v = surface.Bounds()
    u1, u2 = _into_range(u1, u2, lo_u, hi_u, surface.IsUPeriodic(), tol)
    v1, v2 = _into_range(v1, v2, lo_v, hi_v, surface.IsVPeriodic(), tol)
    if u1 is None or v1 is None:
        return None
    # _into_range gives both ends or neither
    return u1, cast(float, u2), v1, cast(float, v2)


def _bare(k: SimpleNamespace, face: Any) -> Any:
    """The face's surface with every rectangular trim taken off."""
    surface = k.BRep_Tool.Surface_s(face)
    while isinstance(surface, k.Trimmed):
        surface = surface.BasisSurface()
    return surface


def _exact_sweep(k: SimpleNamespace, surface: Any) -> bool:
    """A surface of revolution or extrusion whose swept curve GeomConvert turns into a
    B-spline curve without approximation (an offset or other curve would be approximated)."""
    if not isinstance(surface, k.Swept):
        return False
    curve = surface.BasisCurve()
    while isinstance(curve, k.TrimmedCurve):
        curve = curve.BasisCurve()
    return isinstance(curve, k.ExactCurves)


def _into_range(a: float, b: float, lo: float, hi: float, periodic: bool, tol: float
                ) -> tuple[float | None, float | None]:
    """[a, b] moved by whole periods into [lo, hi] (clipped by tol there), else (None, None)
    (a range across the seam would need splitting: left to OpenCASCADE)."""
    if periodic:
        shift = np.floor((a - lo + tol) / (hi - lo)) * (hi - lo)
        a, b = a - shift, b - shift
    if a < lo - tol or b > hi + tol:
        return None, None
    return max(a, lo), min(b, hi)


def rectangle_face(face: Any, box: tuple[float, float, float, float], apex: np.ndarray
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(values, bar): values = [V, ∫d (3), ∫d dᵀ (9), area] of the cone from ``apex`` over
    the face (its rectangle from `rectangle`), about the apex (d = x - apex), bar the first
    13's quadrature bound.
    ValueError when the surface does not evaluate there or the rule does not settle by
    ``NURBS_MAX_ORDER`` (the caller falls back)."""
    k = _occ()
    tu, pu, tv, pv, homogeneous, (u1, u2, v1, v2) = _surface_data(face, box)
    sign = -1.0 if face.Orientation() == k.REVERSED else 1.0
    # Gauss-Legendre with n points is exact to degree 2n-1: r·N x x of a polynomial patch has
    # degree ~5p in each direction, so the first order integrates that case exactly
    n = max(3, (5 * max(pu, pv) + 2) // 2 + 1)
    if np.ptp(homogeneous[..., 3]) > 0:
        # rational: measured on quadratic patches, orders below this are never at round-off
        n += NURBS_RATIONAL_START
    previous = None
    while True:
        values, scale = _rule(n, tu, pu, tv, pv, homogeneous, (u1, u2), (v1, v2), apex)
        values[:13] *= sign
        if not np.all(np.isfinite(values)):
            raise ValueError("the surface does not evaluate on its rectangle")
        if previous is not None:
            diff = np.abs(values[:13] - previous[:13])
            if np.all(diff <= NURBS_AGREEMENT * scale):
                return values, CAD_INTEGRATION_SAFETY * diff
            if n >= NURBS_MAX_ORDER:
                # not settled: a slowly converging rule's last difference need not bound its
                # error, so the caller hands the solid to the adaptive rule and its bar
                raise ValueError("the Gauss rule did not settle on this face")
        previous = values
        n += NURBS_ORDER_STEP


def _surface_data(face: Any, box: tuple[float, float, float, float]
                  ) -> tuple[np.ndarray, int, np.ndarray, int, np.ndarray, tuple]:
    """(u knots, u degree, v knots, v degree, homogeneous poles (nu, nv, 4): w x, w y, w z, w,
    the rectangle to integrate over) of the face's surface, non-periodic, its location
    applied. A swept surface's patch over ``box`` is converted exactly (GeomConvert: the
    swept curve's B-spline form times a line or rational circle arcs) and integrated over its
    own whole domain; ValueError when the converted patch's corners are not the face's."""
    k = _occ()
    surface = _bare(k, face)
    if isinstance(surface, k.Swept):
        original = k.BRep_Tool.Surface_s(face)   # with the face's location, as the conversion
        surface = k.GeomConvert.SurfaceToBSplineSurface_s(k.RectTrim(original, *box))
        lo_u, hi_u, lo_v, hi_v = surface.Bounds()
        corners = [(np.array(original.Value(u, v).Coord()),
                    np.array(surface.Value(cu, cv).Coord()))
                   for (u, cu) in ((box[0], lo_u), (box[1], hi_u))
                   for (v, cv) in ((box[2], lo_v), (box[3], hi_v))]
        size = max(np.abs(a).max() for a, _ in corners) + max(
            np.abs(a - b).max() for a, _ in corners for b, _ in corners)
        if max(np.abs(a - b).max() for a, b in corners) > 1e-9 * size:
            raise ValueError("the converted patch is not the face's")
        box = (lo_u, hi_u, lo_v, hi_v)
    elif isinstance(surface, k.Bezier):
        surface = k.GeomConvert.SurfaceToBSplineSurface_s(surface)
    else:
        surface = surface.Copy()   # the periodic flags are changed below: not on the file's
    if surface.IsUPeriodic():
        surface.SetUNotPeriodic()
    if surface.IsVPeriodic():
        surface.SetVNotPeriodic()
    nu, nv = surface.NbUPoles(), surface.NbVPoles()
    h = np.empty((nu, nv, 4))
    for i in range(nu):
        for j in range(nv):
            p = surface.Pole(i + 1, j + 1)
            w = surface.Weight(i + 1, j + 1)
            h[i, j] = (w * p.X(), w * p.Y(), w * p.Z(), w)
    tu = _flat_knots(surface.UKnot, surface.UMultiplicity, surface.NbUKnots())
    tv = _flat_knots(surface.VKnot, surface.VMultiplicity, surface.NbVKnots())
    return tu, surface.UDegree(), tv, surface.VDegree(), h, box


def _flat_knots(knot: Any, multiplicity: Any, count: int) -> np.ndarray:
    return np.repeat([knot(i) for i in range(1, count + 1)],
                     [multiplicity(i) for i in range(1, count + 1)])


@functools.cache
def _gauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.polynomial.legendre.leggauss(n)


def _nodes(knots: np.ndarray, lo: float, hi: float, n: int) -> tuple[np.ndarray, np.ndarray]:
    """n Gauss-Legendre nodes and weights on each knot span within [lo, hi]."""
    cuts = np.unique(np.concatenate(([lo, hi], knots[(knots > lo) & (knots < hi)])))
    x, w = _gauss(n)
    a, b = cuts[:-1, None], cuts[1:, None]
    half = (b - a) / 2
    return ((a + b) / 2 + half * x).ravel(), (half * w).ravel()


def _basis(knots: np.ndarray, degree: int, at: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(B, dB/dt): every basis function and its derivative at the points, (len(at), n)."""
    from scipy.interpolate import BSpline  # scipy: loaded only for free-form faces

    count = len(knots) - degree - 1
    spline = BSpline(knots, np.eye(count), degree, extrapolate=False)
    return np.nan_to_num(spline(at)), np.nan_to_num(spline(at, 1))


_BLOCK_POINTS = 65536
"""Points evaluated at once: a surface of many knot spans is taken in blocks of u rows, so the
arrays stay a few MB whatever its size (a 200 x 200-span patch at 15 points per span is 9M
points)."""


def _rule(n: int, tu: np.ndarray, pu: int, tv: np.ndarray, pv: int, h: np.ndarray,
          urange: tuple[float, float], vrange: tuple[float, float], apex: np.ndarray
          ) -> tuple[np.ndarray, np.ndarray]:
    """[V, ∫x (3), ∫x xᵀ (9), area] with n points per span, and the scale of each of the 13
    (the integral of the absolute integrand) against which agreement is judged."""
    u, wu = _nodes(tu, *urange, n)
    v, wv = _nodes(tv, *vrange, n)
    bu, dbu = _basis(tu, pu, u)
    bv, dbv = _basis(tv, pv, v)
    p = np.asarray(apex, dtype=float)
    rows = max(1, _BLOCK_POINTS // len(v))
    sums = np.zeros(14 + 13)   # Σw r·N, Σ w r·N d (3), Σ w r·N d dᵀ (9), area; then scales
    for start in range(0, len(u), rows):
        block = slice(start, start + rows)
        sums += _block(bu[block], dbu[block], wu[block], bv, dbv, wv, h, p)
    values = np.empty(14)
    values[:13] = cone_moments(sums[0], sums[1:4], sums[4:13].reshape(3, 3))
    values[13] = sums[13]
    scale = np.empty(13)
    scale[0] = sums[14] / 3
    scale[1:4] = sums[15] / 3
    scale[4:13] = sums[16] / 3
    return values, scale


def cone_moments(flux: float, first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """[V, ∫d (3), ∫d dᵀ (9)] of the cone from an apex over a surface, about that apex, from its
    flux sums ∫ d·N dA, ∫ (d·N) d dA, ∫ (d·N) d dᵀ dA (d = S - apex, N the outward normal): the
    cone's points apex + t d, t in [0, 1], have dV = t² dt d·N dA."""
    out = np.empty(13)
    out[0] = flux / 3
    out[1:4] = first / 4
    out[4:13] = (second / 5).ravel()
    return out


def _block(bu: np.ndarray, dbu: np.ndarray, wu: np.ndarray, bv: np.ndarray, dbv: np.ndarray,
           wv: np.ndarray, h: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Sums over a block of u rows (all v): Σ w d·N, Σ w d·N d, Σ w d·N d dᵀ, Σ w |N| (the
    area), then Σ |w d·N|, Σ |w d·N| r, Σ |w d·N| r² (r = |d|), padded to 27."""
    nu, nv = h.shape[:2]
    flat = h.reshape(nu, nv * 4)
    along_v = (bu @ flat).reshape(-1, nv, 4)           # (mu, nv, 4)
    a = np.matmul(bv, along_v)                          # (mu, mv, 4)
    av = np.matmul(dbv, along_v)
    au = np.matmul(bv, (dbu @ flat).reshape(-1, nv, 4))
    s, normal = _point_normal(a, au, av)
    weight = np.outer(wu, wv)
    d = s.reshape(-1, 3) - p
    wr = weight.ravel() * np.sum(d * normal.reshape(-1, 3), axis=1)
    out = np.zeros(27)
    out[0] = wr.sum()
    out[1:4] = wr @ d
    out[4:13] = ((d * wr[:, None]).T @ d).ravel()
    out[13] = np.sum(weight * np.linalg.norm(normal, axis=-1))
    wa = np.abs(wr)
    r = np.linalg.norm(d, axis=1)
    out[14] = wa.sum()
    out[15] = wa @ r
    out[16] = wa @ (r * r)
    return out


def _point_normal(a: np.ndarray, au: np.ndarray, av: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """(S, S_u x S_v) from the homogeneous point and its two derivatives (..., 4): the
    quotient rule, S_u = (A_u - w_u S) / w."""
    w = a[..., 3:]
    s = a[..., :3] / w
    su = (au[..., :3] - au[..., 3:] * s) / w
    sv = (av[..., :3] - av[..., 3:] * s) / w
    return s, np.cross(su, sv)


def spline_evaluator(face: Any):
    """For a face on a B-spline or Bezier surface: a function (u, v) arrays -> (S (n, 3),
    S_u x S_v (n, 3)), evaluated from the surface's own poles, weights and knots (location
    applied; a periodic surface's parameters taken modulo its period), vectorised; else None
    (the caller evaluates point by point)."""
    k = _occ()
    basis = _bare(k, face)
    if not isinstance(basis, (k.BSpline, k.Bezier)):
        return None
    tu, pu, tv, pv, h, _ = _surface_data(face, (0.0, 0.0, 0.0, 0.0))
    ranges = [(t[p], t[-p - 1], periodic) for t, p, periodic in (
        (tu, pu, basis.IsUPeriodic()), (tv, pv, basis.IsVPeriodic()))]

    def wrap(x: np.ndarray, lo: float, hi: float, periodic: bool) -> np.ndarray:
        # a periodic face may sit a period further on; the knots describe [lo, hi] only, and
        # a point a rounding outside it would evaluate to nothing (the basis is cut there)
        x = lo + np.mod(x - lo, hi - lo) if periodic else x
        return np.clip(x, lo, hi)

    def evaluate(u: np.ndarray, v: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        u = wrap(np.asarray(u, dtype=float), *ranges[0])
        v = wrap(np.asarray(v, dtype=float), *ranges[1])
        bu, dbu = _basis(tu, pu, u)
        bv, dbv = _basis(tv, pv, v)
        a = np.einsum("pi,ijk,pj->pk", bu, h, bv)
        au = np.einsum("pi,ijk,pj->pk", dbu, h, bv)
        av = np.einsum("pi,ijk,pj->pk", bu, h, dbv)
        return _point_normal(a, au, av)

    return evaluate
