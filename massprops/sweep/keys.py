"""Paths to scene values and to a run's outputs: ``bodies.upper.mass``, ``forces[0].stiffness``,
``joints.elbow.damping``, ``initial.angular_velocity[1]``, ``final.joints.elbow.force``.

A path is mapping keys joined by dots and list items by ``[i]``; in a list whose items are
mappings with a ``name`` (a system's joints), an item may also be named (``joints.elbow``). The
same grammar reads a scene document (its composed YAML nodes, so that the rest of the file,
its styles and its numbers stay exactly as written) and a result's JSON object.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

import yaml

from massprops.errors import SceneError, UsageError

_TOKEN = re.compile(r"\.?([A-Za-z_][A-Za-z0-9_-]*)|\[(\d+)\]")
_FLOAT_TAG = "tag:yaml.org,2002:float"
_NUMBER_TAGS = ("tag:yaml.org,2002:int", _FLOAT_TAG)

Step = str | int
"""One step of a path: a mapping key or a named list item (str), or a list index (int)."""


def parse_path(text: str, what: str = "key") -> tuple[Step, ...]:
    """The steps of ``text``; UsageError naming it when it is not a path."""
    steps: list[Step] = []
    at = 0
    while at < len(text):
        match = _TOKEN.match(text, at)
        if match is None or (at == 0 and text.startswith(".")):
            raise UsageError(f"{what} {text!r}: not a path (keys joined by dots, list items by "
                             "[i], e.g. bodies.upper.mass or forces[0].stiffness)")
        steps.append(match[1] if match[1] is not None else int(match[2]))
        at = match.end()
    if not steps:
        raise UsageError(f"{what} {text!r}: empty")
    return tuple(steps)


def show_path(steps: tuple[Step, ...]) -> str:
    """``steps`` written back as a path."""
    out = ""
    for s in steps:
        out += f"[{s}]" if isinstance(s, int) else (f".{s}" if out else s)
    return out


# --- scene documents ----------------------------------------------------------------------------
@dataclass(frozen=True)
class Place:
    """Where a path ends in a scene document: the scalar node and what holds it (a mapping's
    key/value pair index, or a sequence's item index), so that it can be replaced."""

    parent: yaml.Node
    index: int
    node: yaml.ScalarNode


def _child(node: yaml.Node, step: Step) -> tuple[int, yaml.Node] | None:
    if isinstance(node, yaml.MappingNode) and isinstance(step, str):
        for i, (key, value) in enumerate(node.value):
            if key.value == step:
                return i, value
        return None
    if isinstance(node, yaml.SequenceNode):
        if isinstance(step, int):
            return (step, node.value[step]) if step < len(node.value) else None
        for i, item in enumerate(node.value):  # a named item
            if isinstance(item, yaml.MappingNode) and any(
                    k.value == "name" and getattr(v, "value", None) == step
                    for k, v in item.value):
                return i, item
    return None


def find(root: yaml.Node, steps: tuple[Step, ...], source: str) -> Place:
    """The number at ``steps`` in the document ``root``; SceneError (one line, naming the file
    and the key) when the path does not lead to a number."""
    parent, index, node = None, 0, root
    for depth, step in enumerate(steps):
        found = _child(node, step)
        if found is None:
            raise SceneError(f"{source}: sweep key {show_path(steps)}: the scene has no "
                             f"{show_path(steps[:depth + 1])}")
        parent, (index, node) = node, found
    if isinstance(node, yaml.SequenceNode):
        raise SceneError(f"{source}: sweep key {show_path(steps)} is a list; vary one of its "
                         f"items, e.g. {show_path(steps)}[0]")
    if not isinstance(node, yaml.ScalarNode) or node.tag not in _NUMBER_TAGS \
            and not _is_number(node.value):
        raise SceneError(f"{source}: sweep key {show_path(steps)} is {node.value!r}, not a "
                         "number")
    assert parent is not None
    return Place(parent, index, node)


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def value_at(place: Place) -> float:
    """The number written at ``place``."""
    return float(place.node.value)


def set_value(place: Place, value: float) -> None:
    """Write ``value`` at ``place`` (a plain float scalar, exactly as repr gives it)."""
    new = yaml.ScalarNode(_FLOAT_TAG, repr(float(value)), place.node.start_mark,
                          place.node.end_mark)
    if isinstance(place.parent, yaml.MappingNode):
        key, _ = place.parent.value[place.index]
        place.parent.value[place.index] = (key, new)
    else:
        place.parent.value[place.index] = new


# --- results ------------------------------------------------------------------------------------
def read_output(obj: Any, steps: tuple[Step, ...]) -> Any:
    """The value at ``steps`` in a result's JSON object (dicts and lists), or KeyError."""
    for step in steps:
        if isinstance(obj, dict):
            obj = obj[step]
        elif isinstance(obj, list) and isinstance(step, int) and step < len(obj):
            obj = obj[step]
        else:
            raise KeyError(step)
    return obj
