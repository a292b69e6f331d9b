"""Solids and files for the CAD tests, made with the same kernel (OpenCASCADE via OCP).

Imported only by tests that first did ``pytest.importorskip("OCP")``."""

from __future__ import annotations

import math

from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut
from OCP.BRepBuilderAPI import BRepBuilderAPI_NurbsConvert, BRepBuilderAPI_Transform
from OCP.BRepFilletAPI import BRepFilletAPI_MakeFillet
from OCP.BRepPrimAPI import (
    BRepPrimAPI_MakeBox,
    BRepPrimAPI_MakeCone,
    BRepPrimAPI_MakeCylinder,
    BRepPrimAPI_MakeSphere,
    BRepPrimAPI_MakeTorus,
)
from OCP.BRepTools import BRepTools
from OCP.gp import gp_Ax2, gp_Dir, gp_Pnt, gp_Trsf, gp_Vec
from OCP.Interface import Interface_Static
from OCP.STEPCAFControl import STEPCAFControl_Writer
from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer
from OCP.TCollection import TCollection_ExtendedString
from OCP.TDataStd import TDataStd_Name
from OCP.TDocStd import TDocStd_Document
from OCP.TopAbs import TopAbs_EDGE
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopLoc import TopLoc_Location
from OCP.XCAFDoc import XCAFDoc_DocumentTool

import massprops.cad.occ as occ

occ.require_occ("tests")  # silence the translators' console output


def closed_forms(kind: str, a: float) -> tuple[float, tuple, tuple]:
    """(volume, COM relative to the solid's anchor, diagonal inertia per unit density about the
    COM) of the analytic solids below, size a."""
    pi = math.pi
    if kind == "box":           # a x 2a x 3a from the anchor
        x, y, z = a, 2 * a, 3 * a
        v = x * y * z
        return v, (x / 2, y / 2, z / 2), (v * (y * y + z * z) / 12, v * (x * x + z * z) / 12,
                                         v * (x * x + y * y) / 12)
    if kind == "cylinder":      # radius a, height 2a along z
        r, h = a, 2 * a
        v = pi * r * r * h
        side = v * (3 * r * r + h * h) / 12
        return v, (0, 0, h / 2), (side, side, v * r * r / 2)
    if kind == "sphere":
        v = 4 * pi * a**3 / 3
        return v, (0, 0, 0), (0.4 * v * a * a,) * 3
    if kind == "torus":         # major 2a, minor a/2, axis z
        big, r = 2 * a, a / 2
        v = 2 * pi * pi * big * r * r
        izz = v * (big * big + 0.75 * r * r)
        ixx = v * (big * big / 2 + 5 * r * r / 8)
        return v, (0, 0, 0), (ixx, ixx, izz)
    if kind == "cone":          # base radius a at z=0, apex at z=2a
        r, h = a, 2 * a
        v = pi * r * r * h / 3
        ixx = v * (3 * r * r / 20 + 3 * h * h / 80)
        return v, (0, 0, h / 4), (ixx, ixx, 0.3 * v * r * r)
    raise ValueError(kind)


def make(kind: str, a: float, at: tuple = (0.0, 0.0, 0.0)):
    """An analytic solid of size a with its anchor at ``at``."""
    ax = gp_Ax2(gp_Pnt(*at), gp_Dir(0, 0, 1))
    if kind == "box":
        return BRepPrimAPI_MakeBox(gp_Pnt(*at), a, 2 * a, 3 * a).Shape()
    if kind == "cylinder":
        return BRepPrimAPI_MakeCylinder(ax, a, 2 * a).Shape()
    if kind == "sphere":
        return BRepPrimAPI_MakeSphere(gp_Pnt(*at), a).Shape()
    if kind == "torus":
        return BRepPrimAPI_MakeTorus(ax, 2 * a, a / 2).Shape()
    if kind == "cone":
        return BRepPrimAPI_MakeCone(ax, a, 0.0, 2 * a).Shape()
    raise ValueError(kind)


def drilled_box(a: float, at: tuple = (0.0, 0.0, 0.0)):
    """Cube of side 2a, a through hole of radius a/2 along z through its centre."""
    x, y, z = at
    cube = BRepPrimAPI_MakeBox(gp_Pnt(x, y, z), 2 * a, 2 * a, 2 * a).Shape()
    hole = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(x + a, y + a, z - a), gp_Dir(0, 0, 1)),
                                    a / 2, 4 * a).Shape()
    return BRepAlgoAPI_Cut(cube, hole).Shape()


def filleted_box(a: float, r: float, at: tuple = (0.0, 0.0, 0.0)):
    """Cube of side 2a with its four edges parallel to z rounded with radius r."""
    x, y, z = at
    cube = BRepPrimAPI_MakeBox(gp_Pnt(x, y, z), 2 * a, 2 * a, 2 * a).Shape()
    fillet = BRepFilletAPI_MakeFillet(cube)
    explorer = TopExp_Explorer(cube, TopAbs_EDGE)
    seen = set()
    from OCP.BRep import BRep_Tool
    from OCP.TopoDS import TopoDS
    while explorer.More():
        edge = TopoDS.Edge(explorer.Current())
        p = BRep_Tool.Pnt_s(TopExp.FirstVertex_s(edge))
        q = BRep_Tool.Pnt_s(TopExp.LastVertex_s(edge))
        key = (round(p.X(), 9), round(p.Y(), 9))
        if abs(p.X() - q.X()) < 1e-12 * a and abs(p.Y() - q.Y()) < 1e-12 * a and key not in seen:
            seen.add(key)
            fillet.Add(r, edge)
        explorer.Next()
    return fillet.Shape()


def filleted_box_forms(a: float, r: float) -> tuple[float, tuple]:
    """(volume, diagonal inertia per unit density about the centre) of filleted_box."""
    s = 2 * a
    h = s
    # square of side s minus four corner pieces (square r x r minus quarter disc)
    corner_area = r * r * (1 - math.pi / 4)
    area = s * s - 4 * corner_area
    # polar second moment of a corner piece about the square's centre
    c = a - r   # centre of the quarter disc, from the square centre, per axis
    # square r x r with centre at (c + r/2, c + r/2): Ixx-type (integral y²) about origin
    sq_y2 = r * r * (r * r / 12 + (c + r / 2) ** 2)
    # quarter disc centred at (c, c) in the outer quadrant: ∫y² = ∫(c + v)² over v in quarter
    q_area = math.pi * r * r / 4
    q_v = 4 * r / (3 * math.pi) * q_area    # ∫v dA
    q_v2 = math.pi * r**4 / 16              # ∫v² dA
    disc_y2 = c * c * q_area + 2 * c * q_v + q_v2
    y2 = s**4 / 12 - 4 * (sq_y2 - disc_y2)  # ∫y² over the section (= ∫x²)
    v = area * h
    ixx = h * y2 + area * h**3 / 12
    izz = 2 * h * y2
    return v, (ixx, ixx, izz)


def nurbs(shape):
    return BRepBuilderAPI_NurbsConvert(shape, True).Shape()


def moved(shape, offset):
    trsf = gp_Trsf()
    trsf.SetTranslation(gp_Vec(*offset))
    return BRepBuilderAPI_Transform(shape, trsf, True).Shape()


def write_step(shape, path, unit: str = "M") -> None:
    """One shape to STEP; coordinates are taken as ``unit`` (no scaling)."""
    writer = STEPControl_Writer()   # first: creating it initialises the parameters below
    for key in ("write.step.unit", "xstep.cascade.unit"):
        assert Interface_Static.SetCVal_s(key, unit)
    try:
        writer.Transfer(shape, STEPControl_AsIs)
        assert int(writer.Write(str(path))) == 1
    finally:
        Interface_Static.SetCVal_s("xstep.cascade.unit", "MM")


def write_brep(shape, path) -> None:
    assert BRepTools.Write_s(shape, str(path))


def write_assembly(parts, path, name: str = "assembly") -> None:
    """parts: [(name, shape, (dx, dy, dz))] in millimetres -> a STEP assembly in mm whose
    components are placed by translations."""
    doc = TDocStd_Document(TCollection_ExtendedString("test"))
    XCAFDoc_DocumentTool.SetLengthUnit_s(doc, 0.001)
    tool = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    top = tool.NewShape()
    TDataStd_Name.Set_s(top, TCollection_ExtendedString(name))
    for part_name, shape, offset in parts:
        label = tool.AddShape(shape, False)
        TDataStd_Name.Set_s(label, TCollection_ExtendedString(part_name))
        trsf = gp_Trsf()
        trsf.SetTranslation(gp_Vec(*offset))
        tool.AddComponent(top, label, TopLoc_Location(trsf))
    tool.UpdateAssemblies()
    writer = STEPCAFControl_Writer()
    for key in ("write.step.unit", "xstep.cascade.unit"):
        Interface_Static.SetCVal_s(key, "MM")
    writer.SetNameMode(True)
    assert writer.Transfer(doc, STEPControl_AsIs)
    assert int(writer.Write(str(path))) == 1


def write_named(parts, path, fmt: str) -> None:
    """parts: [(name, shape, material or None)] in millimetres -> a STEP (with material
    designations, density in g/cm³ as OpenCASCADE's translator writes it) or IGES (names as
    entity name properties, solids as B-rep) file of free parts."""
    from OCP.IGESCAFControl import IGESCAFControl_Writer
    from OCP.TCollection import TCollection_HAsciiString

    doc = TDocStd_Document(TCollection_ExtendedString("named"))
    XCAFDoc_DocumentTool.SetLengthUnit_s(doc, 0.001)
    tool = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    materials = XCAFDoc_DocumentTool.MaterialTool_s(doc.Main())
    for name, shape, material in parts:
        label = tool.AddShape(shape, False)
        TDataStd_Name.Set_s(label, TCollection_ExtendedString(name))
        if material is not None:
            title, density = material
            materials.SetMaterial(label, TCollection_HAsciiString(title),
                                  TCollection_HAsciiString(""), density / 1000.0,
                                  TCollection_HAsciiString("density"),
                                  TCollection_HAsciiString("POSITIVE_RATIO_MEASURE"))
    if fmt == "step":
        writer = STEPCAFControl_Writer()
        for key in ("write.step.unit", "xstep.cascade.unit"):
            Interface_Static.SetCVal_s(key, "MM")
        writer.SetNameMode(True)
        writer.SetMaterialMode(True)
        assert writer.Transfer(doc, STEPControl_AsIs)
        assert int(writer.Write(str(path))) == 1
        return
    from OCP.IGESControl import IGESControl_Controller

    IGESControl_Controller.Init_s()   # registers the parameters below
    assert Interface_Static.SetIVal_s("write.iges.brep.mode", 1)   # solids, not loose faces
    assert Interface_Static.SetCVal_s("write.iges.unit", "MM")
    writer = IGESCAFControl_Writer()   # after: it takes the modes when made
    writer.SetNameMode(True)
    try:
        assert writer.Transfer(doc)
        assert writer.Write(str(path))
    finally:
        Interface_Static.SetIVal_s("write.iges.brep.mode", 0)


def write_iges_faces(shape, path, unit: str = "MM") -> None:
    """One shape to IGES in the writer's default mode (brep mode 0: its faces as trimmed
    surfaces, no shell or solid around them, as many CAD tools write); coordinates taken as
    ``unit`` (no scaling)."""
    from OCP.IGESControl import IGESControl_Writer

    writer = IGESControl_Writer(unit, 0)
    section = writer.Model().GlobalSection()
    section.SetCascadeUnit(section.UnitValue())   # the shape's numbers are in ``unit`` already
    writer.Model().SetGlobalSection(section)
    writer.AddShape(shape)
    writer.ComputeModel()
    assert writer.Write(str(path))


PROFILE = ((3.0, 0.0), (2.2, 1.8), (0.3, 2.6), (-1.6, 1.9), (-2.8, 0.2), (-2.0, -1.7),
           (0.1, -2.4), (2.1, -1.5))
"""Poles of a periodic cubic B-spline profile (uniform knots 0..8): a smooth convex blob."""


def bspline_prism(poles=PROFILE, height: float = 1.5, at: tuple = (0.0, 0.0, 0.0)):
    """The prism of a periodic cubic B-spline profile in the plane z = at[2] (poles offset by
    at[0], at[1]), extruded by ``height`` along z: a surface of linear extrusion for its side,
    two planes bounded by the spline for its caps."""
    from OCP.BRepBuilderAPI import (
        BRepBuilderAPI_MakeEdge,
        BRepBuilderAPI_MakeFace,
        BRepBuilderAPI_MakeWire,
    )
    from OCP.BRepPrimAPI import BRepPrimAPI_MakePrism
    from OCP.collections import Array1_double, Array1_gp_Pnt, Array1_int
    from OCP.Geom import Geom_BSplineCurve

    n = len(poles)
    points = Array1_gp_Pnt(1, n)
    for i, (x, y) in enumerate(poles):
        points.SetValue(i + 1, gp_Pnt(x + at[0], y + at[1], at[2]))
    knots, mults = Array1_double(1, n + 1), Array1_int(1, n + 1)
    for i in range(n + 1):
        knots.SetValue(i + 1, float(i))
        mults.SetValue(i + 1, 1)
    curve = Geom_BSplineCurve(points, knots, mults, 3, True)
    wire = BRepBuilderAPI_MakeWire(BRepBuilderAPI_MakeEdge(curve).Edge()).Wire()
    face = BRepBuilderAPI_MakeFace(wire).Face()
    return BRepPrimAPI_MakePrism(face, gp_Vec(0, 0, height)).Shape()


def slanted_cylinder(r: float, h: float, m: float):
    """x² + y² <= r², 0 <= z <= h + m x (h > m r): a cylinder cut by an oblique plane, its wall
    trimmed by an ellipse (not an iso-line of its parameters)."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Cut
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeFace
    from OCP.BRepPrimAPI import BRepPrimAPI_MakeHalfSpace
    from OCP.gp import gp_Pln

    tall = BRepPrimAPI_MakeCylinder(gp_Ax2(gp_Pnt(0, 0, 0), gp_Dir(0, 0, 1)), r,
                                    2 * (h + abs(m) * r)).Shape()
    plane = BRepBuilderAPI_MakeFace(gp_Pln(gp_Pnt(0, 0, h), gp_Dir(-m, 0, 1))).Face()
    above = BRepPrimAPI_MakeHalfSpace(plane, gp_Pnt(0, 0, 2 * (h + abs(m) * r))).Solid()
    return BRepAlgoAPI_Cut(tall, above).Shape()


def slanted_cylinder_forms(r: float, h: float, m: float) -> tuple[float, tuple, list]:
    """(volume, COM, inertia per unit density about the COM) of slanted_cylinder, from the
    disc's moments (∫x² = π r⁴/4) integrated over z in [0, h + m x]."""
    pi = math.pi
    area, x2 = pi * r * r, pi * r**4 / 4
    v = area * h
    first = (m * x2, 0.0, (h * h * area + m * m * x2) / 2)
    xx, yy = h * x2, h * x2
    zz = (h**3 * area + 3 * h * m * m * x2) / 3
    xz = h * m * x2
    com = tuple(f / v for f in first)
    second = [[xx, 0.0, xz], [0.0, yy, 0.0], [xz, 0.0, zz]]
    c = com
    s = [[second[i][j] - v * c[i] * c[j] for j in range(3)] for i in range(3)]
    trace = s[0][0] + s[1][1] + s[2][2]
    inertia = [[(trace if i == j else 0.0) - s[i][j] for j in range(3)] for i in range(3)]
    return v, com, inertia


def profile_moments(poles):
    """[A, ∫x, ∫y, ∫x², ∫y², ∫xy] of the region inside a periodic cubic B-spline (uniform
    knots), by Green's theorem on each span, where the curve is a cubic polynomial: Gauss-
    Legendre with 10 points is exact for the integrands' degree 11. The curve is evaluated by
    scipy from the poles, independently of OpenCASCADE; and the same moments of a 200,000-gon
    inscribed in it (shoelace formulas), which agree to its O(1/N²)."""
    import numpy as np
    from scipy.interpolate import BSpline

    p = np.asarray(poles, dtype=float)
    n = len(p)
    spline = BSpline(np.arange(-3.0, n + 4), np.vstack([p, p[:3]]), 3)
    slope = spline.derivative()
    g, w = np.polynomial.legendre.leggauss(10)
    total = np.zeros(6)
    for k in range(n):
        t = k + (g + 1) / 2
        (x, y), (dx, dy) = spline(t).T, slope(t).T
        total += [w @ (x * dy), w @ (x * x * dy), -w @ (y * y * dx), w @ (x**3 * dy) * 2 / 3,
                  -w @ (y**3 * dx) * 2 / 3, w @ (x * x * y * dy)]
    total /= [2, 4, 4, 4, 4, 4]   # the Gauss weights' 1/2 with Green's 1, 1/2, 1/2, 1/3, 1/3, 1/2
    q = spline(np.linspace(0, n, 200_000, endpoint=False))
    (x0, y0), (x1, y1) = q.T, np.roll(q, -1, axis=0).T
    c = x0 * y1 - x1 * y0
    gon = np.array([c.sum() / 2, ((x0 + x1) * c).sum() / 6, ((y0 + y1) * c).sum() / 6,
                    ((x0 * x0 + x0 * x1 + x1 * x1) * c).sum() / 12,
                    ((y0 * y0 + y0 * y1 + y1 * y1) * c).sum() / 12,
                    ((x0 * y1 + 2 * x0 * y0 + 2 * x1 * y1 + x1 * y0) * c).sum() / 24])
    assert np.all(np.abs(gon - total) <= 1e-9 * np.abs(total).max())
    return total
