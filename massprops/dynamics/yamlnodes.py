"""Read plain YAML data as nodes that keep their line, so every error names file, line and key path.

Scene-agnostic: this module knows YAML, not scenes. The text is composed, not loaded
(``yaml.compose`` with ``SafeLoader``): no object is ever built from a tag, tags other than the
plain ones, merge keys (``<<``) and duplicate keys are refused, and each value is read by a small
reader (``read_number``, ``read_vector``, ``read_mapping``, ...) that raises ``SceneError`` with a
one-line message ``source:line: key.path: expected ..., got ...``.
"""

from __future__ import annotations

import difflib
import math
import re
from collections.abc import Mapping, Sequence

import numpy as np
import yaml

from massprops.errors import SceneError

__all__ = [
    "Field",
    "compose",
    "is_null",
    "is_str",
    "one_line",
    "read_boolean",
    "read_choice",
    "read_direction",
    "read_mapping",
    "read_matrix3",
    "read_non_negative",
    "read_number",
    "read_optional_mapping",
    "read_positive",
    "read_string",
    "read_vector",
    "readonly_array",
    "shown",
]

_TAG = "tag:yaml.org,2002:"
_STR, _INT, _FLOAT, _BOOL, _NULL = (_TAG + t for t in ("str", "int", "float", "bool", "null"))
_SEQ, _MAP = _TAG + "seq", _TAG + "map"
_PLAIN_TAGS = frozenset({_STR, _INT, _FLOAT, _BOOL, _NULL, _SEQ, _MAP})

# PyYAML follows YAML 1.1, which reads a plain ``1e-9`` (no dot) as a string; nobody writing that
# means text, so a plain (unquoted) scalar of YAML 1.2 float form counts as the number it shows.
_YAML12_FLOAT = re.compile(r"[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?")
_SCALARS = yaml.constructor.SafeConstructor()  # only its int/float/bool scalar readers are used


# --- composing the document ---------------------------------------------------------------------
def compose(text: str, source: str) -> yaml.Node | None:
    """The YAML node tree of ``text``, or None for an empty document (nothing, or a bare null).

    source : the name used in messages. YAML's own errors are raised as SceneError at their line
    and column.
    """
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as exc:
        mark, context = exc.problem_mark or exc.context_mark, exc.context_mark
        where = f"{source}:{mark.line + 1}:{mark.column + 1}" if mark else source
        opened = f" (line {context.line + 1}, column {context.column + 1})" if context else ""
        what = "; ".join(p for p in (exc.context and exc.context + opened, exc.problem) if p)
        raise SceneError(one_line(f"{where}: invalid YAML: {what}")) from exc
    except yaml.reader.ReaderError as exc:  # a forbidden character: a position, no mark
        line = text.count("\n", 0, exc.position) + 1
        char = f"#x{exc.character:04x}" if isinstance(exc.character, int) else repr(exc.character)
        raise SceneError(one_line(f"{source}:{line}: invalid YAML: {exc.reason} "
                                  f"(character {char}); remove it")) from exc
    if root is None or (isinstance(root, yaml.ScalarNode) and root.tag == _NULL):
        return None
    return root


# --- nodes with their key path ------------------------------------------------------------------
class Field:
    """One YAML node and the key path that reached it, so an error can name file, line and key."""

    __slots__ = ("node", "path", "source")

    def __init__(self, node: yaml.Node, path: str, source: str) -> None:
        self.node, self.path, self.source = node, path, source
        if node.tag not in _PLAIN_TAGS:  # every node read is wrapped first, so none escapes this
            raise self.error(_tag_problem(node.tag))

    def child(self, node: yaml.Node, key: str | int) -> Field:
        if isinstance(key, int):
            return Field(node, f"{self.path}[{key}]", self.source)
        return Field(node, f"{self.path}.{key}" if self.path else key, self.source)

    def where(self) -> str:
        """``file:line: key.path: `` (no key path at the top level)."""
        line = self.node.start_mark.line + 1
        return f"{self.source}:{line}: " + (f"{self.path}: " if self.path else "")

    def error(self, message: str) -> SceneError:
        return SceneError(one_line(self.where() + message))


def _tag_problem(tag: str) -> str:
    shown_tag = tag.replace(_TAG, "!!")
    if shown_tag == "!!merge":
        return "YAML merge keys (<<) are not supported; write the keys out"
    return f"unsupported YAML tag {shown_tag!r}: a scene is plain data; remove the tag"


def one_line(text: str) -> str:
    """``text`` with every run of whitespace (newlines included) made one space."""
    return " ".join(text.split())


def shown(node: yaml.Node) -> str:
    """How a received value is named in a message."""
    if isinstance(node, yaml.SequenceNode):
        return "a list"
    if isinstance(node, yaml.MappingNode):
        return "a mapping"
    if node.tag == _NULL:
        return "nothing (null)"
    if node.tag == _STR:  # a whole file read as one string (XML, a log) must not fill the line
        text = repr(node.value)
        return text if len(text) <= 60 else text[:56] + "...'"
    if node.tag == _BOOL:
        return f"{node.value} (a boolean)"
    return node.value if len(node.value) <= 40 else node.value[:37] + "..."


def _unknown(word: str, known: Sequence[str], what: str,
             candidates: Sequence[str] | None = None) -> str:
    close = difflib.get_close_matches(word, known if candidates is None else candidates, n=1)
    hint = f"did you mean {close[0]!r}? " if close else ""
    return f"unknown {what} {word!r}; {hint}expected one of: {', '.join(known)}"


def is_null(field: Field | None) -> bool:
    """True for an absent field (None) or an explicit null / empty value."""
    return field is None or (isinstance(field.node, yaml.ScalarNode) and field.node.tag == _NULL)


def is_str(node: yaml.Node) -> bool:
    """True for a string scalar (plain or quoted), e.g. a mapping key."""
    return isinstance(node, yaml.ScalarNode) and node.tag == _STR


# --- container readers --------------------------------------------------------------------------
def read_mapping(field: Field, known: Sequence[str],
                 required: Mapping[str, str] | None = None, *, elsewhere: Sequence[str] = (),
                 alternatives: str = "") -> dict[str, Field]:
    """Children of a mapping by key; refuses unknown and duplicate keys, and missing required ones
    (``required`` maps each to an example shown in the message). An unknown key's message may
    suggest a key of ``elsewhere`` too (keys a mapping of another kind takes at this place) and
    ends with ``alternatives`` (what those other kinds are)."""
    node = field.node
    if not isinstance(node, yaml.MappingNode):
        raise field.error(f"expected a mapping with keys {', '.join(known)}, got {shown(node)}")
    out: dict[str, Field] = {}
    for key_node, value_node in node.value:
        key_field = Field(key_node, field.path, field.source)  # refuses a tagged key, e.g. <<
        if not is_str(key_node):
            raise key_field.error(f"expected a key name, got {shown(key_node)}")
        key = key_node.value
        named = field.child(key_node, key)
        if key not in known:
            # another kind's own key is not a typo of one: the alternatives say where it goes
            pool = known if key in elsewhere else (*known, *elsewhere)
            raise named.error(_unknown(key, known, "key", pool)
                              + (f"; {alternatives}" if alternatives else ""))
        if key in out:
            raise named.error("duplicate key: YAML would silently keep only the last; keep one")
        out[key] = field.child(value_node, key)
    for key, example in (required or {}).items():
        if key not in out:
            raise field.child(node, key).error(f"missing; it is required, e.g. {example}")
    return out


def read_optional_mapping(field: Field | None, known: Sequence[str]) -> dict[str, Field]:
    """An optional section: absent or empty (``initial:``) means all defaults."""
    return {} if field is None or is_null(field) else read_mapping(field, known)


def _items(field: Field, length: int, what: str) -> list[Field]:
    node = field.node
    if not isinstance(node, yaml.SequenceNode):
        raise field.error(f"expected {what}, got {shown(node)}")
    if len(node.value) != length:
        raise field.error(f"expected {what}, got a list of {len(node.value)}")
    return [field.child(item, i) for i, item in enumerate(node.value)]


# --- scalar readers -----------------------------------------------------------------------------
def read_number(field: Field) -> float:
    """A finite int or float (bool is not a number; neither is a quoted string)."""
    node = field.node
    value: float | None = None
    if isinstance(node, yaml.ScalarNode):
        try:
            if node.tag == _INT:
                value = float(_SCALARS.construct_yaml_int(node))
            elif node.tag == _FLOAT:
                value = float(_SCALARS.construct_yaml_float(node))
            elif node.tag == _STR and node.style is None and _YAML12_FLOAT.fullmatch(node.value):
                value = float(node.value)
        except OverflowError:  # an integer literal beyond float range
            value = math.inf
    if value is None:
        raise field.error(f"expected a number, got {shown(node)}")
    if not math.isfinite(value):
        raise field.error(f"expected a finite number, got {shown(node)}")
    return value


def read_positive(field: Field) -> float:
    value = read_number(field)
    if value <= 0:
        raise field.error(f"expected a positive number, got {shown(field.node)}")
    return value


def read_non_negative(field: Field) -> float:
    value = read_number(field)
    if value < 0:
        raise field.error(f"expected a non-negative number, got {shown(field.node)}")
    return value


def read_string(field: Field, what: str = "a string") -> str:
    """A non-empty string; ``what`` names the expectation in the message."""
    node = field.node
    if not (is_str(node) and node.value):
        raise field.error(f"expected {what}, got {shown(node)}")
    return node.value


def read_strings(field: Field, what: str = "a string") -> list[tuple[Field, str]]:
    """One string or a list of them (each non-empty), each with its field (for its line)."""
    if not isinstance(field.node, yaml.SequenceNode):
        return [(field, read_string(field, f"{what} or a list of them"))]
    items = [field.child(item, i) for i, item in enumerate(field.node.value)]
    return [(item, read_string(item, what)) for item in items]


def read_choice(field: Field, options: Sequence[str], what: str = "value") -> str:
    """One of ``options``; an unknown word gets a did-you-mean suggestion."""
    value = read_string(field, f"one of {', '.join(options)}")
    if value not in options:
        raise field.error(_unknown(value, options, what))
    return value


def read_type(item: Field, known: Sequence[str], what: str, *, expected: str,
              missing: str) -> str:
    """The ``type`` of a list item that must be a mapping (a force, a joint), one of ``known``.
    ``expected`` starts the error for an item that is no mapping (", got ..." follows);
    ``missing`` the error for a mapping without ``type`` (the known types follow)."""
    if not isinstance(item.node, yaml.MappingNode):
        raise item.error(f"{expected}, got {shown(item.node)}")
    types = [v for k, v in item.node.value if is_str(k) and k.value == "type"]
    if not types:
        raise item.child(item.node, "type").error(f"{missing}{', '.join(known)}")
    return read_choice(item.child(types[0], "type"), known, what)


def read_boolean(field: Field) -> bool:
    node = field.node
    if not (isinstance(node, yaml.ScalarNode) and node.tag == _BOOL):
        raise field.error(f"expected true or false, got {shown(node)}")
    return bool(_SCALARS.construct_yaml_bool(node))


# --- arrays -------------------------------------------------------------------------------------
def readonly_array(values: list[float] | list[list[float]]) -> np.ndarray:
    """``values`` as a float64 array that cannot be written to."""
    array = np.array(values, dtype=np.float64)
    array.setflags(write=False)
    return array


def read_vector(field: Field, length: int = 3) -> np.ndarray:
    """(length,) float64, read-only."""
    return readonly_array([read_number(f)
                           for f in _items(field, length, f"a list of {length} numbers")])


def read_direction(field: Field) -> np.ndarray:
    """(3,) a unit vector along a list of 3 numbers that is not zero, read-only. Scaled by its
    largest component before its length is taken, so that no length overflows or underflows
    (|[1e300, 0, 0]|² is beyond float64, |[1e-170, 0, 0]|² below it): any finite non-zero
    vector has a direction."""
    v = np.array(read_vector(field))
    largest = float(np.abs(v).max())
    if largest == 0.0:
        raise field.error("expected a non-zero direction, got a zero-length axis")
    v = v / largest
    return readonly_array((v / float(np.linalg.norm(v))).tolist())


def read_matrix3(field: Field) -> np.ndarray:
    """(3, 3) float64 from a list of 3 rows, read-only."""
    rows = _items(field, 3, "a 3x3 matrix as a list of 3 rows")
    return readonly_array([[read_number(f) for f in _items(row, 3, "a row of 3 numbers")]
                           for row in rows])
