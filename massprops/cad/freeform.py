"""A solid with free-form faces (or analytic faces the fixed rule is not exact on): every face
by one of our own rules, each with its error bar; OpenCASCADE's adaptive rule only when one of
ours does not settle.

Ours: faces found by `massprops.cad.nurbs.rectangle` (B-spline, Bezier, revolution and
extrusion faces whose domain is their parameter rectangle: tensor-product Gauss-Legendre per
knot span), planes and flat splines (`massprops.cad.planar`: Green's theorem along their
edges), and every other face (`massprops.cad.trimmed`: Green's theorem in its parameters, the
inner integral per knot span); each with a bar from two orders. Each face's share is the cone
from one apex (the bounding box's centre) over it: over a closed surface the cones add up to
the solid. When a rule does not settle (``NURBS_MAX_ORDER``) or a surface does not evaluate,
the whole solid goes to OpenCASCADE's adaptive rule at the nested tolerances
``CAD_ADAPTIVE_EPS``, with a bar from their difference (its own estimate is never the bar).
"""

from __future__ import annotations

import functools
from types import SimpleNamespace
from typing import Any

import numpy as np

from massprops.cad.faces import (
    is_analytic,
    occ_area,
)
from massprops.cad.nurbs import RawMoments, rectangle, rectangle_face
from massprops.cad.planar import plane_face, plane_frame
from massprops.cad.trimmed import trimmed_face
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
    from OCP.BRepGProp import BRepGProp
    from OCP.GProp import GProp_GProps
    from OCP.TopAbs import TopAbs_FACE
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS

    return SimpleNamespace(BRepGProp=BRepGProp, GProp_GProps=GProp_GProps, FACE=TopAbs_FACE,
                           Explorer=TopExp_Explorer, TopoDS=TopoDS)


def integrate_free_form(local: Any, only_closed: bool, centre: tuple[float, float, float]
                        ) -> tuple[Values, tuple[float, np.ndarray, np.ndarray], str, float]:
    """((volume, COM, inertia about the COM), (their integration bars), method, the area of
    the free-form faces) of a solid about its own origin, file unit; centre: its bounding
    box's. method: "own" (every face by our rules) or "adaptive" (all by OpenCASCADE's)."""
    k = _occ()
    faces = []   # (face, its rectangle or None, its plane's frame or None)
    explorer = k.Explorer(local, k.FACE)
    while explorer.More():
        face = k.TopoDS.Face(explorer.Current())
        frame = plane_frame(face)
        faces.append((face, rectangle(face) if frame is None else None, frame))
        explorer.Next()
    try:
        # about the box's centre: the bars, first order in the moments about that point,
        # grow with the COM's distance from it (a cylinder about its base: 1.6e-13 in
        # inertia, for an error of 1.5e-15)
        raw = _own(faces, np.asarray(centre, dtype=float))
    except ValueError:   # a surface our rules do not settle on: all to OpenCASCADE
        free = [face for face, _, _ in faces if not is_analytic(face)]
        return (*_adaptive(local, only_closed), occ_area(free))
    return (*_central(raw), "own", raw.area)


def _own(faces: list, apex: np.ndarray) -> RawMoments:
    """The raw moments about ``apex`` of the faces (face, its rectangle or None, its plane's
    frame from `plane_frame` or None), each face's share the cone from the apex, summed with
    their bars; ValueError when a rule does not settle. area: the free-form faces' only (the
    census bounds the analytic ones' already)."""
    total = np.zeros(14)
    err = np.zeros(13)
    for face, box, frame in faces:
        if box is not None:
            values, bar = rectangle_face(face, box, apex)
        elif frame is not None:
            values, bar = plane_face(face, apex, frame)
        else:
            values, bar = trimmed_face(face, apex)
        if is_analytic(face):
            values[13] = 0.0
        total += values
        err += bar
    return RawMoments(float(total[0]), total[1:4], total[4:13].reshape(3, 3), float(err[0]),
                      err[1:4], err[4:13].reshape(3, 3), float(total[13]),
                      np.asarray(apex, dtype=float))


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


def _central(raw: RawMoments) -> tuple[Values, tuple[float, np.ndarray, np.ndarray]]:
    """Raw moments and their bars to (volume, COM, inertia about the COM) and first-order
    bars of those."""
    volume = raw.volume
    local = raw.first / volume          # the COM from ``about``
    com = raw.about + local
    second = raw.second - volume * np.outer(local, local)
    second = (second + second.T) / 2   # the sums' round-off is not symmetric: the tensor is
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
