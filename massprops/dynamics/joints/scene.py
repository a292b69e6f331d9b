"""The scene's ``joints:`` list and ``initial.project_initial``: read, checked against each other
and against the initial state, with one-line ``file:line: key.path: problem`` messages.

Called by massprops.dynamics.scene once the body is known (the checks need its centre of mass
and size). ``bind_scene`` is also the library's entry for a Scene built in code.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import Any, cast

import yaml

from massprops.dynamics.joints.hold import JointRefusal, consistent_initial, hold_of
from massprops.dynamics.joints.model import Joint, RevoluteJoint, SphericalJoint
from massprops.dynamics.model import Scene
from massprops.dynamics.yamlnodes import (
    Field,
    is_null,
    read_boolean,
    read_direction,
    read_mapping,
    read_non_negative,
    read_number,
    read_type,
    read_vector,
    shown,
)
from massprops.errors import SceneError

__all__ = ["JOINT_TYPES", "bind_scene", "parse_joints"]

INITIAL_KEYS = ("position", "orientation", "velocity", "angular_velocity")


def _spherical(fields: dict[str, Field]) -> dict[str, Any]:
    out: dict[str, Any] = {"anchor": read_vector(fields["anchor"])}
    if "point" in fields:
        out["point"] = read_vector(fields["point"])
    return out


def _revolute(fields: dict[str, Field]) -> dict[str, Any]:
    out = _spherical(fields)
    out["axis"] = read_direction(fields["axis"])
    if "world_axis" in fields:
        out["world_axis"] = read_direction(fields["world_axis"])
    if "damping" in fields:
        out["damping"] = read_non_negative(fields["damping"])
    if "torque" in fields:
        out["torque"] = read_number(fields["torque"])
    start = read_number(fields["start"]) if "start" in fields else -math.inf
    end = read_number(fields["end"]) if "end" in fields else math.inf
    if start >= end:
        # one of the two is given: start < end holds for both bounds infinite
        where = cast(Field, fields.get("end", fields.get("start")))
        raise where.error(f"expected start < end, got start {start!r} and end {end!r}")
    out["start"], out["end"] = start, end
    return out


JOINT_TYPES: dict[str, tuple[type, tuple[str, ...], dict[str, str],
                             Callable[[dict[str, Field]], dict[str, Any]]]] = {
    "spherical": (SphericalJoint, ("type", "point", "anchor"),
                  {"anchor": "anchor: [0, 0, 0]"}, _spherical),
    "revolute": (RevoluteJoint, ("type", "point", "axis", "anchor", "world_axis", "damping",
                                 "torque", "start", "end"),
                 {"axis": "axis: [0, 0, 1]", "anchor": "anchor: [0, 0, 0]"}, _revolute),
}
"""YAML ``type`` -> (model class, keys it takes, required keys with an example, reader)."""


def parse_joints(field: Field | None) -> tuple[tuple[Joint, ...], list[dict[str, Field]]]:
    """The joints of the ``joints:`` list (absent or empty: none) and, per joint, its key
    fields (for messages about a joint found wrong later)."""
    if field is None or is_null(field):
        return (), []
    if not isinstance(field.node, yaml.SequenceNode):
        raise field.error("expected a list of joints, one '- {type: spherical, anchor: "
                          f"[0, 0, 0]}}' line each, got {shown(field.node)}")
    joints, all_fields = [], []
    known = tuple(JOINT_TYPES)
    for i, node in enumerate(field.node.value):
        item = field.child(node, i)
        name = read_type(item, known, "joint type",
                         expected="expected a mapping such as {type: spherical, anchor: [0, 0, 0]}",
                         missing="missing; every joint needs a type, one of: ")
        cls, keys, required, reader = JOINT_TYPES[name]
        fields = read_mapping(item, keys, required)
        joints.append(cls(**reader(fields)))
        all_fields.append({"": item, **fields})
    return tuple(joints), all_fields


def bind_scene(scene: Scene, *, project: bool = False, given: frozenset[str] | None = None,
               joint_fields: list[dict[str, Field]] | None = None,
               initial_fields: dict[str, Field] | None = None,
               initial_field: Field | None = None) -> Scene:
    """``scene`` with its joints checked and its initial state on them.

    given : initial values the scene set (default: all); those not given are derived. project:
    move given values that miss the joints onto them (reported in ``Scene.notes``) instead of
    refusing them. The fields, when the scene came from YAML, place the messages.
    Raises SceneError (one line) for joints that over-constrain the body or an initial state
    that misses them.
    """
    if not scene.joints:
        return scene
    given = frozenset(INITIAL_KEYS) if given is None else given
    try:
        hold = hold_of(scene.joints, scene.body)
    except JointRefusal as exc:
        raise _refusal(scene, exc.key, str(exc), joint_fields, None) from exc
    hold, initial, deviations = consistent_initial(hold, scene.body, scene.initial, given,
                                                   scene.time.duration)
    notes = scene.notes
    if deviations and not project:
        d = deviations[0]
        place = (initial_fields or {}).get(d.key) or initial_field
        raise _refusal(scene, f"initial.{d.key}", d.message(), joint_fields, place)
    if deviations:
        moved = ", ".join(f"{d.key.replace('_', ' ')} by {d.amount:.3g} {d.unit}"
                          for d in deviations)
        where = initial_field.where() if initial_field is not None else f"{scene.source}: "
        notes = (*notes, f"{where}projected onto the joints: {moved}")
    joints = tuple(dataclasses.replace(j, world_axis=hold.world_axis)
                   if isinstance(j, RevoluteJoint) else j for j in scene.joints)
    return dataclasses.replace(scene, initial=initial, joints=joints, notes=notes)


def _refusal(scene: Scene, key: str, message: str, joint_fields, place: Field | None
             ) -> SceneError:
    """A SceneError at the line of ``key`` (``joints[i].name`` or ``initial.name``)."""
    if place is None and key.startswith("joints[") and joint_fields:
        index = int(key[len("joints["):key.index("]")])
        name = key.split(".", 1)[1] if "." in key else ""
        fields = joint_fields[index]
        place = fields.get(name) or fields[""]
    if place is None and joint_fields:
        place = joint_fields[0][""]
    if place is None:
        return SceneError(f"{scene.source}: {key}: {message}")
    line = place.node.start_mark.line + 1
    return SceneError(f"{place.source}:{line}: {key}: {message}")


def read_project(fields: dict[str, Field]) -> bool:
    """``initial.project_initial`` (default false)."""
    return read_boolean(fields["project_initial"]) if "project_initial" in fields else False
