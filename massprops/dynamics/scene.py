"""Read a scene YAML file and validate all of it into the value objects of ``dynamics.model``.

The YAML is composed, not loaded (``yaml.compose`` with ``SafeLoader``): no object is ever built
from a tag, and every node keeps its line, so each error names the file, the line and the key path
in one line: ``scene.yaml:12: forces[2].stiffness: expected a non-negative number, got -3``.
Everything is checked before anything runs; the one expensive step, integrating a mesh body, comes
last, so a typo elsewhere is reported at once.
"""

from __future__ import annotations

import dataclasses
import difflib
import math
import os
import re
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np
import yaml

from massprops.dynamics.model import (
    INF,
    Drag,
    ForceTerm,
    Gravity,
    InitialState,
    OutputSettings,
    PointForce,
    RigidBody,
    Scene,
    Spring,
    TimeSettings,
    Torque,
)
from massprops.errors import InputError, SceneError, UnphysicalInertiaError

KNOWN_INTEGRATORS: tuple[str, ...] = ("auto", "exact", "rk4", "dop853", "splitting", "implicit")
"""Names ``time.integrator`` accepts by default (``parse_scene(known_integrators=...)``)."""

FRAMES: tuple[str, ...] = ("world", "body")
OUTPUT_SUFFIXES: tuple[str, ...] = (".csv", ".npz")

_TAG = "tag:yaml.org,2002:"
_STR, _INT, _FLOAT, _BOOL, _NULL = (_TAG + t for t in ("str", "int", "float", "bool", "null"))
_SEQ, _MAP = _TAG + "seq", _TAG + "map"
_PLAIN_TAGS = frozenset({_STR, _INT, _FLOAT, _BOOL, _NULL, _SEQ, _MAP})

# PyYAML follows YAML 1.1, which reads a plain ``1e-9`` (no dot) as a string; nobody writing that
# means text, so a plain (unquoted) scalar of YAML 1.2 float form counts as the number it shows.
_YAML12_FLOAT = re.compile(r"[-+]?(\.[0-9]+|[0-9]+(\.[0-9]*)?)([eE][-+]?[0-9]+)?")
_SCALARS = yaml.constructor.SafeConstructor()  # only its int/float/bool scalar readers are used


# --- nodes with their key path ------------------------------------------------------------------
class _Field:
    """One YAML node and the key path that reached it, so an error can name file, line and key."""

    __slots__ = ("node", "path", "source")

    def __init__(self, node: yaml.Node, path: str, source: str) -> None:
        self.node, self.path, self.source = node, path, source
        if node.tag not in _PLAIN_TAGS:  # every node read is wrapped first, so none escapes this
            raise self.error(_tag_problem(node.tag))

    def child(self, node: yaml.Node, key: str | int) -> _Field:
        if isinstance(key, int):
            return _Field(node, f"{self.path}[{key}]", self.source)
        return _Field(node, f"{self.path}.{key}" if self.path else key, self.source)

    def where(self) -> str:
        """``file:line: key.path: `` (no key path at the top level)."""
        line = self.node.start_mark.line + 1
        return f"{self.source}:{line}: " + (f"{self.path}: " if self.path else "")

    def error(self, message: str) -> SceneError:
        return SceneError(_one_line(self.where() + message))


def _tag_problem(tag: str) -> str:
    shown = tag.replace(_TAG, "!!")
    if shown == "!!merge":
        return "YAML merge keys (<<) are not supported; write the keys out"
    return f"unsupported YAML tag {shown!r}: a scene is plain data; remove the tag"


def _one_line(text: str) -> str:
    return " ".join(text.split())


def _shown(node: yaml.Node) -> str:
    """How a received value is named in a message."""
    if isinstance(node, yaml.SequenceNode):
        return "a list"
    if isinstance(node, yaml.MappingNode):
        return "a mapping"
    if node.tag == _NULL:
        return "nothing (null)"
    if node.tag == _STR:
        return repr(node.value)
    if node.tag == _BOOL:
        return f"{node.value} (a boolean)"
    return node.value if len(node.value) <= 40 else node.value[:37] + "..."


def _unknown(word: str, known: Sequence[str], what: str) -> str:
    close = difflib.get_close_matches(word, known, n=1)
    hint = f"did you mean {close[0]!r}? " if close else ""
    return f"unknown {what} {word!r}; {hint}expected one of: {', '.join(known)}"


def _is_null(field: _Field | None) -> bool:
    return field is None or (isinstance(field.node, yaml.ScalarNode) and field.node.tag == _NULL)


# --- scalar and container readers ----------------------------------------------------------------
def _mapping(field: _Field, known: Sequence[str],
             required: Mapping[str, str] | None = None) -> dict[str, _Field]:
    """Children of a mapping by key; refuses unknown and duplicate keys, and missing required ones
    (``required`` maps each to an example shown in the message)."""
    node = field.node
    if not isinstance(node, yaml.MappingNode):
        raise field.error(f"expected a mapping with keys {', '.join(known)}, got {_shown(node)}")
    out: dict[str, _Field] = {}
    for key_node, value_node in node.value:
        key_field = _Field(key_node, field.path, field.source)  # refuses a tagged key, e.g. <<
        if not (isinstance(key_node, yaml.ScalarNode) and key_node.tag == _STR):
            raise key_field.error(f"expected a key name, got {_shown(key_node)}")
        key = key_node.value
        named = field.child(key_node, key)
        if key not in known:
            raise named.error(_unknown(key, known, "key"))
        if key in out:
            raise named.error("duplicate key: YAML would silently keep only the last; keep one")
        out[key] = field.child(value_node, key)
    for key, example in (required or {}).items():
        if key not in out:
            raise field.child(node, key).error(f"missing; it is required, e.g. {example}")
    return out


def _optional_mapping(field: _Field | None, known: Sequence[str]) -> dict[str, _Field]:
    """An optional section: absent or empty (``initial:``) means all defaults."""
    return {} if _is_null(field) else _mapping(field, known)


def _number(field: _Field) -> float:
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
        raise field.error(f"expected a number, got {_shown(node)}")
    if not math.isfinite(value):
        raise field.error(f"expected a finite number, got {_shown(node)}")
    return value


def _positive(field: _Field) -> float:
    value = _number(field)
    if value <= 0:
        raise field.error(f"expected a positive number, got {_shown(field.node)}")
    return value


def _non_negative(field: _Field) -> float:
    value = _number(field)
    if value < 0:
        raise field.error(f"expected a non-negative number, got {_shown(field.node)}")
    return value


def _items(field: _Field, length: int, what: str) -> list[_Field]:
    node = field.node
    if not isinstance(node, yaml.SequenceNode):
        raise field.error(f"expected {what}, got {_shown(node)}")
    if len(node.value) != length:
        raise field.error(f"expected {what}, got a list of {len(node.value)}")
    return [field.child(item, i) for i, item in enumerate(node.value)]


def _readonly(values: list[float] | list[list[float]]) -> np.ndarray:
    array = np.array(values, dtype=np.float64)
    array.setflags(write=False)
    return array


def _vector(field: _Field, length: int = 3) -> np.ndarray:
    """(length,) float64, read-only."""
    return _readonly([_number(f) for f in _items(field, length, f"a list of {length} numbers")])


def _matrix3(field: _Field) -> np.ndarray:
    """(3, 3) float64 from a list of 3 rows, read-only."""
    rows = _items(field, 3, "a 3x3 matrix as a list of 3 rows")
    return _readonly([[_number(f) for f in _items(row, 3, "a row of 3 numbers")] for row in rows])


def _string(field: _Field, what: str = "a string") -> str:
    node = field.node
    if not (isinstance(node, yaml.ScalarNode) and node.tag == _STR and node.value):
        raise field.error(f"expected {what}, got {_shown(node)}")
    return node.value


def _choice(field: _Field, options: Sequence[str], what: str = "value") -> str:
    value = _string(field, f"one of {', '.join(options)}")
    if value not in options:
        raise field.error(_unknown(value, options, what))
    return value


def _boolean(field: _Field) -> bool:
    node = field.node
    if not (isinstance(node, yaml.ScalarNode) and node.tag == _BOOL):
        raise field.error(f"expected true or false, got {_shown(node)}")
    return bool(_SCALARS.construct_yaml_bool(node))


def _existing_file(field: _Field, base_dir: Path) -> Path:
    """A path relative to the scene file's folder (or absolute) that names an existing file."""
    path = base_dir / _string(field, "a file name")
    if not path.is_file():
        problem = "is not a file" if path.exists() else "does not exist"
        raise field.error(f"{path} {problem}; relative paths start at the scene file's folder")
    return path


# --- the body -----------------------------------------------------------------------------------
_EXPLICIT_BODY_KEYS = ("mass", "inertia", "center_of_mass")
_MESH_BODY_KEYS = ("mesh", "density", "mass", "unit", "allow_open")
_BODY_EXAMPLE = ("body: {mesh: part.obj, density: 7850} or "
                 "body: {mass: 12.0, inertia: [[8, 0, 0], [0, 13, 0], [0, 0, 13]]}")


@dataclasses.dataclass(frozen=True)
class _MeshBodySpec:
    """A mesh body checked but not yet read: reading and integrating it is the slow part."""

    field: _Field  # the ``mesh`` key: errors from the mesh modules are reported at its line
    path: Path
    unit: str
    allow_open: bool
    amount: dict[str, float]  # {"density": rho} or {"mass": m}


def _body_spec(field: _Field, base_dir: Path) -> RigidBody | _MeshBodySpec:
    fields = _mapping(field, tuple(dict.fromkeys(_MESH_BODY_KEYS + _EXPLICIT_BODY_KEYS)))
    if "mesh" in fields:
        return _mesh_body_spec(fields, base_dir)
    if "inertia" in fields:
        return _explicit_body(fields, field)
    raise field.error(f"expected a mesh or an explicit mass and inertia, e.g. {_BODY_EXAMPLE}")


def _refuse_keys(fields: dict[str, _Field], allowed: Sequence[str], kind: str) -> None:
    for key, child in fields.items():
        if key not in allowed:
            raise child.error(f"{kind} takes only {', '.join(allowed)}; remove {key!r}")


def _explicit_body(fields: dict[str, _Field], field: _Field) -> RigidBody:
    _refuse_keys(fields, _EXPLICIT_BODY_KEYS, "an explicit body (no mesh:)")
    if "mass" not in fields:
        raise field.child(field.node, "mass").error("missing; an explicit body needs a mass (kg)")
    mass = _positive(fields["mass"])
    inertia = _matrix3(fields["inertia"])
    com = _vector(fields["center_of_mass"]) if "center_of_mass" in fields else np.zeros(3)
    try:
        return RigidBody.from_inertia(mass, inertia, com)
    except UnphysicalInertiaError as exc:
        raise fields["inertia"].error(
            f"{exc}; give the tensor about the centre of mass in body axes, kg·m²") from exc


def _mesh_body_spec(fields: dict[str, _Field], base_dir: Path) -> _MeshBodySpec:
    _refuse_keys(fields, _MESH_BODY_KEYS, "a mesh body")
    if "density" in fields and "mass" in fields:
        raise fields["mass"].error("give density or mass, not both")
    path = _existing_file(fields["mesh"], base_dir)
    unit = _unit(fields["unit"]) if "unit" in fields else "m"
    allow_open = _boolean(fields["allow_open"]) if "allow_open" in fields else False
    if "mass" in fields:
        amount = {"mass": _positive(fields["mass"])}
    else:  # the same default as ``inspect``
        amount = {"density": _positive(fields["density"]) if "density" in fields else 1.0}
    return _MeshBodySpec(fields["mesh"], path, unit, allow_open, amount)


def _unit(field: _Field) -> str:
    from massprops.io import UNITS  # the readers' own table, as for the CLI's --unit

    return _choice(field, tuple(UNITS), "unit")


def _mesh_body(spec: _MeshBodySpec) -> tuple[RigidBody, tuple[str, ...]]:
    """Read, check and integrate the mesh: the body and the health check's warnings. Errors keep
    their class, prefixed with our place."""
    # Imported here: the mesh pipeline is heavy and only mesh bodies need it.
    from massprops.health import prepare_mesh
    from massprops.io import read_mesh
    from massprops.mass import mass_properties

    try:
        mesh, health = prepare_mesh(read_mesh(spec.path, unit=spec.unit),
                                     allow_open=spec.allow_open)
        props = mass_properties(mesh, **spec.amount)
    except InputError as exc:
        raise _with_place(exc, spec.field) from exc
    axes = np.asarray(props.principal_axes, dtype=np.float64)
    inertia = (axes * np.asarray(props.principal_moments, dtype=np.float64)) @ axes.T
    try:  # the same checks as an explicit body: an open mesh (allow_open) can fail them
        body = RigidBody.from_inertia(float(props.mass), inertia, props.center_of_mass)
    except UnphysicalInertiaError as exc:
        raise _with_place(type(exc)(f"{spec.path.name}: {exc}"), spec.field) from exc
    used = mesh.vertices[np.unique(mesh.faces)]
    bounding_radius = float(np.linalg.norm(used - body.center_of_mass, axis=1).max())
    return dataclasses.replace(body, size=max(bounding_radius, body.size)), tuple(health.warnings)


def _mesh_files(path: Path) -> tuple[Path, ...]:
    """The files a mesh body reads: a ``.vtx``/``.fac`` pair is two (the reader finds the other)."""
    pair = {".vtx": ".fac", ".fac": ".vtx"}.get(path.suffix)
    return (path,) if pair is None else (path, path.with_suffix(pair))


def _with_place(exc: InputError, field: _Field) -> InputError:
    """The same error class (so callers can still tell an open mesh from a bad scene), its
    message prefixed with the scene file, line and key path."""
    # The mesh modules word their fixes for the command line; in a scene the option is a key.
    message = _one_line(field.where() + str(exc).replace("--allow-open", "allow_open: true"))
    try:
        return type(exc)(message)
    except TypeError:  # a subclass with a different constructor
        return SceneError(message)


# --- initial state, forces, time, output ---------------------------------------------------------
def _quaternion(field: _Field) -> np.ndarray:
    """(4,) unit quaternion [w, x, y, z]; a non-unit one is normalised, a zero one refused."""
    q = np.array(_vector(field, 4))
    norm = float(np.linalg.norm(q))
    if norm == 0:
        raise field.error("expected a non-zero quaternion [w, x, y, z], got zero; "
                          "the identity is [1, 0, 0, 0]")
    return _readonly((q / norm).tolist())


def _initial(field: _Field | None) -> InitialState:
    fields = _optional_mapping(field, ("position", "orientation", "velocity", "angular_velocity",
                                       "angular_velocity_frame"))
    values: dict[str, object] = {k: _vector(fields[k]) for k in
                                 ("position", "velocity", "angular_velocity") if k in fields}
    if "orientation" in fields:
        values["orientation"] = _quaternion(fields["orientation"])
    if "angular_velocity_frame" in fields:
        frame = _choice(fields["angular_velocity_frame"], FRAMES, "frame")
        values["angular_velocity_frame"] = frame
    return InitialState(**values)


def _frame(fields: dict[str, _Field]) -> dict[str, object]:
    return {"frame": _choice(fields["frame"], FRAMES, "frame")} if "frame" in fields else {}


def _point(fields: dict[str, _Field]) -> dict[str, object]:
    return {"point": _vector(fields["point"])} if "point" in fields else {}


def _window(fields: dict[str, _Field]) -> dict[str, object]:
    """start/end (s) of a force or torque; absent means always (an infinite bound)."""
    start = _number(fields["start"]) if "start" in fields else -INF
    end = _number(fields["end"]) if "end" in fields else INF
    if start >= end:
        where = fields.get("end", fields.get("start"))
        raise where.error(f"expected start < end, got start {start!r} and end {end!r}")
    return {"start": start, "end": end}


def _gravity_fields(item: _Field) -> dict[str, object]:
    fields = _mapping(item, ("type", "g"), {"g": "g: [0, 0, -9.81]"})
    return {"g": _vector(fields["g"])}


def _point_force_fields(item: _Field) -> dict[str, object]:
    fields = _mapping(item, ("type", "vector", "frame", "point", "start", "end"),
                      {"vector": "vector: [1, 0, 0]"})
    return {"vector": _vector(fields["vector"]), **_frame(fields), **_point(fields),
            **_window(fields)}


def _torque_fields(item: _Field) -> dict[str, object]:
    fields = _mapping(item, ("type", "vector", "frame", "start", "end"),
                      {"vector": "vector: [0, 0, 1]"})
    return {"vector": _vector(fields["vector"]), **_frame(fields), **_window(fields)}


def _spring_fields(item: _Field) -> dict[str, object]:
    fields = _mapping(item, ("type", "anchor", "point", "stiffness", "rest_length", "damping"),
                      {"anchor": "anchor: [0, 0, 1]", "stiffness": "stiffness: 100"})
    values: dict[str, object] = {"anchor": _vector(fields["anchor"]),
                                 "stiffness": _non_negative(fields["stiffness"]), **_point(fields)}
    for key in ("rest_length", "damping"):
        if key in fields:
            values[key] = _non_negative(fields[key])
    return values


def _drag_fields(item: _Field) -> dict[str, object]:
    fields = _mapping(item, ("type", "linear", "angular"))
    return {key: _non_negative(fields[key]) for key in ("linear", "angular") if key in fields}


FORCE_TYPES: dict[str, tuple[type[ForceTerm], Callable[[_Field], dict[str, object]]]] = {
    "gravity": (Gravity, _gravity_fields),
    "force": (PointForce, _point_force_fields),
    "torque": (Torque, _torque_fields),
    "spring": (Spring, _spring_fields),
    "drag": (Drag, _drag_fields),
}
"""YAML ``type`` -> (model class, parser of the item's other keys into that class's arguments).
A new kind of force is one entry here."""


def _force(item: _Field) -> ForceTerm:
    known = tuple(FORCE_TYPES)
    if not isinstance(item.node, yaml.MappingNode):
        raise item.error(f"expected a mapping such as {{type: gravity, g: [0, 0, -9.81]}}, "
                         f"got {_shown(item.node)}")
    type_nodes = [v for k, v in item.node.value if isinstance(k, yaml.ScalarNode)
                  and k.tag == _STR and k.value == "type"]
    if not type_nodes:
        raise item.child(item.node, "type").error(f"missing; every force needs a type, one of: "
                                                  f"{', '.join(known)}")
    type_field = item.child(type_nodes[0], "type")
    name = _choice(type_field, known, "force type")
    cls, parse_fields = FORCE_TYPES[name]
    return cls(**parse_fields(item))


def _forces(field: _Field | None) -> tuple[ForceTerm, ...]:
    if _is_null(field):
        return ()
    if not isinstance(field.node, yaml.SequenceNode):
        raise field.error(f"expected a list of forces, one '- {{type: ...}}' line each, "
                          f"got {_shown(field.node)}")
    return tuple(_force(field.child(node, i)) for i, node in enumerate(field.node.value))


def _time(field: _Field, known_integrators: Sequence[str]) -> TimeSettings:
    fields = _mapping(field, ("duration", "integrator", "rtol", "step"),
                      {"duration": "duration: 10.0 (seconds)"})
    values: dict[str, object] = {"duration": _positive(fields["duration"])}
    if "integrator" in fields:
        values["integrator"] = _choice(fields["integrator"], known_integrators, "integrator")
    if "rtol" in fields:
        rtol = _number(fields["rtol"])
        if not 0 < rtol < 1:
            raise fields["rtol"].error(f"expected a number in (0, 1) such as 1.0e-9, got {rtol!r}")
        values["rtol"] = rtol
    if "step" in fields:
        values["step"] = _positive(fields["step"])
    return TimeSettings(**values)


def _output(field: _Field | None, base_dir: Path) -> OutputSettings:
    fields = _optional_mapping(field, ("every", "file"))
    every = _positive(fields["every"]) if "every" in fields else None
    path = None
    if "file" in fields:
        path = base_dir / _string(fields["file"], "a file name ending in .csv or .npz")
        if path.suffix not in OUTPUT_SUFFIXES:
            raise fields["file"].error(f"expected a name ending in .csv or .npz, got {path.name!r}")
        if not path.parent.is_dir():
            raise fields["file"].error(f"folder {path.parent} does not exist; create it first "
                                       "(relative paths start at the scene file's folder)")
    return OutputSettings(every, path)


# --- the document ---------------------------------------------------------------------------------
_TOP_KEYS = ("body", "initial", "forces", "time", "output")


def _compose(text: str, source: str) -> yaml.Node:
    """The YAML node tree; YAML's own errors reported at their line and column."""
    try:
        root = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as exc:
        mark, context = exc.problem_mark or exc.context_mark, exc.context_mark
        where = f"{source}:{mark.line + 1}:{mark.column + 1}" if mark else source
        opened = f" (line {context.line + 1}, column {context.column + 1})" if context else ""
        what = "; ".join(p for p in (exc.context and exc.context + opened, exc.problem) if p)
        raise SceneError(_one_line(f"{where}: invalid YAML: {what}")) from exc
    except yaml.reader.ReaderError as exc:  # a forbidden character: a position, no mark
        line = text.count("\n", 0, exc.position) + 1
        char = f"#x{exc.character:04x}" if isinstance(exc.character, int) else repr(exc.character)
        raise SceneError(_one_line(f"{source}:{line}: invalid YAML: {exc.reason} "
                                   f"(character {char}); remove it")) from exc
    if root is None or (isinstance(root, yaml.ScalarNode) and root.tag == _NULL):
        raise SceneError(f"{source}:1: the file is empty; a scene needs at least "
                         f"{_BODY_EXAMPLE} and time: {{duration: 10.0}}")
    return root


def parse_scene(text: str, *, source: str, base_dir: Path,
                known_integrators: Sequence[str] = KNOWN_INTEGRATORS) -> Scene:
    """Parse and validate a whole scene.

    text : the YAML document. source : the name used in messages (usually the file's path).
    base_dir : folder that relative ``body.mesh`` and ``output.file`` paths start from.
    known_integrators : names ``time.integrator`` may take.
    Raises SceneError (one line: ``source:line: key.path: problem``) for any invalid input; errors
    of the mesh modules (InputError subclasses) keep their class, with the same prefix.
    """
    base_dir = Path(base_dir)
    root = _compose(text, source)
    top = _Field(root, "", source)
    if not isinstance(root, yaml.MappingNode):
        raise top.error(f"expected a mapping with keys {', '.join(_TOP_KEYS)} at the top level, "
                        f"got {_shown(root)}")
    fields = _mapping(top, _TOP_KEYS, {"body": _BODY_EXAMPLE, "time": "time: {duration: 10.0}"})
    body = _body_spec(fields["body"], base_dir)
    initial = _initial(fields.get("initial"))
    forces = _forces(fields.get("forces"))
    time = _time(fields["time"], known_integrators)
    output = _output(fields.get("output"), base_dir)
    if isinstance(body, _MeshBodySpec):
        body_source, inputs = str(body.path), _mesh_files(body.path)
        body, warnings = _mesh_body(body)
    else:
        body_source, inputs, warnings = "explicit", (), ()
    return Scene(body, initial, forces, time, output, source=source, body_source=body_source,
                 input_files=inputs, warnings=warnings)


def load_scene(path: str | os.PathLike[str], *,
               known_integrators: Sequence[str] = KNOWN_INTEGRATORS) -> Scene:
    """Read and validate the scene file at ``path`` (UTF-8 YAML); see ``parse_scene``."""
    path = Path(path)
    source = os.fspath(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except FileNotFoundError as exc:
        raise SceneError(f"{source}: scene file not found; check the path") from exc
    except UnicodeDecodeError as exc:
        raise SceneError(f"{source}: not UTF-8 text (byte {exc.start}); save it as UTF-8") from exc
    except OSError as exc:
        raise SceneError(f"{source}: cannot read the scene file: {exc.strerror}") from exc
    return parse_scene(text, source=source, base_dir=path.parent,
                       known_integrators=known_integrators)
