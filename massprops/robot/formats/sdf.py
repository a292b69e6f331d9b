"""SDFormat: links of every model (nested models too), inertials and collision/visual geometry.

Conventions (sdformat.org specification, 1.4-1.11): ``<pose>x y z roll pitch yaw</pose>`` is
fixed-axis rpy like URDF (``degrees="true"`` for degrees; ``rotation_format="quat_xyzw"`` for
x y z qx qy qz qw). A pose is expressed in the frame named by ``relative_to``, by default the
parent element's frame (the link for collisions, visuals and the inertial; the model for links;
the child link for joints; ``attached_to`` for frames): massprops resolves ``relative_to`` through
the model's links, frames and joints. The inertial pose's origin is the centre of mass and the
``<inertia>`` entries are the tensor about it in the inertial frame's axes, products as matrix
entries (ixy = -∫xy dm, as massprops). Missing ``<mass>``/``<inertia>`` entries take SDF's
defaults (mass 1, ixx = iyy = izz = 1, products 0), with a warning: those are placeholders.
Geometry: ``<box><size>`` full edges, ``<cylinder>``/``<capsule>`` ``<radius><length>`` along z
(capsule length without its caps), ``<sphere><radius>``, ``<ellipsoid><radii>``,
``<mesh><uri><scale>``. ``<plane>`` and ``<heightmap>`` (no finite volume) are ignored with a
warning.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any, cast

import numpy as np

from massprops.robot.formats.poses import quat_matrix, rpy_matrix
from massprops.robot.formats.sdf_include import expand_sdf_includes
from massprops.robot.formats.uris import resolve_uri
from massprops.robot.formats.values import Values
from massprops.robot.formats.xmltree import Node
from massprops.robot.model import Geometry, Link, RobotModel, StatedInertial, pick_source

__all__ = ["parse_sdf"]

Pose = tuple[np.ndarray, np.ndarray]  # (rotation A, translation t): v_parent = A v + t
_IDENTITY: Pose = (np.eye(3), np.zeros(3))
_INERTIA_KEYS = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
_INERTIA_DEFAULTS = {"ixx": 1.0, "iyy": 1.0, "izz": 1.0, "ixy": 0.0, "ixz": 0.0, "iyz": 0.0}


def parse_sdf(root: Node, data: bytes, path: Path, *, source: str = "collision",
              package_paths: Sequence[Path] = ()) -> RobotModel:
    """The links of every ``<model>`` in an SDF file (root ``<sdf>``)."""
    v = Values(path)
    if root.tag != "sdf":
        raise v.error(root, "expected an SDF file whose root element is <sdf>")
    expand_sdf_includes(root, path, package_paths)
    models = [m for m in root.iter("model")]
    if not models:
        raise v.error(root, "no <model> found; nothing to compute")
    links = []
    for model in models:
        prefix = _scope(model)
        frames = _FrameGraph(model, v)
        for node in model.findall("link"):
            name = node.attrs.get("name")
            if not name:
                raise v.error(node, 'a link needs a name="..."')
            warnings: list[str] = []
            inertial = node.find("inertial")
            stated = _stated(inertial, v, warnings) if inertial is not None else None
            geoms = []
            used = pick_source(source, node.findall("collision"), node.findall("visual"))
            auto = inertial is not None and _is_auto(inertial)
            if auto:  # the simulator integrates the collisions: their density, and the mass
                used = "collision"
            for element in node.findall(used):
                geom = _geometry(element, name, frames, v, path, package_paths, warnings)
                if geom is not None and auto:
                    geom = replace(geom, density=_density(element, inertial, v))
                if geom is not None:
                    geoms.append(geom)
            mass = None
            if auto and inertial.find("mass") is not None:
                mass = v.positive(inertial.find("mass"), "<mass>", float(
                    v.text(inertial.find("mass"), 1, "<mass>1.5</mass>")[0]))
            links.append(Link(prefix + name, node, stated, tuple(geoms), inertial,
                              tuple(warnings), source=used, auto_mass=mass))
    return RobotModel(path, "sdf", tuple(links), data)


def _scope(model: Node) -> str:
    """``outer::inner::`` for a nested model's links; "" for a top-level model's."""
    names = []
    node = model.parent
    while node is not None and node.tag == "model":
        names.append(node.attrs.get("name", "?"))
        node = node.parent
    inner = list(reversed(names))
    if model.parent is not None and model.parent.tag == "model":
        inner.append(model.attrs.get("name", "?"))
    return "".join(n + "::" for n in inner)


def pose_of(node: Node | None, v: Values) -> tuple[Pose, str]:
    """The ``<pose>`` child of ``node``: ((A, t), relative_to or "")."""
    pose = None if node is None else node.find("pose")
    if pose is None:
        return _IDENTITY, ""
    fmt = pose.attrs.get("rotation_format", "euler_rpy")
    degrees = pose.attrs.get("degrees", "false").strip().lower()
    if degrees not in ("true", "false", "1", "0"):
        raise v.error(pose, f"degrees={pose.attrs['degrees']!r}: expected true or false")
    if fmt == "euler_rpy":
        x = v.text(pose, 6, "<pose>0 0 0 0 0 0</pose>") if pose.text.strip() else np.zeros(6)
        angles = np.radians(x[3:]) if degrees in ("true", "1") else x[3:]
        return (rpy_matrix(*angles), x[:3]), pose.attrs.get("relative_to", "")
    if fmt == "quat_xyzw":
        x = v.text(pose, 7, "<pose rotation_format='quat_xyzw'>0 0 0 0 0 0 1</pose>")
        return (quat_matrix([x[6], x[3], x[4], x[5]]), x[:3]), pose.attrs.get("relative_to", "")
    raise v.error(pose, f"rotation_format={fmt!r}: expected euler_rpy or quat_xyzw")


def _compose(a: Pose, b: Pose) -> Pose:
    return a[0] @ b[0], a[0] @ b[1] + a[1]


def _inverse(a: Pose) -> Pose:
    return a[0].T, -(a[0].T @ a[1])


class _FrameGraph:
    """Poses of a model's links, frames and joints in the model frame (``__model__``)."""

    def __init__(self, model: Node, v: Values) -> None:
        self.v = v
        self.nodes: dict[str, tuple[Node, str]] = {}   # name -> (element, default frame)
        for kind in ("link", "frame", "joint"):
            for node in model.findall(kind):
                name = node.attrs.get("name", "")
                if kind == "link":
                    default = "__model__"
                elif kind == "frame":
                    default = node.attrs.get("attached_to", "") or "__model__"
                else:
                    child = node.find("child")
                    default = child.text.strip() if child is not None else "__model__"
                self.nodes[name] = (node, default)
        self.cache: dict[str, Pose] = {"__model__": _IDENTITY}

    def in_model(self, name: str, seen: tuple[str, ...] = ()) -> Pose:
        if name in self.cache:
            return self.cache[name]
        if name not in self.nodes:
            raise KeyError(name)
        node, default = self.nodes[name]
        if name in seen:
            raise self.v.error(node, f"pose frames form a loop through {name!r} "
                                     f"({' -> '.join(seen + (name,))}); fix relative_to")
        local, relative_to = pose_of(node, self.v)
        parent = relative_to or default
        if parent not in self.cache and parent not in self.nodes:
            raise self.v.error(node, f"relative_to/attached_to {parent!r}: no such frame in "
                                     "this model")
        pose = _compose(self.in_model(parent, seen + (name,)), local)
        self.cache[name] = pose
        return pose

    def in_link(self, link: str, element: Node) -> Pose:
        """The pose of ``element`` (a collision or visual) in the link frame."""
        local, relative_to = pose_of(element, self.v)
        if not relative_to or relative_to == link:
            return local
        try:
            frame = self.in_model(relative_to)
        except KeyError:  # relative_to came from its <pose>
            raise self.v.error(cast(Node, element.find("pose")), f"relative_to={relative_to!r}: "
                               "no such frame in this model") from None
        return _compose(_inverse(self.in_model(link)), _compose(frame, local))


_DENSITY = 1000.0  # kg/m³: sdformat's Collision::DensityDefault (water)


def _is_auto(inertial: Node) -> bool:
    return inertial.attrs.get("auto", "false").strip().lower() in ("true", "1")


def _density(collision: Node, inertial: Node, v: Values) -> float:
    """SDF 1.11 auto inertial: the collision's ``<density>``, else the inertial's, else 1000."""
    for node in (collision, inertial):
        el = node.find("density")
        if el is not None:
            return v.positive(el, "<density>", float(v.text(el, 1, "<density>1000</density>")[0]))
    return _DENSITY


def _stated(node: Node, v: Values, warnings: list[str]) -> StatedInertial | None:
    if _is_auto(node):
        warnings.append("<inertial auto=\"true\">: the simulator computes it from the "
                        "collisions (their <density>, default 1000 kg/m³, scaled to <mass> when "
                        "given), and so does massprops; nothing stated to compare")
        return None
    (rotation, xyz), relative_to = pose_of(node, v)
    if relative_to:  # read from its <pose>
        raise v.error(cast(Node, node.find("pose")), "an inertial pose is always in the link "
                                                     "frame; remove relative_to")
    mass_el = node.find("mass")
    defaulted = []
    mass = 1.0
    if mass_el is None:
        defaulted.append("mass")
    else:
        mass = float(v.text(mass_el, 1, "<mass>1.5</mass>")[0])
    k = dict(_INERTIA_DEFAULTS)
    inertia_el = node.find("inertia")
    for key in _INERTIA_KEYS:
        el = None if inertia_el is None else inertia_el.find(key)
        if el is None:
            defaulted.append(key)
        else:
            k[key] = float(v.text(el, 1, f"<{key}>0.01</{key}>")[0])
    if defaulted:
        warnings.append(f"stated inertial (line {node.line}) leaves {', '.join(defaulted)} to "
                        "SDF's defaults (mass 1, ixx = iyy = izz = 1): a placeholder")
    j = np.array([[k["ixx"], k["ixy"], k["ixz"]], [k["ixy"], k["iyy"], k["iyz"]],
                  [k["ixz"], k["iyz"], k["izz"]]])
    return StatedInertial(mass, xyz, rotation @ j @ rotation.T, node)


def _geometry(element: Node, link: str, frames: _FrameGraph, v: Values, path: Path,
              package_paths: Sequence[Path], warnings: list[str]) -> Geometry | None:
    rotation, xyz = frames.in_link(link, element)
    geometry = element.find("geometry")
    shape = None if geometry is None else next(iter(geometry.children), None)
    if shape is None:
        raise v.error(element, "expected a <geometry> with one shape inside")
    common: dict[str, Any] = {"node": shape, "rotation": rotation, "translation": xyz}
    tag = shape.tag

    def length(name: str) -> float:
        value = v.child_text(shape, name, 1, example=f"<{name}>0.1</{name}>")
        if value is None:
            raise v.error(shape, f"missing <{name}> (metres)")
        return v.positive(shape, name, float(value[0]), allow_zero=(tag, name) == (
            "capsule", "length"))

    if tag == "box":
        size = v.child_text(shape, "size", 3, [1, 1, 1], "<size>0.1 0.2 0.3</size>")
        return Geometry("box", dims=tuple(v.positive(shape, "size", float(s)) for s in size),
                        **common)
    if tag == "sphere":
        return Geometry("sphere", dims=(length("radius"),), **common)
    if tag in ("cylinder", "capsule"):
        return Geometry(tag, dims=(length("radius"), length("length")), **common)
    if tag == "cone":  # 1.11: frame at mid-height (sdformat's Cone), the solid's at its COM
        radius, height = length("radius"), length("length")
        common["translation"] = xyz + rotation @ np.array([0.0, 0.0, -height / 4])
        return Geometry("cone", dims=(radius, height), **common)
    if tag == "ellipsoid":
        radii = v.child_text(shape, "radii", 3, example="<radii>0.1 0.2 0.3</radii>")
        if radii is None:
            raise v.error(shape, "missing <radii> (metres)")
        return Geometry("ellipsoid", dims=tuple(v.positive(shape, "radii", float(r))
                                                for r in radii), **common)
    if tag == "mesh":
        uri_el = shape.find("uri")
        uri = "" if uri_el is None else uri_el.text.strip()
        if not uri:
            raise v.error(shape, "a <mesh> needs a <uri>")
        scale = v.child_text(shape, "scale", 3, [1, 1, 1], "<scale>0.001 0.001 0.001</scale>")
        origin = shape.file or path   # a mesh of an included model: relative to its file
        resolved, problem = resolve_uri(uri, origin.parent, origin, package_paths)
        if shape.find("submesh") is not None:
            problem = (f"<submesh> (line {cast(Node, shape.find('submesh')).line}) is not "
                       "supported; export the submesh to its own file")
        return Geometry("mesh", path=resolved, uri=uri, scale=scale, problem=problem, **common)
    if tag in ("plane", "heightmap", "empty"):
        warnings.append(f"<{tag}> (line {shape.line}) has no finite volume; ignored")
        return None
    return Geometry(tag, problem=f"<{tag}> geometry (line {shape.line}) is not supported; use "
                                 "box, cylinder, sphere, capsule, ellipsoid, cone or mesh",
                    **common)

