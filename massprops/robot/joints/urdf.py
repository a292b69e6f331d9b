"""URDF joints and link poses (see `joints.frames` for the frames)."""

from __future__ import annotations

from pathlib import Path
from typing import cast

import numpy as np

from massprops.robot.formats.poses import rpy_matrix
from massprops.robot.formats.values import Values
from massprops.robot.formats.xmltree import Node
from massprops.robot.joints.frames import (
    IDENTITY,
    Mechanism,
    Pose,
    RobotCoupling,
    RobotJoint,
    mimic,
    poses_from_tree,
    unit_axis,
)

__all__ = ["urdf_mechanism"]

_URDF_KINDS = {"revolute": "revolute", "continuous": "revolute", "prismatic": "prismatic",
               "fixed": "fixed", "floating": "free"}


def urdf_mechanism(root: Node, path: Path, links: list[str]) -> Mechanism:
    """URDF ``<joint name type>`` with ``<parent link>``, ``<child link>``, ``<origin xyz rpy>``
    (the child link frame in the parent link frame), ``<axis xyz>`` (joint frame; default
    1 0 0, the specification's), ``<limit lower upper>`` and ``<dynamics damping friction>``;
    ``planar`` is two shifts and a turn through massless stages (`_planar`).
    ``<mimic joint multiplier offset>`` is the coupling q = multiplier q_joint + offset
    (defaults 1 and 0), enforced as a constraint (`frames.RobotCoupling`)."""
    v = Values(path)
    joints: list[RobotJoint] = []
    tree: list[tuple[str, str, Pose]] = []
    notes: set[str] = set()
    couplings: list[RobotCoupling] = []
    for node in root.findall("joint"):
        name = node.attrs.get("name")
        if not name:
            raise v.error(node, 'a joint needs a name="..."')
        written = node.attrs.get("type", "")
        if written not in (*_URDF_KINDS, "planar"):
            raise v.error(node, f"joint {name!r}: type {written!r} is not a URDF joint type; "
                                f"use one of {', '.join(_URDF_KINDS)}, planar")
        kind = _URDF_KINDS.get(written, "planar")
        parent = cast(Node, node.find("parent")).attrs["link"]  # parse_urdf checked both ends
        child = cast(Node, node.find("child")).attrs["link"]
        origin = node.find("origin")
        pose = IDENTITY if origin is None else (
            rpy_matrix(*v.attr(origin, "rpy", 3, [0, 0, 0])), v.attr(origin, "xyz", 3, [0, 0, 0]))
        axes = np.zeros((0, 3))
        if kind in ("revolute", "prismatic", "planar"):
            axis = node.find("axis")
            xyz = np.array([1.0, 0.0, 0.0]) if axis is None else v.attr(
                axis, "xyz", 3, [1, 0, 0])
            axes = unit_axis(v, axis if axis is not None else node, xyz)[None, :]
        limits = None
        limit = node.find("limit")
        if written in ("revolute", "prismatic") and limit is not None:
            limits = ((v.number(limit, "lower", 0.0), v.number(limit, "upper", 0.0)),)
        damping = 0.0
        dyn = node.find("dynamics")
        if dyn is not None:
            damping = v.positive(dyn, "damping", v.number(dyn, "damping", 0.0), allow_zero=True)
            if v.number(dyn, "friction", 0.0):
                notes.add("joint friction")
        tag = node.find("mimic")
        if tag is not None:
            couplings.append(mimic(v, tag, name, tag.attrs.get("joint"),
                                   v.number(tag, "multiplier", 1.0), v.number(tag, "offset", 0.0)))
        if kind == "planar":
            _planar(name, parent, child, pose, axes[0], node, joints, tree)
            continue
        joints.append(RobotJoint(name, kind, parent, child, IDENTITY, axes, node, limits,
                                 damping))
        tree.append((parent, child, pose))
    children = {j.child for j in joints}
    roots = [name for name in links if name not in children]
    poses = poses_from_tree(tree, roots)
    floating = frozenset(j.child for j in joints if j.kind == "free")
    if root.find("transmission") is not None:
        notes.add("transmissions (actuators)")
    return Mechanism(path, "urdf", tuple(joints), poses, floating, None, tuple(sorted(notes)),
                     couplings=tuple(couplings))


def _planar(name: str, parent: str, child: str, pose, normal: np.ndarray, node: Node,
            joints: list, tree: list) -> None:
    """A planar joint (URDF: the child moves in the plane normal to ``axis``) as three joints
    through two massless stages on the child's frame: ``name.x`` and ``name.y`` shift along
    e1, e2 (in the plane: e1 = the unit axis × z, or × x when the axis is along z, turned to
    a right-handed e1, e2, axis), then ``name`` turns about the axis. A stage's pose is the
    child's at the zero pose."""
    helper = np.array([0.0, 0.0, 1.0]) if abs(normal[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    e2 = np.cross(normal, helper)
    e2 /= np.linalg.norm(e2)
    e1 = np.cross(e2, normal)
    stages = [f"{child}.{name}.x", f"{child}.{name}.y", child]
    names = [f"{name}.x", f"{name}.y", name]
    kinds = ["prismatic", "prismatic", "revolute"]
    upper = parent
    for k, (stage, axis) in enumerate(zip(stages, (e1, e2, normal))):
        joints.append(RobotJoint(names[k], kinds[k], upper, stage, IDENTITY, axis[None, :],
                                 node))
        tree.append((upper, stage, pose if k == 0 else IDENTITY))
        upper = stage
