"""What an XCAF document says about a part: its name, colour and material (STEP, IGES).

Names: the product or instance name (``TDataStd_Name``). IGES files name entities in two
ways, a name property (entity 406) and the 8-character label of the directory entry; the
translator takes the first and, when an entity has neither, names the part after its shape
type (``COMPOUND``, ``SOLID``): those are not the file's names, so `iges_name` asks the entity
itself and falls back on its label, else on nothing (the caller numbers it).
Materials: STEP's material designation with its density (OpenCASCADE keeps that density in
g/cm³, the unit its translator writes: gram per cubic centimetre), reported in kg/m³; else a
visual material's name. The solid takes that density unless ``--density`` or ``--density-map``
says otherwise (`massprops.cad.inspect`).
"""

from __future__ import annotations

from typing import Any

__all__ = ["colour", "iges_name", "label_name", "material"]


def label_name(label: Any) -> str:
    from OCP.TDataStd import TDataStd_Name  # optional extra

    attr = TDataStd_Name()
    if label.IsAttribute(TDataStd_Name.GetID_s()) and label.FindAttribute(
            TDataStd_Name.GetID_s(), attr):
        return attr.Get().ToExtString()
    return ""


def iges_name(reader: Any, shape: Any) -> str:
    """The IGES entity's own name, else its directory label (with its subscript), else ""."""
    entity = reader.WS().TransferReader().EntityFromShapeResult(shape, -1)
    if entity is None or not hasattr(entity, "HasName"):
        return ""
    if entity.HasName():
        return entity.NameValue().ToCString().strip()
    if entity.HasShortLabel():
        text = entity.ShortLabel().ToCString().strip()
        number = entity.SubscriptNumber() if entity.HasSubscriptNumber() else 0
        return f"{text}.{number}" if text and number else text
    return ""


def colour(label: Any) -> tuple[float, float, float] | None:
    from OCP.Quantity import Quantity_Color  # optional extra
    from OCP.XCAFDoc import XCAFDoc_ColorTool, XCAFDoc_ColorType

    value = Quantity_Color()
    for kind in (XCAFDoc_ColorType.XCAFDoc_ColorSurf, XCAFDoc_ColorType.XCAFDoc_ColorGen):
        if XCAFDoc_ColorTool.GetColor_s(label, kind, value):
            return (value.Red(), value.Green(), value.Blue())
    return None


def material(label: Any) -> dict | None:
    """{"name", "density" kg/m³ (when given), "description" (when given)} or {"name"} of a
    visual material, else None."""
    from OCP.TDataStd import TDataStd_TreeNode  # optional extra
    from OCP.XCAFDoc import XCAFDoc, XCAFDoc_DocumentTool, XCAFDoc_Material

    node = TDataStd_TreeNode()
    # IsAttribute first: FindAttribute's handle comes back broken when there is none
    if label.IsAttribute(XCAFDoc.MaterialRefGUID_s()) and label.FindAttribute(
            XCAFDoc.MaterialRefGUID_s(), node) and node.HasFather():
        found = XCAFDoc_Material()
        if node.Father().Label().FindAttribute(XCAFDoc_Material.GetID_s(), found):
            out: dict = {"name": _text(found.GetName())}
            if found.GetDensity() > 0:
                out["density"] = 1000.0 * found.GetDensity()   # g/cm³ -> kg/m³
            if _text(found.GetDescription()):
                out["description"] = _text(found.GetDescription())
            return out
    # through the document's tool: the static lookup crashes on a document without one (IGES)
    tool = XCAFDoc_DocumentTool.VisMaterialTool_s(label)
    if tool is None or not tool.IsSetShapeMaterial(label):
        return None
    visual = tool.GetShapeMaterial(label)
    if visual is not None and visual.RawName() is not None:
        name = _text(visual.RawName())
        if name:
            return {"name": name}
    return None


def _text(value: Any) -> str:
    return "" if value is None else value.ToCString()
