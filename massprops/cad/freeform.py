"""A solid with free-form faces: our own rules where we have one, OpenCASCADE's adaptive rule
on the rest, each with its error bar.

Ours: faces found by `massprops.cad.nurbs.rectangle` (B-spline, Bezier, revolution and
extrusion faces whose domain is their parameter rectangle: to round-off, bar from two orders
of Gauss-Legendre per knot span) and every planar face (`massprops.cad.planar`: Green's theorem
along its edges, bar from two orders per smooth piece). The other faces (trimmed free-form,
trimmed analytic) go to ``BRepGProp`` together, as one open compound: by its fixed Gauss rule
when that is exact (`massprops.cad.faces.fixed_rule_exact`); else by its adaptive rule at the
nested tolerances ``CAD_ADAPTIVE_EPS`` (bar from their difference). Each face's share is the
cone from OpenCASCADE's apex (the mean of the compound's vertices) in both parts, so the parts
add up. OpenCASCADE returns volume, centre and inertia about the centre, from which the raw
moments about the origin are recovered; when its part encloses almost no volume (below
``1e-3`` of the box's), that recovery would divide by ~0, and the whole solid goes to the
adaptive rule instead.
"""

from __future__ import annotations

import functools
from types import SimpleNamespace
from typing import Any

import numpy as np

from massprops.cad.faces import (
    ANALYTIC_FACES,
    face_census,
    fixed_rule_exact,
    is_analytic,
    occ_area,
)
from massprops.cad.nurbs import RawMoments, rectangle, rectangle_face
from massprops.cad.planar import plane_face, plane_frame
from massprops.mesh.facesums import U
from massprops.tolerances import (
    CAD_ADAPTIVE_EPS,
    CAD_ADAPTIVE_FALLBACK_EPS,
    CAD_INTEGRATION_SAFETY,
)

__all__ = ["integrate_free_form", "occ_levels"]

Values = tuple[float, np.ndarray, np.ndarray]   # volume, COM, inertia about the COM


@functools.cache
def _occ() -> SimpleNamespace:
    """OpenCASCADE names used here (optional extra, imported once with the first CAD file)."""
    from OCP.BRep import BRep_Builder, BRep_Tool
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex
    from OCP.BRepGProp import BRepGProp
    from OCP.gp import gp_Pnt
    from OCP.GProp import GProp_GProps
    from OCP.TopAbs import TopAbs_FACE, TopAbs_VERTEX
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS, TopoDS_Compound

    return SimpleNamespace(Builder=BRep_Builder, BRep_Tool=BRep_Tool, BRepGProp=BRepGProp,
                           GProp_GProps=GProp_GProps, FACE=TopAbs_FACE, VERTEX=TopAbs_VERTEX,
                           Explorer=TopExp_Explorer, TopoDS=TopoDS, Compound=TopoDS_Compound,
                           MakeVertex=BRepBuilderAPI_MakeVertex, gp_Pnt=gp_Pnt)


def integrate_free_form(local: Any, only_closed: bool, box_volume: float,
                        centre: tuple[float, float, float]
                        ) -> tuple[Values, tuple[float, np.ndarray, np.ndarray], str, float]:
    """((volume, COM, inertia about the COM), (their integration bars), method, the area of
    the free-form faces) of a solid with free-form faces about its own origin, file unit;
    centre: its bounding box's. method: "own" (every face by our rule), "mixed", or
    "adaptive" (all by OpenCASCADE's)."""
    k = _occ()
    rects, rest = [], []   # ours (a rectangle, or None for a plane), OpenCASCADE's
    explorer = k.Explorer(local, k.FACE)
    while explorer.More():
        face = k.TopoDS.Face(explorer.Current())
        frame = plane_frame(face)
        box = rectangle(face) if frame is None else None
        if box is None and frame is None:
            rest.append(face)
        else:
            rects.append((face, box, frame))
        explorer.Next()
    free_rest = [face for face in rest if not is_analytic(face)]
    everything = [face for face, box, _ in rects if box is not None] + free_rest
    if not rects:
        return (*_adaptive(local, only_closed), occ_area(everything))
    try:
        if not rest:
            # about the box's centre: the bars, first order in the moments about that point,
            # grow with the COM's distance from it (a cylinder about its base: 1.6e-13 in
            # inertia, for an error of 1.5e-15)
            raw = _own(rects, np.asarray(centre, dtype=float))
            return (*_central(raw), "own", raw.area)
        raw = _mixed(rects, rest, box_volume, centre)
    except ValueError:   # a surface our rule does not take or settle on: all to OpenCASCADE
        return (*_adaptive(local, only_closed), occ_area(everything))
    if raw is None or not _agrees(local, only_closed, raw.volume, box_volume):
        return (*_adaptive(local, only_closed), occ_area(everything))
    return (*_central(raw), "mixed", raw.area + occ_area(free_rest))


def _agrees(local: Any, only_closed: bool, volume: float, box_volume: float) -> bool:
    """The mixed sum against OpenCASCADE's coarse adaptive volume (~2e-7 off on NURBS forms):
    the two parts add up only if OpenCASCADE's cones start where ours do (its apex, the mean
    of the vertices, is not a documented contract); a mismatch moves the volume by a sizeable
    fraction, which this catches."""
    k = _occ()
    props = k.GProp_GProps()
    k.BRepGProp.VolumeProperties_s(local, props, 1e-9, only_closed)
    return abs(props.Mass() - volume) <= 1e-5 * box_volume


def _mixed(rects: list, rest: list, box_volume: float, centre: tuple[float, float, float]
           ) -> RawMoments | None:
    """Our faces and OpenCASCADE's added up as raw moments; None when OpenCASCADE's part
    holds too little volume to recover its moments from."""
    k = _occ()
    compound = k.Compound()
    builder = k.Builder()
    builder.MakeCompound(compound)
    for face in rest:
        builder.Add(compound, face)
    # one free vertex more puts OpenCASCADE's apex at the box's centre: left at the faces' own
    # vertices, it lies in a lone planar face's plane, whose cone then holds no volume to
    # recover the moments from
    count, total = _vertex_sum(compound)
    builder.Add(compound, k.MakeVertex(k.gp_Pnt(*((count + 1) * np.asarray(centre) - total))
                                       ).Vertex())
    count, total = _vertex_sum(compound)
    raw = _own(rects, total / count)
    analytic = all(kind in ANALYTIC_FACES for kind in face_census(compound)[0]) and \
        fixed_rule_exact(compound)
    levels = occ_levels(compound, False, analytic)
    if abs(levels[-1][0]) < 1e-3 * box_volume:
        return None
    raws = [_raw(values, raw.about) for values in levels]
    last = raws[-1]
    bar = (np.zeros(13) if analytic else
           CAD_INTEGRATION_SAFETY * np.abs(last - raws[-2]) + 4 * U * np.abs(last))
    return RawMoments(raw.volume + last[0], raw.first + last[1:4],
                      raw.second + last[4:].reshape(3, 3), raw.volume_err + bar[0],
                      raw.first_err + bar[1:4], raw.second_err + bar[4:].reshape(3, 3),
                      raw.area, raw.about)


def _own(faces: list, apex: np.ndarray) -> RawMoments:
    """The raw moments about ``apex`` of our faces (face, its rectangle or None, its plane's
    frame from `plane_frame` or None), each face's share the cone from the apex, summed with
    their bars; ValueError when a rule does not settle. area: the free-form faces' only (the
    census bounds the true planes' already; a flat spline's counts)."""
    total = np.zeros(14)
    err = np.zeros(13)
    for face, box, frame in faces:
        if box is not None:
            values, bar = rectangle_face(face, box, apex)
        else:
            values, bar = plane_face(face, apex, frame)
            if is_analytic(face):   # a true plane
                values[13] = 0.0
        total += values
        err += bar
    return RawMoments(float(total[0]), total[1:4], total[4:13].reshape(3, 3), float(err[0]),
                      err[1:4], err[4:13].reshape(3, 3), float(total[13]),
                      np.asarray(apex, dtype=float))


def _vertex_sum(shape: Any) -> tuple[int, np.ndarray]:
    """(count, sum) of the shape's vertices, each counted as often as the explorer meets it:
    their mean is the apex of OpenCASCADE's per-face cones (its ``roughBaryCenter``)."""
    k = _occ()
    explorer = k.Explorer(shape, k.VERTEX)
    total, count = np.zeros(3), 0
    while explorer.More():
        p = k.BRep_Tool.Pnt_s(k.TopoDS.Vertex(explorer.Current()))
        total += (p.X(), p.Y(), p.Z())
        count += 1
        explorer.Next()
    return count, total


def occ_levels(shape: Any, only_closed: bool, analytic: bool) -> list[Values]:
    """OpenCASCADE's integral of ``shape``: one fixed-rule level (all faces analytic), else the
    nested adaptive levels, finest last (a coarser one first when the two agree exactly)."""
    k = _occ()
    if analytic:
        props = k.GProp_GProps()
        k.BRepGProp.VolumeProperties_s(shape, props, only_closed)
        return [values(props)]
    levels = []
    for eps in CAD_ADAPTIVE_EPS:
        props = k.GProp_GProps()
        k.BRepGProp.VolumeProperties_s(shape, props, eps, only_closed)
        levels.append(values(props))
    if levels[-1][0] == levels[-2][0]:
        props = k.GProp_GProps()
        k.BRepGProp.VolumeProperties_s(shape, props, CAD_ADAPTIVE_FALLBACK_EPS, only_closed)
        levels.insert(0, values(props))
    return levels


def _adaptive(local: Any, only_closed: bool
              ) -> tuple[Values, tuple[float, np.ndarray, np.ndarray], str]:
    """The whole solid by OpenCASCADE's adaptive levels."""
    levels = occ_levels(local, only_closed, False)
    return levels[-1], level_bar(levels), "adaptive"


def level_bar(levels: list[Values]) -> tuple[float, np.ndarray, np.ndarray]:
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


def values(props: Any) -> Values:
    """(volume, COM, inertia about the COM) of a GProp_GProps, unit density, file unit."""
    c = props.CentreOfMass()
    m = props.MatrixOfInertia()
    xy, xz, yz = (m.Value(1, 2) + m.Value(2, 1)) / 2, (m.Value(1, 3) + m.Value(3, 1)) / 2, \
        (m.Value(2, 3) + m.Value(3, 2)) / 2
    j = np.array([[m.Value(1, 1), xy, xz], [xy, m.Value(2, 2), yz], [xz, yz, m.Value(3, 3)]])
    return props.Mass(), np.array([c.X(), c.Y(), c.Z()]), j


def _raw(v: Values, about: np.ndarray) -> np.ndarray:
    """[V, ∫d (3), ∫d dᵀ (9)], d = x - about, from (volume, COM, inertia about the COM)."""
    volume, com, inertia = v
    c = com - about
    second = np.trace(inertia) / 2 * np.eye(3) - inertia + volume * np.outer(c, c)
    return np.concatenate(([volume], volume * c, second.ravel()))


def _central(raw: RawMoments) -> tuple[Values, tuple[float, np.ndarray, np.ndarray]]:
    """Raw moments and their bars to (volume, COM, inertia about the COM) and first-order
    bars of those."""
    volume = raw.volume
    local = raw.first / volume          # the COM from ``about``
    com = raw.about + local
    second = raw.second - volume * np.outer(local, local)
    inertia = np.trace(second) * np.eye(3) - second
    dv = raw.volume_err
    dc = (raw.first_err + np.abs(local) * dv) / abs(volume)
    ac = np.abs(local)
    d_outer = abs(volume) * (np.outer(ac, dc) + np.outer(dc, ac)) + np.outer(ac, ac) * dv
    d_second = raw.second_err + d_outer
    d_inertia = np.trace(d_second) * np.eye(3) + d_second
    return ((volume, com, inertia),
            (dv + 4 * U * abs(volume), dc + 4 * U * np.abs(com),
             d_inertia + 4 * U * np.abs(inertia)))
