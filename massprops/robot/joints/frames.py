"""The robot as a mechanism: joints and link poses of a description, format-neutral.

Frames. Every link frame's pose is given in the *model frame* at the zero pose (all joint
coordinates 0): ``poses[name] = (A, t)`` with v_model = A v_link + t (m). Each joint's frame is
fixed to its child link: ``frame = (A, t)`` places the joint frame in the child link frame (URDF:
the identity, the child link frame *is* the joint frame); its ``axes`` are unit vectors in the
joint frame. At the zero pose the joint frame is also where the parent carries it, so the joint's
point and axes in the model frame are ``poses[child] ∘ frame``. Coordinates follow the formats
(and the systems engine): a one-axis joint's coordinate is the turn (rad, right hand) or the
shift (m) of the child relative to the parent about or along the axis.

Readers: `joints.urdf`, `joints.sdf`, `joints.mjcf`; `mechanism.read_mechanism`
dispatches on the parsed `RobotModel`. Each refusal is one line naming the file, the line and
the element.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from massprops.robot.formats.values import Values
from massprops.robot.formats.xmltree import Node

__all__ = ["KINDS", "WORLD_LINK", "Mechanism", "RobotCoupling", "RobotJoint", "compose",
           "mark_loops", "mimic", "poses_from_tree"]

Pose = tuple[np.ndarray, np.ndarray]
WORLD_LINK = "world"
"""The parent name of a joint to the ground (URDF: a link called ``world``; SDF: ``world``;
MJCF: ``<worldbody>``)."""

KINDS = ("revolute", "prismatic", "fixed", "free", "spherical", "universal", "cylindrical")
"""Joint kinds of the neutral model (the systems engine's, plus "free": no constraint)."""

IDENTITY: Pose = (np.eye(3), np.zeros(3))


@dataclass(frozen=True, eq=False)
class RobotJoint:
    """One joint of a description.

    name : as written (MJCF: a body's several joints joined by "+"). kind : one of KINDS
    ("continuous" is revolute without limits). parent, child : link names (parent may be
    WORLD_LINK). frame : (A (3, 3), t (3,) m) the joint frame in the child link frame.
    axes : (k, 3) unit, joint frame (revolute, prismatic, cylindrical: 1; universal: 2; else 0).
    limits : ((lower, upper), ...) per coordinate, rad or m, or None (none stated).
    damping : N·m·s/rad or N·s/m. stiffness : N·m/rad or N/m about ``rest`` (MJCF springs).
    loop : a closing joint (MJCF ``<equality><connect>``), not part of the description's tree.
    node : the element it came from (line numbers).
    """

    name: str
    kind: str
    parent: str
    child: str
    frame: Pose
    axes: np.ndarray
    node: Node | None  # None for a joint massprops adds (a description's base)
    limits: tuple | None = None
    damping: float = 0.0
    stiffness: float = 0.0
    rest: float = 0.0
    loop: bool = False


@dataclass(frozen=True, eq=False)
class RobotCoupling:
    """A linear relation Σ c_i q_i = constant between one-axis joints' coordinates (a URDF
    ``<mimic>``, an MJCF joint or fixed-tendon ``<equality>``): ``terms`` ((joint name, c_i),
    ...), the follower first (the relation is in its unit); ``node`` the element it came from."""

    name: str
    terms: tuple
    constant: float
    node: Node


def mimic(v: Values, node: Node, follower: str, leader: str | None, gain: float,
          constant: float) -> RobotCoupling:
    """A ``<mimic>`` (URDF, SDF 1.11): follower = gain × leader + constant; refuses one
    without the joint it follows, at ``node``."""
    if not leader:
        raise v.error(node, f'joint {follower!r}: <mimic> needs joint="..." (the joint it '
                            "follows)")
    return RobotCoupling(f"{follower} mimics {leader}", ((follower, 1.0), (leader, -gain)),
                         constant, node)


@dataclass(frozen=True, eq=False)
class Mechanism:
    """The joints of a description and every link's pose in the model frame at the zero pose.

    floating : links that the description itself sets free (an MJCF ``<freejoint>``, a URDF
    ``floating`` joint). gravity : (3,) m/s² the description states (MJCF ``<option
    gravity>``), else None. notes : what the description holds that a simulation ignores
    (friction, armature, actuators), one phrase each. couplings : the joint relations the
    engine enforces (`RobotCoupling`). remarks : how a number here differs from
    the format's own (MJCF ``ref``), one warning line each.
    """

    path: Path
    format: str
    joints: tuple[RobotJoint, ...]
    poses: dict
    floating: frozenset = frozenset()
    gravity: np.ndarray | None = None
    notes: tuple[str, ...] = field(default=())
    remarks: tuple[str, ...] = field(default=())
    couplings: tuple[RobotCoupling, ...] = field(default=())


def compose(a: Pose, b: Pose) -> Pose:
    """The pose b (in frame a) in a's parent frame."""
    return a[0] @ b[0], a[0] @ b[1] + a[1]


def inverse(a: Pose) -> Pose:
    return a[0].T, -(a[0].T @ a[1])


def unit_axis(v: Values, node: Node, xyz: np.ndarray) -> np.ndarray:
    """``xyz`` normalised; refuses a zero axis at ``node``."""
    norm = float(np.linalg.norm(xyz))
    if norm == 0.0:
        raise v.error(node, "the joint axis is zero; give a direction, e.g. 0 0 1")
    return np.asarray(xyz, float) / norm


def poses_from_tree(joints, roots: list[str]) -> dict:
    """Link poses in the model frame: each root at the identity, each child at its parent's pose
    composed with the joint origin (``joints``: (parent, child, origin in parent frame))."""
    children: dict[str, list] = {}
    for parent, child, origin in joints:
        children.setdefault(parent, []).append((child, origin))
    poses = {r: IDENTITY for r in roots}
    todo = deque(roots)
    while todo:
        link = todo.popleft()
        for child, origin in children.get(link, ()):
            poses[child] = compose(poses[link], origin)
            todo.append(child)
    return poses


def mark_loops(joints: list[RobotJoint], links: list[str]) -> list[RobotJoint]:
    """The joints with every joint that closes a kinematic loop marked ``loop`` (a format that
    allows a link to be the child of several joints: SDF's closed chains, e.g. a leg's push rods).

    A spanning tree grows breadth-first from the roots (the world and every link no joint
    carries), over the joints in file order, parent to child; a joint whose child the tree has
    reached already closes a loop. A ring of links that no root reaches is entered at its first
    link in file order, which then counts as a root (its carrier closes the ring).
    """
    out = list(joints)
    children: dict[str, list[int]] = {}
    for k, j in enumerate(out):
        if not j.loop:
            children.setdefault(j.parent, []).append(k)
    carried = {j.child for j in out if not j.loop}
    reached = set()
    for start in [WORLD_LINK, *[n for n in links if n not in carried], *links]:
        if start in reached:
            continue
        reached.add(start)
        todo = deque([start])
        while todo:
            for k in children.get(todo.popleft(), ()):
                if out[k].child in reached:
                    out[k] = replace(out[k], loop=True)
                else:
                    reached.add(out[k].child)
                    todo.append(out[k].child)
    return out
