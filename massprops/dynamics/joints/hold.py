"""What the joints together leave free, and an initial state that respects it.

One joint or a supported pair reduces to a `Hold`: rotation about a fixed point (``spherical``)
or about a fixed axis through a point (``revolute``). Supported: one spherical joint, one
revolute joint, or two spherical joints at distinct body points (a hinge about the line through
them, e.g. a rotor in two self-aligning bearings; the first takes the axial load, the second
floats axially, as a locating and a floating bearing do). Everything else over-constrains the
body: a joint that adds nothing (a second one at the same point or on the same axis) is refused
as redundant, one that leaves no motion (a hinge plus a point off its axis, two distinct hinges,
three points not on a line) as locking the body. Messages name the joint (``joints[i]``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import cast

import numpy as np

from massprops.dynamics.joints.model import Joint, RevoluteJoint, SphericalJoint
from massprops.dynamics.model import InitialState, RigidBody
from massprops.rotation import quat_multiply, quat_normalize, quat_to_matrix
from massprops.tolerances import JOINT_RTOL

__all__ = ["Deviation", "Hold", "JointRefusal", "consistent_initial", "hold_of"]


class JointRefusal(ValueError):
    """Joints that cannot hold a body together; ``key`` is the key path in the scene
    (``joints[1].anchor``), the message says why and how to fix it."""

    def __init__(self, key: str, message: str) -> None:
        super().__init__(message)
        self.key = key


@dataclass(frozen=True, eq=False)
class Hold:
    """The motion the joints leave: ``kind`` "spherical" (turning about ``point``, held at
    ``anchor``) or "revolute" (turning about the body axis ``axis`` through ``point``, held on
    the world axis ``world_axis`` through ``anchor``). point, axis: (3,) body coordinates (m,
    unit); anchor, world_axis: (3,) world (m, unit; world_axis None until an initial orientation
    fixes it). damping N·m·s/rad and torque N·m (window [start, end) s) act about the axis.
    ``second_point``: the floating joint's body point when two spherical joints make the hinge."""

    kind: str
    point: np.ndarray
    anchor: np.ndarray
    axis: np.ndarray | None = None
    world_axis: np.ndarray | None = None
    damping: float = 0.0
    torque: float = 0.0
    start: float = -math.inf
    end: float = math.inf
    second_point: np.ndarray | None = None


def _unit(v) -> np.ndarray:
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v)


def _point(joint: Joint, body: RigidBody) -> np.ndarray:
    return np.asarray(body.center_of_mass if joint.point is None else joint.point, np.float64)


def _fmt(v) -> str:
    return "[" + ", ".join(f"{float(x) + 0.0:.10g}" for x in np.atleast_1d(v)) + "]"


def hold_of(joints: tuple[Joint, ...], body: RigidBody) -> Hold:
    """The `Hold` of a supported set of joints; raises JointRefusal otherwise."""
    if len(joints) == 1:
        j = joints[0]
        if isinstance(j, SphericalJoint):
            return Hold("spherical", _point(j, body), np.asarray(j.anchor, np.float64))
        return Hold("revolute", _point(j, body), np.asarray(j.anchor, np.float64),
                    _unit(j.axis), None if j.world_axis is None else _unit(j.world_axis),
                    j.damping, j.torque, j.start, j.end)
    size = body.size
    hinge = [i for i, j in enumerate(joints) if isinstance(j, RevoluteJoint)]
    if hinge:
        i = hinge[0]
        k = next(k for k in range(len(joints)) if k != i)
        raise JointRefusal(f"joints[{max(i, k)}]", _with_hinge(joints, i, k, body))
    p1, p2 = _point(joints[0], body), _point(joints[1], body)
    gap = float(np.linalg.norm(p2 - p1))
    if gap <= JOINT_RTOL * size:
        raise JointRefusal("joints[1]", "a second spherical joint at the same body point as "
                           "joints[0] adds no constraint; remove it")
    for k in range(2, len(joints)):
        pk = _point(joints[k], body)
        off = float(np.linalg.norm(np.cross(pk - p1, (p2 - p1) / gap)))
        what = ("lies on the line through joints[0] and joints[1], which already hold it: it "
                "adds no constraint; remove it") if off <= JOINT_RTOL * size else (
                "with joints[0] and joints[1] holds three points not on a line: that locks "
                "the body (no motion is left); remove one")
        raise JointRefusal(f"joints[{k}]", what)
    a1, a2 = (np.asarray(j.anchor, np.float64) for j in joints[:2])
    reach = float(np.linalg.norm(a2 - a1))
    if abs(reach - gap) > JOINT_RTOL * max(gap, size):
        raise JointRefusal("joints[1].anchor", (
            f"is {reach:.10g} m from joints[0]'s anchor, but the two body points are "
            f"{gap:.10g} m apart: the body cannot reach both anchors; place them {gap:.10g} m "
            "apart"))
    return Hold("revolute", p1, a1, (p2 - p1) / gap, (a2 - a1) / reach, second_point=p2)


def _with_hinge(joints, i: int, k: int, body: RigidBody) -> str:
    """Why a revolute joint joints[i] cannot be combined with joints[k]."""
    hinge, other = joints[i], joints[k]
    p, e = _point(hinge, body), _unit(hinge.axis)
    q = _point(other, body)
    on_axis = float(np.linalg.norm(np.cross(q - p, e))) <= JOINT_RTOL * body.size
    if isinstance(other, SphericalJoint):
        if on_axis:
            return (f"a spherical joint on the axis of the revolute joint joints[{i}] adds no "
                    "constraint (the hinge already holds that point); remove it")
        return (f"a spherical joint off the axis of the revolute joint joints[{i}] locks the "
                "body (no motion is left); remove one (two spherical joints on a line make a "
                "hinge)")
    if on_axis and abs(abs(float(e @ _unit(other.axis))) - 1.0) <= JOINT_RTOL:
        return (f"a second revolute joint on the axis of joints[{i}] adds no constraint; "
                "remove it")
    return (f"two revolute joints on different axes (joints[{i}] and joints[{k}]) lock the "
            "body (no motion is left); keep one")


@dataclass(frozen=True)
class Deviation:
    """How far a given initial value misses the hold: ``key`` (initial.<key>), ``amount`` (m,
    rad, m/s or rad/s: ``unit``), the consistent value (in the scene's own form, to copy), and
    what the joint requires, in words."""

    key: str
    amount: float
    unit: str
    consistent: list[float]
    requirement: str

    def message(self) -> str:
        return (f"{self.requirement}; got one {self.amount:.3g} {self.unit} off: "
                f"{_fmt(self.consistent)} would be consistent (or set "
                "initial.project_initial: true to project it)")


def _turn(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """The smallest rotation (quaternion) taking the unit vector u to the unit vector v."""
    w = 1.0 + float(u @ v)
    axis = np.cross(u, v)
    if w < 1e-8:  # antiparallel: half a turn about any axis across u
        helper = np.eye(3)[int(np.argmin(np.abs(u)))]
        axis = np.cross(u, helper)
        return np.concatenate([[0.0], axis / np.linalg.norm(axis)])
    return quat_normalize(np.concatenate([[w], axis]))


def consistent_initial(hold: Hold, body: RigidBody, initial: InitialState,
                       given: frozenset[str], duration: float
                       ) -> tuple[Hold, InitialState, list[Deviation]]:
    """The hold with its world axis fixed, the initial state moved onto it, and how far the
    ``given`` initial values (names of InitialState fields the scene set) were from it, in the
    order orientation, angular_velocity, position, velocity (only those beyond JOINT_RTOL).

    A value not given is derived: the centre of mass where the joints put it, its velocity from
    the angular velocity; a revolute joint's world axis, if not given, is where the initial
    orientation turns the body axis.
    """
    deviations: list[Deviation] = []
    q = np.asarray(initial.orientation, np.float64)
    omega = np.asarray(initial.angular_velocity, np.float64)
    to_world = quat_to_matrix(q)
    w_world = to_world @ omega if initial.angular_velocity_frame == "body" else omega
    if hold.kind == "revolute":
        turned = to_world @ cast(np.ndarray, hold.axis)  # a hinge always has its axis
        world_axis = hold.world_axis
        if world_axis is None:
            world_axis = turned / np.linalg.norm(turned)
            hold = replace(hold, world_axis=world_axis)
        angle = math.atan2(float(np.linalg.norm(np.cross(turned, world_axis))),
                           float(turned @ world_axis))
        q_new = quat_normalize(quat_multiply(_turn(turned, world_axis), q))
        if angle > JOINT_RTOL:
            deviations.append(Deviation(
                "orientation", angle, "rad", q_new.tolist(),
                f"the orientation must turn the hinge axis {_fmt(hold.axis)} (body) onto the "
                f"world axis {_fmt(world_axis)}"))
        q = q_new
        to_world = quat_to_matrix(q)
        if initial.angular_velocity_frame == "body":
            w_world = to_world @ omega
        along = float(w_world @ world_axis) * world_axis
        across = float(np.linalg.norm(w_world - along))
        scale = max(float(np.linalg.norm(w_world)), 1.0 / duration)
        new = along if initial.angular_velocity_frame == "world" else to_world.T @ along
        if across > JOINT_RTOL * scale:
            deviations.append(Deviation(
                "angular_velocity", across, "rad/s", new.tolist(),
                f"a hinge turns the body only about {_fmt(world_axis)} (world), so the "
                "angular velocity must lie along it"))
        omega, w_world = new, along
    com = np.asarray(body.center_of_mass, np.float64)
    r_new = hold.anchor + to_world @ (com - hold.point)
    v_new = np.cross(w_world, r_new - hold.anchor)
    size = body.size
    if "position" in given:
        off = float(np.linalg.norm(np.asarray(initial.position) - r_new))
        if off > JOINT_RTOL * size:
            deviations.append(Deviation(
                "position", off, "m", r_new.tolist(),
                "the centre of mass must be where the joints put it (the joint's point on "
                "its anchor)"))
    if "velocity" in given:
        off = float(np.linalg.norm(np.asarray(initial.velocity) - v_new))
        scale = max(size * float(np.linalg.norm(w_world)), size / duration)
        if off > JOINT_RTOL * scale:
            deviations.append(Deviation(
                "velocity", off, "m/s", v_new.tolist(),
                "the centre of mass must move as the body turns about the joint: ω × (c - "
                "anchor)"))
    state = replace(initial, position=_frozen(r_new), velocity=_frozen(v_new),
                    orientation=_frozen(q), angular_velocity=_frozen(omega))
    return hold, state, deviations


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=np.float64)
    a.setflags(write=False)
    return a
