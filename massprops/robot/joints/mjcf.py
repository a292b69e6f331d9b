"""MJCF joints and body poses (see `joints.frames` for the frames).

Rules (MuJoCo XML reference): a body's ``pos`` and orientation place it in its parent body
(through ``<frame>`` elements); ``<joint pos axis>`` are in the body's own frame (default pos 0,
axis 0 0 1), taking attributes from the body's ``childclass`` or the joint's ``class``
(`mjcf._Defaults`); ``type`` hinge (default), slide, ball, free (``<freejoint>``); ``range`` in
the compiler's angle unit for a hinge, limited when stated (``autolimits``, MuJoCo's default) or
``limited="true"``; ``damping``, ``stiffness`` about ``springref``. A body with no joint is welded
to its parent. Several joints in one body compose in order (each later one turns with the
earlier ones); two hinges through one point are a universal joint, a hinge and a slide along one
axis a cylindrical joint (named ``a+b``, when neither has damping or a spring); any other
set is a chain of massless stages, one joint each (`_Reader._stages`). ``<equality><connect
body1 body2 anchor>`` (anchor in body1's frame), or ``site1 site2`` (sites that coincide as
written), is a loop: a spherical joint between the two
bodies at the anchor. ``ref`` is the coordinate MuJoCo gives the pose as written; here that pose
is the zero, so coordinates, ``springref`` and ``range`` count from it (shifted by -ref), said
once in the mechanism's remarks.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from massprops.robot.formats.mjcf import _Compiler, _Defaults, _pose
from massprops.robot.formats.mjcf_tree import (
    expand_includes,
    replicate_frames,
    replicate_suffix,
)
from massprops.robot.formats.poses import euler_matrix
from massprops.robot.formats.values import Values
from massprops.robot.formats.xmltree import Node
from massprops.robot.joints.frames import (
    IDENTITY,
    WORLD_LINK,
    Mechanism,
    RobotJoint,
    compose,
    unit_axis,
)
from massprops.robot.joints.mjcf_loops import COUPLINGS, coupling, fixed_tendons, loop_joint

__all__ = ["mjcf_mechanism"]

_KINDS = {"hinge": "revolute", "slide": "prismatic", "ball": "spherical", "free": "free"}
_SAME_POINT = 1e-12  # m: two hinges "through one point" up to round-off of the written values
_PARALLEL = 1e-12    # |a × b| of unit axes taken as parallel (written values: exact or not)


class _Reader:
    def __init__(self, root: Node, path: Path) -> None:
        self.v = Values(path)
        expand_includes(root, path)  # idempotent: the parser spliced them already
        self.compiler = _Compiler(root, self.v, path)
        self.defaults = _Defaults(root, self.v)
        attrs: dict[str, str] = {}
        for node in root.findall("compiler"):
            attrs.update(node.attrs)
        self.autolimits = attrs.get("autolimits", "true") == "true"
        self.poses: dict = {}
        self.joints: list[RobotJoint | None] = []  # None: an inactive <equality> loop
        self.floating: set = set()
        self.notes: set = set()
        self.generated: list[str] = []  # <composite>/<flexcomp> met: their bodies not expanded
        self.refs: list[str] = []
        self.suffix = ""  # the name suffix inside <replicate> copies
        self.sites: dict = {}  # name -> (body, point in the model frame at the zero pose)
        self.next_id = 1

    def walk(self, node: Node, childclass: str, frame, body: str, world) -> None:
        for child in node.children:
            if child.tag == "body":
                self.body(child, child.attrs.get("childclass", childclass), frame, body, world)
            elif child.tag == "frame":
                attrs = (self.defaults.attrs(child, childclass) if "class" in child.attrs
                         else child.attrs)
                inner = compose(frame, _pose(attrs, child, self.compiler, self.v))
                self.walk(child, child.attrs.get("childclass", childclass), inner, body, world)
            elif child.tag == "replicate":
                self.replicate(child, childclass, frame, body, world)
            elif child.tag == "site" and child.attrs.get("name"):
                at = compose(world, compose(frame, _pose(self.defaults.attrs(child, childclass),
                                                         child, self.compiler, self.v)))
                self.sites[child.attrs["name"] + self.suffix] = (body, at[1])
            elif child.tag == "attach":
                raise self.v.error(child, "<attach> is not read as a mechanism yet; expand it "
                                          "(mujoco.MjSpec, mj_saveLastXML) first")
            elif child.tag in ("composite", "flexcomp"):  # bodies MuJoCo's compiler makes:
                self.notes.add(f"bodies made by <{child.tag}>, not expanded")  # said, not run
                self.generated.append(child.tag)

    def replicate(self, node: Node, childclass: str, frame, body: str, world) -> None:
        """``count`` copies, each placed by the previous one's pose and `offset`/`euler`, every
        name inside suffixed (the parser's rule, `mjcf_tree.replicate_frames`)."""
        v, compiler = self.v, self.compiler
        count = v.number(node, "count")
        if count is None or count != int(count) or count < 1:
            raise v.error(node, f"count={node.attrs.get('count')!r}: expected a whole number "
                                ">= 1")
        rotation = euler_matrix([compiler.radians(e) for e in v.attr(node, "euler", 3,
                                                                       [0, 0, 0])],
                                compiler.eulerseq)
        outer = self.suffix
        try:
            for i, pose in enumerate(replicate_frames(int(count), rotation,
                                                      v.attr(node, "offset", 3, [0, 0, 0]))):
                self.suffix = replicate_suffix(int(count), i, node.attrs.get("sep", "")) + outer
                self.walk(node, childclass, compose(frame, pose), body, world)
        finally:
            self.suffix = outer

    def body(self, node: Node, childclass: str, frame, parent: str, parent_world) -> None:
        body_id, self.next_id = self.next_id, self.next_id + 1
        name = node.attrs["name"] + self.suffix if node.attrs.get("name") else f"body#{body_id}"
        world = compose(parent_world, compose(frame, _pose(node.attrs, node, self.compiler,
                                                           self.v)))
        own = [c for c in node.children if c.tag in ("joint", "freejoint")]
        # the stages of a split body go before it: a parent's pose precedes its children's
        self.joints.extend(self.joint(own, name, parent, childclass, world) if own else [
            RobotJoint(f"{name}.weld", "fixed", parent, name, IDENTITY, np.zeros((0, 3)), node)])
        self.poses[name] = world
        self.walk(node, childclass, IDENTITY, name, world)

    def one(self, node: Node, childclass: str) -> tuple[str, dict]:
        a = self.defaults.attrs(node, childclass)
        kind = "free" if node.tag == "freejoint" else a.get("type", "hinge")
        if kind not in _KINDS:
            raise self.v.error(node, f"joint type {kind!r}: expected hinge, slide, ball or free")
        return kind, a

    def joint(self, nodes: list[Node], body: str, parent: str, childclass: str,
              world) -> list[RobotJoint]:
        """The joints of one body: one joint, a universal or cylindrical pair, else a chain of
        massless stages (see `_stages`)."""
        v = self.v
        read = [self.one(n, childclass) for n in nodes]
        names = [a["name"] + self.suffix if a.get("name") else f"{body}.joint{k}"
                 for k, (_, a) in enumerate(read)]
        pos = [v.numbers(n, a["pos"], "pos=", 3, 'pos="0 0 0"') if "pos" in a else np.zeros(3)
               for n, (_, a) in zip(nodes, read)]
        axes = [unit_axis(v, n, v.numbers(n, a["axis"], "axis=", 3, 'axis="0 0 1"'))
                if "axis" in a else np.array([0.0, 0.0, 1.0]) for n, (_, a) in zip(nodes, read)]
        kinds = [k for k, _ in read]
        for _, a in read:
            if float(a.get("armature", "0")):
                self.notes.add("joint armature")
            if float(a.get("frictionloss", "0")):
                self.notes.add("joint friction")
        limits = [self.limits(n, k, a) for n, (k, a) in zip(nodes, read)]
        damping = [float(a.get("damping", "0")) for _, a in read]
        stiff = [float(a.get("stiffness", "0")) for _, a in read]
        rest = [self.compiler.radians(float(a.get("springref", "0"))) if k == "hinge"
                else float(a.get("springref", "0")) for k, a in read]
        # ref: MuJoCo's coordinate of the pose as written; here that pose is 0, so the spring's
        # rest and the range move by -ref (the motion is the same, the numbers shift)
        for i, (n, (k, a)) in enumerate(zip(nodes, read)):
            if k not in ("hinge", "slide") or "ref" not in a:
                continue
            ref = float(v.numbers(n, a["ref"], "ref=", 1, 'ref="0"')[0])
            ref = self.compiler.radians(ref) if k == "hinge" else ref
            if ref != 0.0:
                rest[i] -= ref
                if limits[i] is not None:
                    limits[i] = (limits[i][0] - ref, limits[i][1] - ref)
                self.refs.append(names[i])
        if len(nodes) == 1:
            kind = _KINDS[kinds[0]]
            if kind == "free":
                self.floating.add(body)
            ax = axes[0][None, :] if kind in ("revolute", "prismatic") else np.zeros((0, 3))
            return [RobotJoint(names[0], kind, parent, body, (np.eye(3), pos[0]), ax, nodes[0],
                               (limits[0],) if limits[0] else None, damping[0], stiff[0],
                               rest[0])]
        joined = "+".join(names)
        sprung = any(damping) or any(stiff)  # a pair joint carries no damping or spring
        if not sprung and len(nodes) == 2 and kinds == ["hinge", "hinge"] and \
                np.linalg.norm(pos[0] - pos[1]) <= _SAME_POINT and \
                np.linalg.norm(np.cross(axes[0], axes[1])) > _PARALLEL:
            return [RobotJoint(joined, "universal", parent, body, (np.eye(3), pos[0]),
                               np.array(axes), nodes[0], tuple(limits) if any(limits) else None)]
        if not sprung and len(nodes) == 2 and sorted(kinds) == ["hinge", "slide"] and \
                np.linalg.norm(np.cross(axes[0], axes[1])) <= _PARALLEL and axes[0] @ axes[1] > 0:
            turn = kinds.index("hinge")
            order = [turn, 1 - turn]
            return [RobotJoint(joined, "cylindrical", parent, body, (np.eye(3), pos[turn]),
                               axes[turn][None, :], nodes[0],
                               tuple(limits[k] for k in order) if any(limits) else None)]
        if "free" in kinds:
            raise v.error(nodes[0], f"body {body!r} has joints {', '.join(names)} "
                                    f"({', '.join(kinds)}): a free joint must be a body's only "
                                    "joint (as MuJoCo requires); remove the others")
        return self._stages(nodes, body, parent, world, names, kinds, pos, axes, limits,
                            damping, stiff, rest)

    def _stages(self, nodes, body, parent, world, names, kinds, pos, axes, limits, damping,
                stiff, rest) -> list[RobotJoint]:
        """A body's several joints as a chain, as MuJoCo composes them (each later joint moves
        with the earlier ones): joint k carries a massless stage ``body.name_k`` that sits on the
        body's frame at the zero pose, the last joint carries the body; each joint keeps its own
        name, damping and spring (a planar root slide x, slide z, hinge y; three hinges)."""
        out, upper = [], parent
        for k, node in enumerate(nodes):
            child = body if k == len(nodes) - 1 else f"{body}.{names[k]}"
            if child != body:
                if child in self.poses:
                    raise self.v.error(node, f"a body is named {child!r}, the name massprops "
                                             "gives a stage of a body with several joints; "
                                             "rename it")
                self.poses[child] = world
            kind = _KINDS[kinds[k]]
            ax = axes[k][None, :] if kind in ("revolute", "prismatic") else np.zeros((0, 3))
            out.append(RobotJoint(names[k], kind, upper, child, (np.eye(3), pos[k]), ax, node,
                                  (limits[k],) if limits[k] else None, damping[k], stiff[k],
                                  rest[k]))
            upper = child
        return out

    def limits(self, node: Node, kind: str, a: dict):
        limited = a.get("limited", "auto")
        if "range" not in a or limited == "false" or (limited == "auto" and not self.autolimits):
            return None
        lo, hi = self.v.numbers(node, a["range"], "range=", 2, 'range="-90 90"')
        if kind == "hinge":
            lo, hi = self.compiler.radians(lo), self.compiler.radians(hi)
        return (float(lo), float(hi))


def mjcf_mechanism(root: Node, path: Path, links: list[str]) -> Mechanism:
    """Joints (with the ``connect`` loops) and body poses of the MJCF model ``root``."""
    r = _Reader(root, path)
    for top in root.findall("worldbody"):
        r.walk(top, "main", IDENTITY, WORLD_LINK, IDENTITY)
    couplings, tendons = [], fixed_tendons(r, root)
    for eq in root.findall("equality"):
        for k, node in enumerate(eq.children):
            if node.tag in COUPLINGS:
                couplings.append(coupling(r, node, k, tendons))
            else:
                r.joints.append(loop_joint(r, node, k))
    joints = [j for j in r.joints if j is not None]
    gravity = None
    for option in root.findall("option"):
        if "gravity" in option.attrs:
            gravity = r.v.numbers(option, option.attrs["gravity"], "gravity=", 3,
                                  'gravity="0 0 -9.81"')
    if root.find("actuator") is not None:
        r.notes.add("actuators")
    remarks = () if not r.refs else (
        f"joint(s) {', '.join(r.refs[:4])}{' ...' if len(r.refs) > 4 else ''} have a ref: "
        "their coordinates here count from the pose as written (MuJoCo's qpos minus ref); "
        "springref and range are shifted alike, the motion is MuJoCo's",)
    return Mechanism(path, "mjcf", tuple(joints), r.poses, frozenset(r.floating), gravity,
                     tuple(sorted(r.notes)), remarks,
                     tuple(c for c in couplings if c is not None))
