"""Trimmed faces (any surface, any boundary) by Green's theorem in their parameters: our rule.

Why. A face that is neither untrimmed (`massprops.cad.nurbs`) nor flat
(`massprops.cad.planar`) - a B-spline face with a hole, a cylinder cut by an oblique plane, an
offset - was left to OpenCASCADE's adaptive rule, whose own estimate is no bar and whose
levels can agree on a wrong result.

Method. With g(u, v) the cone integrand over the surface ([d·N, (d·N) d, (d·N) d dᵀ], d =
S - apex, N = S_u x S_v), Green's theorem turns the integral over the face's domain into one
along its boundary: ∫∫_D g du dv = ∮ G dv with G(u, v) = ∫_{u0}^{u} g(s, v) ds (u0 the low
side of the face's parameter box). The boundary is the face's parameter curves, run the way
the face's edges are (the face's orientation composed in, so a reversed face comes out
negated: its outward normal is -N). Each curve is cut at its own continuity breaks and where
it crosses a knot line of the surface (G is smooth only between them), and each piece gets
Gauss-Legendre in its parameter; at each of those points the inner integral in s takes
Gauss-Legendre on each knot span of the surface between u0 and the point. A B-spline or
Bezier surface is evaluated from its own poles, all points at once
(`massprops.cad.nurbs.spline_evaluator`); any other (offsets, revolutions, analytic surfaces)
by OpenCASCADE point by point (``BRepAdaptor_Surface.D1``, the face's location applied).
Both orders rise together by ``NURBS_ORDER_STEP`` until two orders agree to
``NURBS_AGREEMENT`` of the face's scale twice in a row; the bar is ``CAD_INTEGRATION_SAFETY``
x the last difference (ValueError by ``NURBS_MAX_ORDER``: the caller falls back).
"""

from __future__ import annotations

import functools
from types import SimpleNamespace
from typing import Any

import numpy as np

from massprops.cad.nurbs import cone_moments, spline_evaluator
from massprops.cad.occ import curve_breaks, face_edges
from massprops.tolerances import (
    CAD_INTEGRATION_SAFETY,
    NURBS_AGREEMENT,
    NURBS_MAX_ORDER,
    NURBS_ORDER_STEP,
)

__all__ = ["trimmed_face"]

_START_ORDER = 8
"""Points per piece and per span of the first order (the integrands are not polynomial in the
boundary's parameter: a rational or trigonometric surface, a curve's own parametrisation)."""

_BRACKET_SAMPLES = 32
"""Samples per boundary piece to bracket its crossings of the surface's knot lines, each then
bisected to round-off."""


@functools.cache
def _occ() -> SimpleNamespace:
    """OpenCASCADE names used here (optional extra, imported once with the first CAD file)."""
    from OCP.BRep import BRep_Tool
    from OCP.BRepAdaptor import BRepAdaptor_Curve2d, BRepAdaptor_Surface
    from OCP.collections import Array1_double
    from OCP.GeomAbs import GeomAbs_CN
    from OCP.gp import gp_Pnt, gp_Pnt2d, gp_Vec, gp_Vec2d
    from OCP.TopAbs import TopAbs_REVERSED

    return SimpleNamespace(BRep_Tool=BRep_Tool, Curve2d=BRepAdaptor_Curve2d,
                           Surface=BRepAdaptor_Surface, Reals=Array1_double, CN=GeomAbs_CN,
                           gp_Pnt=gp_Pnt, gp_Pnt2d=gp_Pnt2d, gp_Vec=gp_Vec, gp_Vec2d=gp_Vec2d,
                           REVERSED=TopAbs_REVERSED)


def trimmed_face(face: Any, apex: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(values, bar): values = [V, ∫d (3), ∫d dᵀ (9), area] of the cone from ``apex`` over the
    face, about the apex (d = x - apex, file unit; area: ∫|N| du dv), bar the first 13's
    quadrature bound. ValueError when the rule does not settle or the surface does not
    evaluate."""
    k = _occ()
    surface = k.Surface(face)   # restricted to the face's parameter box, its location applied
    u0 = surface.FirstUParameter()
    u_breaks = _breaks(surface.NbUIntervals(k.CN), surface.UIntervals)
    v_breaks = _breaks(surface.NbVIntervals(k.CN), surface.VIntervals)
    pieces = _pieces(face, u_breaks, v_breaks)
    p = np.asarray(apex, dtype=float)
    evaluate = spline_evaluator(face) or functools.partial(_point_by_point, surface)
    order, previous, agreed = _START_ORDER, None, False
    while True:
        values, scale = _rule(evaluate, pieces, u0, u_breaks, order, p)
        if not np.all(np.isfinite(values)):
            raise ValueError("the surface does not evaluate on the face")
        if previous is not None:
            diff = np.abs(values[:13] - previous[:13])
            settled = agreed
            agreed = bool(np.all(diff <= NURBS_AGREEMENT * scale))
            if agreed and settled:
                return values, CAD_INTEGRATION_SAFETY * diff
            if order >= NURBS_MAX_ORDER:
                raise ValueError("the Gauss rule did not settle on this trimmed face")
        previous = values
        order += NURBS_ORDER_STEP


def _breaks(count: int, fill: Any) -> np.ndarray:
    k = _occ()
    cuts = k.Reals(1, count + 1)
    fill(cuts, k.CN)
    return np.array([cuts.Value(i) for i in range(1, count + 2)])


def _pieces(face: Any, u_breaks: np.ndarray, v_breaks: np.ndarray) -> list[tuple[Any, float,
                                                                                  float]]:
    """(parameter curve, t0, t1) pieces of the face's boundary, t0 to t1 the way its edge runs
    in the face, cut at the curve's own breaks and where it crosses an inner knot line of the
    surface (u = const or v = const)."""
    k = _occ()
    out: list[tuple[Any, float, float]] = []
    for edge in face_edges(face):
        curve = k.Curve2d(edge, face)
        cuts = curve_breaks(curve)
        for a, b in zip(cuts[:-1], cuts[1:]):
            inner = [a, b]
            for axis, lines in ((0, u_breaks[1:-1]), (1, v_breaks[1:-1])):
                for line in lines:
                    inner += _crossings(curve, a, b, axis, float(line))
            inner = sorted(set(inner))
            spans = list(zip(inner[:-1], inner[1:]))
            if edge.Orientation() == k.REVERSED:
                spans = [(t1, t0) for t0, t1 in reversed(spans)]
            out.extend((curve, t0, t1) for t0, t1 in spans if t1 != t0)
    return out


def _crossings(curve: Any, a: float, b: float, axis: int, line: float) -> list[float]:
    """Parameters in (a, b) where the curve's u (axis 0) or v (axis 1) equals ``line``."""
    ts = np.linspace(a, b, _BRACKET_SAMPLES + 1)
    f = np.array([curve.Value(float(t)).Coord()[axis] - line for t in ts])
    out = []
    for i in np.nonzero(f[:-1] * f[1:] < 0)[0]:
        lo, hi, f_lo = ts[i], ts[i + 1], f[i]
        for _ in range(60):   # bisection to round-off
            mid = (lo + hi) / 2
            if mid in (lo, hi):
                break
            f_mid = curve.Value(float(mid)).Coord()[axis] - line
            if (f_mid < 0) == (f_lo < 0):
                lo, f_lo = mid, f_mid
            else:
                hi = mid
        out.append(float((lo + hi) / 2))
    return out


@functools.cache
def _gauss(n: int) -> tuple[np.ndarray, np.ndarray]:
    return np.polynomial.legendre.leggauss(n)


def _point_by_point(surface: Any, u: np.ndarray, v: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """(S, S_u x S_v) at each (u, v) by OpenCASCADE (any surface type: offsets, revolutions,
    analytic surfaces), one call per point."""
    k = _occ()
    pnt, du, dv = k.gp_Pnt(), k.gp_Vec(), k.gp_Vec()
    pts, nrm = np.empty((len(u), 3)), np.empty((len(u), 3))
    for i, (ui, vi) in enumerate(zip(u, v)):
        surface.D1(float(ui), float(vi), pnt, du, dv)
        pts[i] = pnt.Coord()
        nrm[i] = np.cross(du.Coord(), dv.Coord())
    return pts, nrm


def _rule(evaluate: Any, pieces: list, u0: float, u_breaks: np.ndarray, n: int,
          apex: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """[V, ∫d, ∫d dᵀ, area] with n points per boundary piece and per inner span, and the
    scale of each of the 13 (Σ |w d·N| r^k / 3, r = |d|) that agreement is judged against.
    evaluate: (u, v) arrays -> (S, S_u x S_v)."""
    k = _occ()
    x, w = _gauss(n)
    pnt2, tan2 = k.gp_Pnt2d(), k.gp_Vec2d()
    us, vs, ws = [], [], []   # every inner point of every outer point, with its weight
    for curve, t0, t1 in pieces:
        half = (t1 - t0) / 2
        for t, wt in zip((t0 + t1) / 2 + half * x, half * w):
            curve.D1(float(t), pnt2, tan2)
            u, v = pnt2.X(), pnt2.Y()
            dvdt = tan2.Y()
            if dvdt == 0:   # along u: contributes nothing (∮ G dv)
                continue
            inside = u_breaks[(u_breaks > min(u0, u)) & (u_breaks < max(u0, u))]
            cuts = np.concatenate(([u0], np.sort(inside)[::1 if u >= u0 else -1], [u]))
            lo, hi = cuts[:-1, None], cuts[1:, None]
            s = ((lo + hi) / 2 + (hi - lo) / 2 * x).ravel()
            us.append(s)
            vs.append(np.full(len(s), v))
            ws.append(((hi - lo) / 2 * w).ravel() * (wt * dvdt))
    sums = np.zeros(17)
    if us:
        u_all, v_all, w_all = map(np.concatenate, (us, vs, ws))
        for start in range(0, len(u_all), _BLOCK):
            block = slice(start, start + _BLOCK)
            pts, nrm = evaluate(u_all[block], v_all[block])
            ws_ = w_all[block]
            d = pts - apex
            flux = ws_ * np.einsum("ij,ij->i", d, nrm)
            sums[0] += flux.sum()
            sums[1:4] += flux @ d
            sums[4:13] += ((d * flux[:, None]).T @ d).ravel()
            sums[13] += ws_ @ np.linalg.norm(nrm, axis=1)   # signed, as the flux: the area
            r = np.linalg.norm(d, axis=1)
            sums[14] += np.abs(flux).sum()
            sums[15] += np.abs(flux) @ r
            sums[16] += np.abs(flux) @ (r * r)
    values = np.empty(14)
    values[:13] = cone_moments(sums[0], sums[1:4], sums[4:13].reshape(3, 3))
    values[13] = abs(sums[13])
    scale = np.empty(13)
    scale[0] = sums[14] / 3
    scale[1:4] = sums[15] / 3
    scale[4:13] = sums[16] / 3
    return values, scale


_BLOCK = 8192
"""Points evaluated at once (the spline evaluator's dense basis matrices stay a few MB)."""
