"""Loose faces to closed solids: what a writer's face mode leaves (IGES ``brep mode 0``, the
default of OpenCASCADE's ``IGESControl_Writer`` and of many CAD tools, writes a solid as its
trimmed surfaces, entity 144, with no shell or solid around them).

Method. Every face and shell of the file that belongs to no solid is handed to
``BRepBuilderAPI_Sewing`` at once, at the file's own tolerance (`sewing_tolerance`): the
largest tolerance of those faces' edges and vertices, never below the file's stated precision
(for IGES: its resolution, and half the last of the ten digits its writers print, at its
largest coordinate; a 100 m part in mm is uncertain by 1.4e-4 mm from its printed digits
alone). Each sewn shell that closes (no free edge: each used by two faces, a seam by its
one face twice) becomes a solid, oriented outward (``BRepLib::OrientClosedSolid``: the
classifier puts infinity outside); what does not close stays as it was, an open shell, and is
refused as before (or taken by ``--allow-open`` / ``--shell``). The sewing tolerance goes to the
solid's ``input`` bar: a gap of width τ closed anywhere on the surface moves the boundary by
at most τ, so ∫g dV moves by at most max|g| τ A (`massprops.cad.inspect`).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any

__all__ = ["Sewn", "sew_loose", "sewing_tolerance"]


@dataclass(frozen=True, eq=False)
class Sewn:
    """One closed solid made from loose faces: ``solid`` (TopoDS_Solid, oriented outward),
    ``pieces`` (indices of the input shapes whose faces it holds), ``faces`` (how many)."""

    solid: Any
    pieces: tuple[int, ...]
    faces: int


@functools.cache
def _occ() -> SimpleNamespace:
    """OpenCASCADE names used here (optional extra, imported once with the first CAD file)."""
    from OCP.BRep import BRep_Builder, BRep_Tool
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeSolid, BRepBuilderAPI_Sewing
    from OCP.BRepLib import BRepLib
    from OCP.collections import IndexedMap_TopoDS_Shape_TopTools_ShapeMapHasher as ShapeMap
    from OCP.ShapeAnalysis import ShapeAnalysis_ShapeTolerance
    from OCP.TopAbs import TopAbs_FACE, TopAbs_SHAPE, TopAbs_SHELL
    from OCP.TopExp import TopExp_Explorer
    from OCP.TopoDS import TopoDS, TopoDS_Shell

    return SimpleNamespace(Builder=BRep_Builder, BRep_Tool=BRep_Tool,
                           MakeSolid=BRepBuilderAPI_MakeSolid, Sewing=BRepBuilderAPI_Sewing,
                           BRepLib=BRepLib, Tolerance=ShapeAnalysis_ShapeTolerance,
                           FACE=TopAbs_FACE, SHAPE=TopAbs_SHAPE, SHELL=TopAbs_SHELL,
                           Explorer=TopExp_Explorer, TopoDS=TopoDS, Shell=TopoDS_Shell,
                           Map=ShapeMap)


def sewing_tolerance(shapes: list, precision: float) -> float:
    """The tolerance the loose faces are sewn at (their file unit): the largest tolerance of
    their faces, edges and vertices (the translator widens each to the gap it found), and at
    least ``precision``, what the file itself states or implies (see the module)."""
    k = _occ()
    largest = precision
    for shape in shapes:
        largest = max(largest, float(k.Tolerance().Tolerance(shape, 1, k.SHAPE)))
    return largest


def sew_loose(shapes: list, tolerance: float) -> list[Sewn]:
    """The closed solids the loose ``shapes`` (faces and shells, placed) sew into at
    ``tolerance``; shapes whose faces end in an open shell are in none of them."""
    k = _occ()
    sewing = k.Sewing(tolerance)
    for shape in shapes:
        sewing.Add(shape)
    sewing.Perform()
    result = sewing.SewedShape()
    shells = _shells(result)
    out = []
    for shell in shells:
        faces = k.Map()
        explorer = k.Explorer(shell, k.FACE)
        while explorer.More():
            faces.Add(explorer.Current())
            explorer.Next()
        if not _closes(shell):
            continue
        solid = k.MakeSolid(shell).Solid()
        if not k.BRepLib.OrientClosedSolid_s(solid):   # the classifier could not tell inside
            continue
        pieces = tuple(i for i, shape in enumerate(shapes) if _in(sewing, shape, faces))
        out.append(Sewn(solid, pieces, faces.Extent()))
    return out


def _shells(result: Any) -> list:
    """The sewn result as shells: a lone face (a sphere's or a torus's one face, sewn to
    itself along its seam) comes back bare and is wrapped in a shell of its own."""
    k = _occ()
    shells = []
    explorer = k.Explorer(result, k.SHELL)
    while explorer.More():
        shells.append(k.TopoDS.Shell(explorer.Current()))
        explorer.Next()
    explorer = k.Explorer(result, k.FACE, k.SHELL)
    while explorer.More():
        shell = k.Shell()
        k.Builder().MakeShell(shell)
        k.Builder().Add(shell, explorer.Current())
        shells.append(shell)
        explorer.Next()
    return shells


def _closes(shell: Any) -> bool:
    """Every edge of the shell used an even number of times by its faces (a seam counts
    twice): no free edge left, a gap wider than the tolerance (``BRep_Tool::IsClosed``)."""
    return bool(_occ().BRep_Tool.IsClosed_s(shell))


def _in(sewing: Any, shape: Any, faces: Any) -> bool:
    """Whether the (sewn form of the) first face of ``shape`` is one of ``faces``."""
    k = _occ()
    explorer = k.Explorer(shape, k.FACE)
    if not explorer.More():
        return False
    face = explorer.Current()
    sewn = sewing.Modified(face) if sewing.IsModified(face) else face
    return faces.Contains(sewn) or faces.Contains(sewn.Reversed())
