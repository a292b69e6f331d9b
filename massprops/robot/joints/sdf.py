"""SDFormat joints and link poses (see `joints.frames` for the frames).

Rules (sdformat.org, joint and pose semantics): a link's ``<pose>`` is in the model frame (1.7+:
``relative_to`` another frame); a joint's ``<pose>`` is in its *child link* frame (1.4-1.6: always;
1.7+: unless ``relative_to`` names another frame; both resolved by `sdf._FrameGraph`).
``<axis><xyz>`` is in the joint frame, except with ``<use_parent_model_frame>true`` (1.5-1.6:
the model frame) or ``<xyz expressed_in="F">`` (1.7+: frame F). A nested model's links are
``outer::inner::link``; the model's own ``<pose>`` places it in its parent model (the
top-level one in the world). Kinds: revolute, continuous (no limits), prismatic, fixed, ball,
universal (``axis`` fixed in the parent, ``axis2`` in the child); revolute2, screw and gearbox
are refused. Limits of ±1e16 (SDF's "none") are no limits. A ``<static>true`` model's joints
(its nested models' too) are all welds. A joint's <parent>/<child> may name a nested model's link
as ``inner::link``; its child must be in the joint's own model. A link may be the child of
several joints (a closed chain): the joints that close loops are marked (`frames.mark_loops`).
"""

from __future__ import annotations

from pathlib import Path
from typing import cast

import numpy as np

from massprops.robot.formats.sdf import _FrameGraph, _scope, pose_of
from massprops.robot.formats.values import Values
from massprops.robot.formats.xmltree import Node
from massprops.robot.joints.frames import (
    IDENTITY,
    WORLD_LINK,
    Mechanism,
    Pose,
    RobotCoupling,
    RobotJoint,
    compose,
    inverse,
    mark_loops,
    mimic,
    unit_axis,
)

__all__ = ["sdf_mechanism"]

_KINDS = {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic",
          "fixed": "fixed", "ball": "spherical", "universal": "universal"}
_NO_LIMIT = 1e15  # SDF writes "no limit" as ±1e16


def _version(root: Node) -> tuple[int, int]:
    try:
        major, minor = root.attrs.get("version", "1.7").split(".")[:2]
        return int(major), int(minor)
    except ValueError:
        return 1, 7


def sdf_mechanism(root: Node, path: Path, links: list[str]) -> Mechanism:
    """Joints and link poses of every ``<model>`` under the SDF root ``root``."""
    v = Values(path)
    version = _version(root)
    joints: list[RobotJoint] = []
    poses: dict[str, Pose] = {}
    notes: set[str] = set()
    couplings: list[RobotCoupling] = []
    for model in root.iter("model"):
        prefix = _scope(model)
        placed = IDENTITY
        node = model
        while node is not None and node.tag == "model":
            placed = compose(pose_of(node, v)[0], placed)
            node = node.parent
        graph = _FrameGraph(model, v)
        for link in model.findall("link"):
            poses[prefix + link.attrs.get("name", "")] = compose(
                placed, graph.in_model(link.attrs.get("name", "")))
        static = _static(model)
        full = "".join(n + "::" for n in _names(model))
        for node in model.findall("joint"):
            joint = _joint(node, (prefix, full), graph, v, version, set(links), notes,
                           couplings)
            if static:  # a static model does not move: every joint is a weld
                joint = RobotJoint(joint.name, "fixed", joint.parent, joint.child, joint.frame,
                                   np.zeros((0, 3)), joint.node)
            joints.append(joint)
    return Mechanism(path, "sdf", tuple(mark_loops(joints, list(poses))), poses, frozenset(),
                     None, tuple(sorted(notes)), couplings=tuple(couplings))


def _static(model: Node) -> bool:
    """``<static>true`` on the model or any model enclosing it."""
    node: Node | None = model
    while node is not None and node.tag == "model":
        flag = node.find("static")
        if flag is not None and flag.text.strip().lower() in ("true", "1"):
            return True
        node = node.parent
    return False


def _names(model: Node) -> list[str]:
    """The names of ``model`` and its enclosing models, outermost first."""
    out = []
    node: Node | None = model
    while node is not None and node.tag == "model":
        out.append(node.attrs.get("name", "?"))
        node = node.parent
    return out[::-1]


def _end(node: Node, tag: str, scopes: tuple[str, str], links: set, v: Values,
         name: str, graph: _FrameGraph) -> str:
    """The link a joint's <parent>/<child> names: in the joint's model (its links' prefix), a
    nested model's link written ``inner::link`` (scoped by every enclosing model's name), or
    (1.7+) a frame of the model, standing for the link it is attached to."""
    el = node.find(tag)
    text = "" if el is None else el.text.strip()
    if not text:
        raise v.error(node, f"joint {name!r} needs <{tag}>link name</{tag}>")
    if text == WORLD_LINK and tag == "parent":
        return WORLD_LINK
    for scope in scopes:
        if scope + text in links:
            return scope + text
    attached = _attached_link(text, graph)
    for scope in scopes if attached is not None else ():
        if scope + cast(str, attached) in links:
            return scope + cast(str, attached)
    # a text, so el is there
    raise v.error(cast(Node, el), f"joint {name!r}: no link named {text!r} in this model; "
                                  "check the spelling")


def _attached_link(frame: str, graph: _FrameGraph) -> str | None:
    """The link an SDF 1.7+ ``<frame>`` (or a joint) is attached to, following ``attached_to``
    through other frames and joints (a joint: its child); a name outside this model's own
    (``inner::link``) is returned for the caller to look up; None for a frame attached to the
    model frame, or a loop."""
    seen = set()
    while frame in graph.nodes and frame not in seen:
        seen.add(frame)
        node, default = graph.nodes[frame]
        if node.tag == "link":
            return frame
        frame = default
    return None if frame in seen or frame == "__model__" else frame


def _joint(node: Node, scopes: tuple[str, str], graph: _FrameGraph, v: Values, version,
           links: set, notes: set, couplings: list) -> RobotJoint:
    """One ``<joint>``; an ``<axis><mimic>`` (SDFormat 1.11) adds its coupling to
    ``couplings``: follower = multiplier (leader − reference) + offset (defaults 1, 0, 0)."""
    name = node.attrs.get("name", "")
    if not name:
        raise v.error(node, 'a joint needs a name="..."')
    written = node.attrs.get("type", "")
    if written not in _KINDS:
        raise v.error(node, f"joint {name!r}: type {written!r} is not supported by the systems "
                            f"engine; use one of {', '.join(_KINDS)}")
    kind = _KINDS[written]
    prefix = scopes[0]
    parent = _end(node, "parent", scopes, links, v, name, graph)
    child = _end(node, "child", scopes, links, v, name, graph)
    local_child = child[len(prefix):] if child.startswith(prefix) else child
    if "::" in local_child or not child.startswith(prefix):
        raise v.error(node, f"joint {name!r}: a child link inside a nested model "
                            f"({local_child!r}) is not supported; put the joint in that model")
    in_model = graph.in_model(name)
    frame = compose(inverse(graph.in_model(local_child)), in_model)
    count = {"revolute": 1, "prismatic": 1, "universal": 2}.get(kind, 0)
    axes, limits, damping = [], [], 0.0
    for k, tag in enumerate(("axis", "axis2")[:count]):
        axis = node.find(tag)
        xyz_el = None if axis is None else axis.find("xyz")
        if xyz_el is None:
            raise v.error(axis or node, f"joint {name!r} ({written}) needs <{tag}><xyz>"
                                        "0 0 1</xyz></{tag}>: the direction it turns or slides "
                                        "along")
        axis = cast(Node, axis)  # xyz_el came from it
        xyz = v.text(xyz_el, 3, "<xyz>0 0 1</xyz>")
        axes.append(in_model[0].T @ _axis_in_model(axis, xyz_el, xyz, graph, in_model, v,
                                                    version))
        axes[-1] = unit_axis(v, xyz_el, axes[-1])
        mimic_el = axis.find("mimic")
        if mimic_el is not None:
            couplings.append(_mimic(mimic_el, prefix + name, prefix, v))
        limit = axis.find("limit")
        lo = _number(limit, "lower", v)
        hi = _number(limit, "upper", v)
        if written != "continuous" and lo is not None and hi is not None and \
                max(abs(lo), abs(hi)) < _NO_LIMIT:
            limits.append((lo, hi))
        dyn = axis.find("dynamics")
        if k == 0 and dyn is not None:
            d = _number(dyn, "damping", v)
            damping = v.positive(dyn, "damping", d, allow_zero=True) if d is not None else 0.0
            if _number(dyn, "friction", v):
                notes.add("joint friction")
    return RobotJoint(prefix + name, kind, parent, child, frame,
                      np.array(axes).reshape(-1, 3), node,
                      tuple(limits) if limits else None, damping)


def _mimic(tag: Node, follower: str, prefix: str, v: Values) -> RobotCoupling:
    """SDF's follower = multiplier (leader − reference) + offset, as `frames.mimic`."""
    values = {name: _number(tag, name, v) for name in ("multiplier", "offset", "reference")}
    gain = 1.0 if values["multiplier"] is None else values["multiplier"]
    leader = tag.attrs.get("joint")
    return mimic(v, tag, follower, leader and prefix + leader, gain,
                 (values["offset"] or 0.0) - gain * (values["reference"] or 0.0))


def _axis_in_model(axis: Node, xyz_el: Node, xyz: np.ndarray, graph: _FrameGraph, in_model,
                   v: Values, version) -> np.ndarray:
    """The axis direction in the model frame, by the version's rule."""
    if version < (1, 7):
        flag = axis.find("use_parent_model_frame")
        if flag is not None and flag.text.strip().lower() in ("true", "1"):
            return xyz
        return in_model[0] @ xyz
    frame = xyz_el.attrs.get("expressed_in", "")
    if not frame:
        return in_model[0] @ xyz
    try:
        return graph.in_model(frame)[0] @ xyz
    except KeyError:
        raise v.error(xyz_el, f"expressed_in={frame!r}: no such frame in this model") from None


def _number(node: Node | None, tag: str, v: Values) -> float | None:
    value = None if node is None else v.child_text(node, tag, 1, example=f"<{tag}>0</{tag}>")
    return None if value is None else float(value[0])
