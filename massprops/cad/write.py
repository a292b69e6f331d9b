"""``align`` for CAD files: the exact geometry moved into the principal frame and written as
STEP, IGES or BREP (never over the input, atomically), or tessellated to a mesh format."""

from __future__ import annotations

import os
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from massprops.cad.inspect import CadInspection
from massprops.errors import MeshFileError
from massprops.io.atomic import OutputKind, atomic_write_bytes, check_output
from massprops.io.dispatch import mesh_output

__all__ = ["CadAlignment", "align_cad", "cad_output", "ALIGN_DEFLECTION"]

ALIGN_DEFLECTION = 1e-3
"""Mesh outputs of ``align``: the chord deflection as a fraction of each solid's largest half
extent (volume and inertia then within ~1e-3 of exact, the tessellation's first-order bound,
as meshes exported by CAD tools at their defaults; 1e-4 costs ~10x the triangles)."""

_EXACT = {".step": "step", ".stp": "step", ".iges": "iges", ".igs": "iges", ".brep": "brep"}


@dataclass(frozen=True, eq=False)
class CadAlignment:
    """The map v ↦ rotation @ (v - center_of_mass) (m, file frame -> principal frame) applied to
    every solid; ``tessellated``: the output is a mesh (STL, OBJ, ...), not exact geometry."""

    rotation: np.ndarray
    center_of_mass: np.ndarray
    principal_moments: np.ndarray
    tessellated: bool

    def as_dict(self) -> dict:
        return {"rotation": self.rotation.tolist(),
                "translation": (-(self.rotation @ self.center_of_mass)).tolist(),
                "principal_moments": self.principal_moments.tolist(),
                "tessellated": self.tessellated}


def cad_output() -> OutputKind:
    """The output rule's `OutputKind` for ``align`` of a CAD file: exact geometry (STEP, IGES,
    BREP) or a tessellated mesh in any format massprops writes."""
    return OutputKind("an aligned part", tuple(sorted({*_EXACT, *mesh_output().extensions})))


def align_cad(result: CadInspection, output: str | os.PathLike, *, force: bool = False
              ) -> CadAlignment:
    """Write the file's solids moved by v ↦ Rᵀ(v − c), R and c of the whole (the total, or the
    one solid), in ``output``'s format: STEP/IGES/BREP keep the exact geometry (in the input's
    unit); other extensions are mesh formats and get a tessellation (in the input's unit)."""
    props = result.total[0] if result.total is not None else result.solids[0].properties
    r = props.principal_axes
    c = props.center_of_mass
    cad = result.file
    target = check_output(output, cad_output(), force=force, protect=[cad.name])
    anchor, delta = _anchored_com(result)
    moved = [_moved(s.solid.shape, anchor, delta, r) for s in result.solids]
    kind = _EXACT.get(target.suffix.lower())
    if kind is None:
        _write_mesh(moved, target, cad, force)
    else:
        data = _exact_bytes(moved, kind, cad.unit, target)
        atomic_write_bytes(target, data, force=force, protect=[cad.name])
    return CadAlignment(r.T.copy(), np.array(c), props.principal_moments.copy(), kind is None)


def _anchored_com(result: CadInspection) -> tuple[np.ndarray, np.ndarray]:
    """The whole's COM as anchor + delta, both in the file unit: the anchor the first solid's
    local origin (the float its geometry was integrated about), delta the COM from it (of the
    part's size). One float for the COM of a part 1e6 sizes away is rounded to half an ulp of
    that distance (1e-9 mm at 1.5e7 mm, 8e-11 of a 10 mm part): the written part's COM would be
    off by that much."""
    scale = result.file.scale
    solids = result.solids
    anchors = [np.zeros(3) if s.integral.anchor is None else s.integral.anchor for s in solids]
    anchor = anchors[0]
    masses = np.array([s.properties.mass for s in solids])
    # each solid's COM from the anchor: the anchors' difference (exact where they are close)
    # in the file unit, then the solid's own COM from its anchor (small) in metres
    rel = np.array([(a - anchor) * scale + s.integral.moments.com_local
                    for a, s in zip(anchors, solids)])
    delta = (masses[:, None] * rel).sum(axis=0) / masses.sum()
    return anchor, delta / scale


def _moved(shape: Any, anchor: np.ndarray, delta: np.ndarray, r: np.ndarray) -> Any:
    """The shape's geometry translated by -anchor, then by -delta, THEN rotated by Rᵀ (file
    unit): each far coordinate minus the anchor near it is exact (Sterbenz), and what is left is
    of the part's size; one composite transform would add the rounding of the far coordinates
    back in (as `massprops.inspection.align.to_principal_frame` does for meshes)."""
    # optional extra: OCP is imported only once a CAD file is read
    from OCP.BRepBuilderAPI import BRepBuilderAPI_Transform
    from OCP.gp import gp_Trsf, gp_Vec
    from OCP.TopLoc import TopLoc_Location

    shift = gp_Trsf()
    shift.SetTranslation(gp_Vec(*(-anchor)))
    placement = shape.Location()
    if not placement.IsIdentity():   # into the geometry, as in integrate_solid
        shift = shift.Multiplied(placement.Transformation())
        shape = shape.Located(TopLoc_Location())
    shape = BRepBuilderAPI_Transform(shape, shift, True).Shape()
    near = gp_Trsf()
    near.SetTranslation(gp_Vec(*(-delta)))
    shape = BRepBuilderAPI_Transform(shape, near, True).Shape()
    rotate = gp_Trsf()
    rt = r.T
    rotate.SetValues(*rt[0], 0.0, *rt[1], 0.0, *rt[2], 0.0)
    return BRepBuilderAPI_Transform(shape, rotate, True).Shape()


def _compound(shapes: list) -> Any:
    from OCP.BRep import BRep_Builder  # optional extra
    from OCP.TopoDS import TopoDS_Compound

    builder = BRep_Builder()
    out = TopoDS_Compound()
    builder.MakeCompound(out)
    for s in shapes:
        builder.Add(out, s)
    return out


_OCC_UNITS = {"m": "M", "mm": "MM", "cm": "CM", "um": "UM", "in": "INCH", "ft": "FT"}


def _exact_bytes(shapes: list, kind: str, unit: str, target: Path) -> bytes:
    """The file's bytes, written by OpenCASCADE to a private temporary directory (its writers
    take a path; the atomic publication is ours)."""
    shape = _compound(shapes) if len(shapes) > 1 else shapes[0]
    with tempfile.TemporaryDirectory(dir=target.parent) as tmp:
        path = os.path.join(tmp, "out" + target.suffix.lower())
        ok = _write_native(shape, kind, unit, path)
        if not ok or not os.path.isfile(path):
            raise MeshFileError(f"{target}: OpenCASCADE could not write the {kind.upper()} "
                                "file; check the disk and the directory's permissions")
        with open(path, "rb") as fh:
            return fh.read()


def _write_native(shape: Any, kind: str, unit: str, path: str) -> bool:
    # optional extra: OCP is imported only once a CAD file is read
    from OCP.Interface import Interface_Static

    if kind == "brep":
        from OCP.BRepTools import BRepTools

        return bool(BRepTools.Write_s(shape, path))
    previous = Interface_Static.CVal_s("xstep.cascade.unit")
    try:
        if kind == "step":
            from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer

            writer = STEPControl_Writer()  # first: it initialises the parameters below
            Interface_Static.SetCVal_s("write.step.unit", _OCC_UNITS[unit])
            Interface_Static.SetCVal_s("xstep.cascade.unit", _OCC_UNITS[unit])
            writer.Transfer(shape, STEPControl_AsIs)
            return int(writer.Write(path)) == 1
        from OCP.IGESControl import IGESControl_Writer

        writer = IGESControl_Writer(_OCC_UNITS[unit], 1)   # 1: B-rep mode (solids)
        # the shape's numbers are in the file's unit already: tell the translator so (its
        # "cascade unit", in millimetres), or it rescales them as if they were millimetres
        section = writer.Model().GlobalSection()
        section.SetCascadeUnit(section.UnitValue())
        writer.Model().SetGlobalSection(section)
        writer.AddShape(shape)
        writer.ComputeModel()
        return bool(writer.Write(path))
    finally:
        Interface_Static.SetCVal_s("xstep.cascade.unit", previous)


def _write_mesh(shapes: list, target: Path, cad: Any, force: bool) -> None:
    from massprops.cad.tessellate import tessellate  # CAD branch only
    from massprops.io import write_mesh
    from massprops.mesh import Mesh

    points, faces, offset = [], [], 0
    for shape in shapes:
        from OCP.Bnd import Bnd_Box  # optional extra
        from OCP.BRepBndLib import BRepBndLib

        box = Bnd_Box()
        BRepBndLib.Add_s(shape, box, False)
        lo, hi = box.CornerMin(), box.CornerMax()
        size = max(hi.X() - lo.X(), hi.Y() - lo.Y(), hi.Z() - lo.Z()) / 2
        v, f = tessellate(shape, ALIGN_DEFLECTION * size)
        points.append(v)
        faces.append(f + offset)
        offset += len(v)
    mesh = Mesh(np.concatenate(points), np.concatenate(faces), name=os.fspath(target))
    write_mesh(mesh, target, force=force, protect=(cad.name,))
