"""CAD files to solids: names, assembly paths, placements and the file's length unit.

STEP and IGES go through OpenCASCADE's XCAF readers (product names, assembly structure,
colours); BREP files hold one shape and no unit (``unit`` says it, default metres). The geometry
is kept in the FILE's unit (the translator's conversion to millimetres is switched off while
reading): scaling far-away coordinates before integrating would round them (1e-8 at 1e8 sizes);
the integral converts its results instead. Faces and shells that belong to no solid (IGES
written in face mode) are sewn into closed solids where they close (`massprops.cad.sew`), at
least at the file's own precision (IGES: its resolution and its ten printed digits).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from massprops.cad.labels import colour, iges_name, label_name, material
from massprops.cad.occ import quiet_stdout, require_occ
from massprops.errors import (
    MeshFormatError,
    UnknownFormatError,
    UsageError,
    setting_ref,
)
from massprops.files import check_input_file

__all__ = ["CadFile", "CadSolid", "UNIT_METRES", "read_cad"]

UNIT_METRES = {"m": 1.0, "cm": 0.01, "mm": 0.001, "um": 1e-6, "in": 0.0254, "ft": 0.3048}
"""The --unit choices (as for meshes), in metres."""

# STEP/IGES unit names as OpenCASCADE reports them -> (our unit, the translator's name for it)
_FILE_UNITS = {"metre": ("m", "M"), "meter": ("m", "M"), "m": ("m", "M"),
               "millimetre": ("mm", "MM"), "millimeter": ("mm", "MM"), "mm": ("mm", "MM"),
               "centimetre": ("cm", "CM"), "centimeter": ("cm", "CM"), "cm": ("cm", "CM"),
               "micrometre": ("um", "UM"), "micrometer": ("um", "UM"), "um": ("um", "UM"),
               "micron": ("um", "UM"), "inch": ("in", "INCH"), "in": ("in", "INCH"),
               "foot": ("ft", "FT"), "ft": ("ft", "FT")}


@dataclass(frozen=True, eq=False)
class CadSolid:
    """One solid (or, with allow_open, an open shell) of a CAD file.

    name : product name from the file, else ``solid1``, ``solid2``, ... in file order.
    path : its place in the assembly, names joined by '/'.
    shape : the OpenCASCADE TopoDS_Shape, placed in the file's (assembly) frame, file unit.
    placement : (4, 4) float64, the instance's placement (file frame <- the part's own frame),
        translation in the file unit.
    closed : False for a shell or face set that bounds no solid.
    colour : (r, g, b) in 0..1 when the file gives one, else None.
    material : {"name", "density" kg/m³, ...} when the file gives one (`massprops.cad.labels`),
        else None.
    sewn : the tolerance (file unit) at which the file's loose faces were sewn: for a solid
        made of them (``faces`` of them), or for loose faces that did not close at it; None
        for a solid as the file wrote it.
    """

    name: str
    path: str
    shape: Any
    placement: np.ndarray
    closed: bool
    colour: tuple[float, float, float] | None = None
    material: dict | None = None
    sewn: float | None = None
    faces: int = 0


@dataclass(frozen=True, eq=False)
class CadFile:
    """format : "step" | "iges" | "brep". unit : the file's length unit (a UNIT_METRES key).
    scale : metres per file unit. solids : in file order. digits : significant digits the file's
    numbers carry when the format limits them (IGES writers: 10), else None."""

    name: str
    format: str
    unit: str
    scale: float
    solids: tuple[CadSolid, ...]
    digits: int | None = None


def read_cad(path: str | os.PathLike, *, unit: str | None = None) -> CadFile:
    """Read a STEP (.step/.stp), IGES (.iges/.igs) or BREP (.brep) file.

    unit : for BREP, the file's unit (default "m"); for STEP/IGES, None or the file's own unit
        (a different one is a UsageError: the file says what its numbers mean).
    Raises CadExtraMissingError (no OpenCASCADE), MeshFileError, MeshFormatError.
    """
    name = os.fspath(path)
    ext = os.path.splitext(name)[1].lower()
    fmt = {".step": "step", ".stp": "step", ".iges": "iges", ".igs": "iges",
           ".brep": "brep"}.get(ext)
    if fmt is None:
        raise UnknownFormatError(f"{name}: not a CAD file extension ({ext!r}); expected .step, "
                                 ".stp, .iges, .igs or .brep")
    check_input_file(name, what="a CAD file")  # OpenCASCADE opens it by its path
    if unit is not None and unit not in UNIT_METRES:
        raise UsageError(f"{name}: unknown unit {unit!r}; expected one of {sorted(UNIT_METRES)}")
    require_occ(name)
    if fmt == "brep":
        return _read_brep(name, unit or "m")
    return _read_xcaf(name, fmt, unit)


def _read_brep(name: str, unit: str) -> CadFile:
    # optional extra: OCP is imported only once a CAD file is read
    from OCP.BRep import BRep_Builder
    from OCP.BRepTools import BRepTools
    from OCP.TopoDS import TopoDS_Shape

    shape = TopoDS_Shape()
    try:
        with quiet_stdout():
            ok = BRepTools.Read_s(shape, name, BRep_Builder())
    except Exception as exc:  # the binding raises its own types on a malformed file
        raise MeshFormatError(f"{name}: not a readable BREP file ({exc}); check the file") from exc
    if not ok or shape.IsNull():
        raise MeshFormatError(f"{name}: not a readable BREP file; check that it was written by "
                              "BRepTools (OpenCASCADE's native format)")
    pieces = _split(shape, "", "", np.eye(4), None, None, 0)
    return CadFile(name, "brep", unit, UNIT_METRES[unit], _solids(pieces, 0.0))


def _read_xcaf(name: str, fmt: str, unit: str | None) -> CadFile:
    # optional extra: OCP is imported only once a CAD file is read
    from OCP.collections import Sequence_TDF_Label as TDF_LabelSequence
    from OCP.Interface import Interface_Static
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDocStd import TDocStd_Document
    from OCP.XCAFDoc import XCAFDoc_DocumentTool

    reader = _xcaf_reader(fmt)
    with quiet_stdout():
        status = reader.ReadFile(name)
    if int(status) != 1:   # 1: IFSelect_RetDone
        raise MeshFormatError(f"{name}: not a readable {fmt.upper()} file (translator status "
                              f"{status}); check that the file is complete")
    # the unit from the model just parsed (parsing the file a second time for it cost a
    # quarter of the whole read on a 2.5 MB part); the translator applies it at Transfer
    file_unit, occ_unit = _file_unit(name, fmt, reader)
    if unit is not None and unit != file_unit:
        raise UsageError(f"{name}: {setting_ref('unit')} {unit} disagrees with the file's own "
                         f"unit ({file_unit}); drop {setting_ref('unit')} (the file says what its "
                         "numbers mean)")
    previous = Interface_Static.CVal_s("xstep.cascade.unit")
    previous_curves = Interface_Static.IVal_s("read.surfacecurve.mode")
    Interface_Static.SetCVal_s("xstep.cascade.unit", occ_unit)  # keep the file's numbers
    precision = _iges_precision(reader) if fmt == "iges" else 0.0
    if fmt == "iges":
        # a trimmed surface's boundary is stored twice, in 3D and in the surface's parameters;
        # the parameter copy, printed to ten digits, does not close (2π printed as
        # 6.283185307): taking it, as the file's preference flag asks, the translator built a
        # 100 m torus's face with two overlapping loops (invalid, volume ~0); the 3D curves,
        # projected, gave valid faces on every part tried (3: prefer 3D)
        Interface_Static.SetIVal_s("read.surfacecurve.mode", 3)
    try:
        doc = TDocStd_Document(TCollection_ExtendedString("massprops"))
        # the document's own length unit, else XCAF rescales to millimetres
        XCAFDoc_DocumentTool.SetLengthUnit_s(doc, UNIT_METRES[file_unit])
        with quiet_stdout():
            done = reader.Transfer(doc)
        if not done:
            raise MeshFormatError(f"{name}: not a readable {fmt.upper()} file (the translator "
                                  "found no shapes to transfer); check that the file is complete")
    finally:
        Interface_Static.SetCVal_s("xstep.cascade.unit", previous)
        Interface_Static.SetIVal_s("read.surfacecurve.mode", previous_curves)
    tool = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())
    roots = TDF_LabelSequence()
    tool.GetFreeShapes(roots)
    pieces: list[_Piece] = []
    for i in range(1, roots.Length() + 1):
        _walk(tool, reader, roots.Value(i), None, "", name, pieces)
    return CadFile(name, fmt, file_unit, UNIT_METRES[file_unit], _solids(pieces, precision),
                   IGES_DIGITS if fmt == "iges" else None)


IGES_DIGITS = 10
"""Significant digits IGES writers print (OpenCASCADE's: 6.283185307 for 2π, whatever the
global section claims)."""


def _iges_precision(reader: Any) -> float:
    """What an IGES file's numbers are good to (file unit): its stated resolution, and at
    least half the last printed digit at its largest coordinate (the global section's)."""
    section = reader.IGESModel().GlobalSection()
    return max(float(section.Resolution()),
               0.5 * 10.0 ** (1 - IGES_DIGITS) * abs(float(section.MaxCoord())))


def _xcaf_reader(fmt: str) -> Any:
    if fmt == "step":
        from OCP.STEPCAFControl import STEPCAFControl_Reader  # optional extra

        reader = STEPCAFControl_Reader()
    else:
        from OCP.IGESCAFControl import IGESCAFControl_Reader  # optional extra

        reader = IGESCAFControl_Reader()
    reader.SetNameMode(True)
    reader.SetColorMode(True)
    if fmt == "step":
        reader.SetMatMode(True)
    return reader


def _file_unit(name: str, fmt: str, reader: Any) -> tuple[str, str]:
    """(our unit name, the translator's name) of the file's length unit (first one given), from
    an XCAF reader that has parsed the file."""
    if fmt == "step":
        from OCP.collections import Sequence_TCollection_AsciiString as Names  # optional extra

        lengths, angles, solid_angles = Names(), Names(), Names()
        reader.Reader().FileUnits(lengths, angles, solid_angles)
        found = [lengths.Value(i).ToCString().lower() for i in range(1, lengths.Length() + 1)]
    else:
        model = reader.IGESModel()
        unit_name = model.GlobalSection().UnitName()
        if unit_name is None or model.NbEntities() == 0:
            raise MeshFormatError(f"{name}: not a readable IGES file (no global section or no "
                                  "entities); check that the file is complete")
        found = [unit_name.ToCString().lower()]
    for text in found:
        key = text.strip().strip("'").split()[0] if text.strip() else ""
        if key in _FILE_UNITS:
            return _FILE_UNITS[key]
    if not found or not found[0]:
        return "mm", "MM"  # STEP/IGES default when a file names none
    raise MeshFormatError(f"{name}: unsupported length unit {found[0]!r}; expected metres, "
                          "millimetres, centimetres, micrometres, inches or feet")


def _walk(tool: Any, reader: Any, label: Any, location: Any, prefix: str, file: str,
          out: list[_Piece]) -> None:
    """Depth first through the assembly: components carry their placement down."""
    from OCP.collections import Sequence_TDF_Label as TDF_LabelSequence  # optional extra
    from OCP.TDF import TDF_Label
    from OCP.TopLoc import TopLoc_Location
    from OCP.XCAFDoc import XCAFDoc_ShapeTool

    location = TopLoc_Location() if location is None else location
    name = label_name(label)
    if XCAFDoc_ShapeTool.IsAssembly_s(label):
        components = TDF_LabelSequence()
        XCAFDoc_ShapeTool.GetComponents_s(label, components, False)
        here = f"{prefix}{name or 'assembly'}/"
        for i in range(1, components.Length() + 1):
            component = components.Value(i)
            referred = TDF_Label()
            XCAFDoc_ShapeTool.GetReferredShape_s(component, referred)
            placed = location.Multiplied(XCAFDoc_ShapeTool.GetLocation_s(component))
            _walk(tool, reader, referred, placed, here, file, out)
        return
    shape = XCAFDoc_ShapeTool.GetShape_s(label)
    if shape.IsNull():
        return
    if hasattr(reader, "IGESModel"):
        name = iges_name(reader, shape)   # not the shape type the translator puts instead
    matrix = _matrix(location)
    placed = shape if location.IsIdentity() else shape.Moved(location)
    out.extend(_split(placed, prefix, name, matrix, colour(label), material(label),
                      len(out) and out[-1].part + 1))


@dataclass(frozen=True, eq=False)
class _Piece:
    """A solid, shell or loose face of one part, before sewing and naming. part : which part
    (label) of the file it belongs to, in file order."""

    shape: Any
    prefix: str
    name: str
    matrix: np.ndarray
    rgb: tuple[float, float, float] | None
    material: dict | None
    part: int
    solid: bool


def _split(shape: Any, prefix: str, name: str, matrix: np.ndarray,
           rgb: tuple[float, float, float] | None, carried: dict | None, part: int
           ) -> list[_Piece]:
    """The solids of one part, then its shells and faces that belong to no solid (open)."""
    from OCP.TopAbs import TopAbs_FACE, TopAbs_SHELL, TopAbs_SOLID  # optional extra
    from OCP.TopExp import TopExp_Explorer

    out: list[_Piece] = []
    for kind, outside in ((TopAbs_SOLID, None), (TopAbs_SHELL, TopAbs_SOLID),
                          (TopAbs_FACE, TopAbs_SHELL)):
        explorer = (TopExp_Explorer(shape, kind) if outside is None else
                    TopExp_Explorer(shape, kind, outside))
        while explorer.More():
            out.append(_Piece(explorer.Current(), prefix, name, matrix, rgb, carried, part,
                              kind == TopAbs_SOLID))
            explorer.Next()
    return out


def _solids(pieces: list[_Piece], precision: float) -> tuple[CadSolid, ...]:
    """The pieces as named solids, in file order, the loose ones sewn first (`massprops.cad.
    sew`, at least at ``precision``): a sewn solid takes the place, part and name of its
    first face (no name when its faces come from several parts)."""
    loose = [i for i, piece in enumerate(pieces) if not piece.solid]
    tolerance, faces = None, {}
    if loose:
        from massprops.cad.sew import sew_loose, sewing_tolerance  # same layer; loose faces

        shapes = [pieces[i].shape for i in loose]
        tolerance = sewing_tolerance(shapes, precision)
        replaced: dict[int, _Piece] = {}
        taken: set[int] = set()
        for sewn in sew_loose(shapes, tolerance):
            members = [loose[j] for j in sewn.pieces]
            if not members:
                continue
            first = pieces[members[0]]
            if any(pieces[i].part != first.part for i in members):
                first = _Piece(first.shape, first.prefix, "", np.eye(4), None, None,
                               -1 - len(replaced), False)
            replaced[members[0]] = _Piece(sewn.solid, first.prefix, first.name, first.matrix,
                                          first.rgb, first.material, first.part, True)
            faces[id(replaced[members[0]])] = sewn.faces
            taken.update(members)
        pieces = [replaced.get(i, piece) for i, piece in enumerate(pieces)
                  if i in replaced or i not in taken]
    per_part: dict[int, int] = {}
    for piece in pieces:
        per_part[piece.part] = per_part.get(piece.part, 0) + 1
    out: list[CadSolid] = []
    seen: dict[int, int] = {}
    for number, piece in enumerate(pieces, start=1):
        k = seen.get(piece.part, 0)
        seen[piece.part] = k + 1
        label = (f"solid{number}" if not piece.name else
                 piece.name if per_part[piece.part] == 1 else f"{piece.name}.{k + 1}")
        made = id(piece) in faces or not piece.solid   # sewn, or loose and left open
        out.append(CadSolid(label, piece.prefix + label, piece.shape, piece.matrix,
                            piece.solid and _closed(piece.shape), piece.rgb, piece.material,
                            tolerance if made else None, faces.get(id(piece), 0)))
    return tuple(out)


def _closed(solid: Any) -> bool:
    """Every shell of the solid closed (each edge shared by two faces)."""
    from OCP.BRep import BRep_Tool  # optional extra
    from OCP.TopAbs import TopAbs_SHELL
    from OCP.TopExp import TopExp_Explorer

    explorer = TopExp_Explorer(solid, TopAbs_SHELL)
    found = False
    while explorer.More():
        found = True
        if not BRep_Tool.IsClosed_s(explorer.Current()):
            return False
        explorer.Next()
    return found


def _matrix(location: Any) -> np.ndarray:
    """(4, 4) of a TopLoc_Location (translation in the file unit; the caller scales it)."""
    trsf = location.Transformation()
    out = np.eye(4)
    for i in range(3):
        for j in range(4):
            out[i, j] = trsf.Value(i + 1, j + 1)
    return out
