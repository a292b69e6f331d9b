"""URDF: links, their ``<inertial>`` and their collision (or visual) geometry.

Conventions (ROS URDF specification, wiki.ros.org/urdf/XML/link): ``<origin xyz rpy>`` places a
child frame in the link frame, rpy fixed-axis (poses.rpy_matrix); the inertial frame's origin is
the centre of mass and ``<inertia ixx ixy ixz iyy iyz izz>`` is the tensor about it *in the
inertial frame's axes*, with the products as matrix entries (ixy = -∫xy dm: the same tensor as
massprops'). ``<box size>`` full edges, ``<cylinder radius length>`` along z, ``<sphere radius>``,
``<mesh filename scale>``; the ``<capsule radius length>`` extension (and Drake's
``drake:capsule``/``drake:ellipsoid``) are read too. Joints must form a tree.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any, cast

import numpy as np

from massprops.robot.formats.poses import rpy_matrix
from massprops.robot.formats.uris import resolve_uri
from massprops.robot.formats.values import Values
from massprops.robot.formats.xmltree import Node
from massprops.robot.model import Geometry, Link, RobotModel, StatedInertial, pick_source

__all__ = ["parse_urdf"]


def parse_urdf(root: Node, data: bytes, path: Path, *, source: str = "collision",
               package_paths: Sequence[Path] = ()) -> RobotModel:
    """The links of a URDF whose root element is ``root``; ``source`` "collision", "visual" or
    "auto" (collision, else visual: `model.pick_source`)."""
    v = Values(path)
    if root.tag != "robot":
        raise v.error(root, "expected a URDF whose root element is <robot>; is this an SDF "
                            "or MJCF file with a .urdf name?")
    _refuse_xacro(root, v)
    links = []
    names: set[str] = set()
    for node in root.findall("link"):
        name = node.attrs.get("name")
        if not name:
            raise v.error(node, 'a link needs a name="..."')
        if name in names:
            raise v.error(node, f"link name {name!r} is used twice; link names must be unique")
        names.add(name)
        inertial = node.find("inertial")
        used = pick_source(source, node.findall("collision"), node.findall("visual"))
        geoms = tuple(_geometry(el, v, path, package_paths)
                      for el in node.findall(used))
        links.append(Link(name, node, _stated(inertial, v) if inertial else None, geoms,
                          inertial, source=used))
    _check_tree(root, names, v)
    return RobotModel(path, "urdf", tuple(links), data)


def _origin(parent: Node, v: Values) -> tuple[np.ndarray, np.ndarray]:
    origin = parent.find("origin")
    if origin is None:
        return np.eye(3), np.zeros(3)
    xyz = v.attr(origin, "xyz", 3, [0, 0, 0])
    rpy = v.attr(origin, "rpy", 3, [0, 0, 0])
    return rpy_matrix(*rpy), xyz


def _stated(node: Node, v: Values) -> StatedInertial:
    rotation, xyz = _origin(node, v)
    mass_el, inertia_el = node.find("mass"), node.find("inertia")
    if mass_el is None or "value" not in mass_el.attrs:
        raise v.error(node, 'an <inertial> needs <mass value="..."/>; add it or remove the '
                            "<inertial> (massprops model --write fills it in)")
    if inertia_el is None:
        raise v.error(node, "an <inertial> needs <inertia ixx= ixy= ixz= iyy= iyz= izz=/>")
    mass = cast(float, v.number(mass_el, "value"))  # value= is there (checked above)
    k = {}
    for key in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"):
        if key not in inertia_el.attrs:
            raise v.error(inertia_el, f"missing {key}=; URDF needs all six of ixx ixy ixz iyy "
                                      "iyz izz")
        k[key] = v.number(inertia_el, key)
    j = np.array([[k["ixx"], k["ixy"], k["ixz"]], [k["ixy"], k["iyy"], k["iyz"]],
                  [k["ixz"], k["iyz"], k["izz"]]])
    return StatedInertial(mass, xyz, rotation @ j @ rotation.T, node)


def _geometry(element: Node, v: Values, path: Path, package_paths: Sequence[Path]) -> Geometry:
    rotation, xyz = _origin(element, v)
    geometry = element.find("geometry")
    shape = None if geometry is None else next(iter(geometry.children), None)
    if shape is None:
        raise v.error(element, "expected a <geometry> with one shape (box, cylinder, sphere, "
                               "mesh) inside")
    tag = shape.tag.removeprefix("drake:")
    common: dict[str, Any] = {"node": shape, "rotation": rotation, "translation": xyz}
    if tag == "box":
        return Geometry("box", dims=_dims(v, shape, ("size",), 3), **common)
    if tag == "sphere":
        return Geometry("sphere", dims=(_length(v, shape, "radius"),), **common)
    if tag in ("cylinder", "capsule"):
        return Geometry(tag, dims=(_length(v, shape, "radius"), _length(v, shape, "length")),
                        **common)
    if tag == "ellipsoid":
        return Geometry("ellipsoid", dims=tuple(_length(v, shape, k) for k in "abc"), **common)
    if tag == "mesh":
        uri = shape.attrs.get("filename")
        if not uri:
            raise v.error(shape, 'a <mesh> needs filename="..."')
        scale = v.attr(shape, "scale", (3, 1), [1, 1, 1], example='scale="0.001 0.001 0.001"')
        resolved, problem = resolve_uri(uri, path.parent, path, package_paths)
        return Geometry("mesh", path=resolved, uri=uri, scale=np.broadcast_to(scale, 3).copy(),
                        problem=problem, **common)
    return Geometry(tag, problem=f"<{shape.tag}> geometry is not supported (line "
                                 f"{shape.line}); use box, cylinder, sphere, capsule or mesh",
                    **common)


def _length(v: Values, node: Node, name: str) -> float:
    value = v.number(node, name)
    if value is None:
        raise v.error(node, f'missing {name}="..." (metres)')
    return v.positive(node, name, value)


def _dims(v: Values, node: Node, names: tuple[str, ...], count: int) -> tuple[float, ...]:
    size = v.attr(node, names[0], count)
    if size is None:
        raise v.error(node, f'missing {names[0]}="x y z" (metres)')
    for value in size:
        v.positive(node, names[0], float(value))
    return tuple(float(s) for s in size)


def _refuse_xacro(root: Node, v: Values) -> None:
    for node in root.iter():
        if node.tag.startswith("xacro:") or any("${" in a or "$(" in a
                                                  for a in node.attrs.values()):
            raise v.error(node, "unexpanded xacro; run `xacro robot.urdf.xacro > robot.urdf` "
                                "and give massprops the result")


def _check_tree(root: Node, links: set[str], v: Values) -> None:
    """Every joint names known links; no link has two parents; no loop."""
    parent_of: dict[str, tuple[str, Node]] = {}
    for joint in root.findall("joint"):
        ends = {}
        for end in ("parent", "child"):
            el = joint.find(end)
            name = None if el is None else el.attrs.get("link")
            if not name:
                raise v.error(joint, f'a joint needs <{end} link="..."/>')
            if name not in links:  # a name: el is there
                raise v.error(cast(Node, el), f"joint {joint.attrs.get('name', '?')!r}: no "
                                              f"link named {name!r}; check the spelling")
            ends[end] = name
        child = ends["child"]
        if child in parent_of:
            raise v.error(joint, f"joint loop: link {child!r} is the child of two joints "
                                 f"({parent_of[child][1].attrs.get('name', '?')!r} at line "
                                 f"{parent_of[child][1].line} and "
                                 f"{joint.attrs.get('name', '?')!r}); URDF needs a tree")
        parent_of[child] = (ends["parent"], joint)
    for start in parent_of:
        seen, link = {start}, start
        while link in parent_of:
            link, joint = parent_of[link]
            if link in seen:
                raise v.error(joint, f"joint loop through link {link!r}; URDF joints must form "
                                     "a tree (break the loop or model it in SDF/MJCF)")
            seen.add(link)
