"""Validate a scene YAML file, all of it, into the value objects of ``dynamics.model``.

The scene rules live here: the keys each section takes, the body (a mesh or explicit mass and
inertia), the initial state, the forces (the ``FORCE_TYPES`` registry), time and output; the
joints' own rules live in massprops.dynamics.joints.scene, called from here. Reading
YAML nodes is ``dynamics.yamlnodes``' job, so each error names the file, the line and the key path
in one line: ``scene.yaml:12: forces[2].stiffness: expected a non-negative number, got -3``.
Everything is checked before anything runs; the one expensive step, integrating a mesh body, comes
last, so a typo elsewhere is reported at once.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any, cast

import numpy as np
import yaml

from massprops import tolerances
from massprops.dynamics.budget import too_fast
from massprops.dynamics.integrators import integrator_names
from massprops.dynamics.joints.scene import bind_scene, parse_joints, read_project
from massprops.dynamics.model import (
    INF,
    Drag,
    ForceTerm,
    Gravity,
    InitialState,
    MeshSource,
    OutputSettings,
    PointForce,
    RigidBody,
    Scene,
    Spring,
    TimeSettings,
    Torque,
)
from massprops.dynamics.trajectory import TRAJECTORY_EXTENSIONS
from massprops.dynamics.yamlnodes import (
    Field,
    compose,
    is_null,
    one_line,
    read_boolean,
    read_choice,
    read_mapping,
    read_matrix3,
    read_non_negative,
    read_number,
    read_optional_mapping,
    read_positive,
    read_string,
    read_type,
    read_vector,
    readonly_array,
    shown,
)
from massprops.errors import InputError, MeshFileError, SceneError, UnphysicalInertiaError
from massprops.files import file_problem, read_input

__all__ = ["FORCE_TYPES", "FRAMES", "MODEL_KEYS", "ONE_BODY_KEYS", "OUTPUT_SUFFIXES",
           "SYSTEM_KEYS", "load_scene", "parse_scene", "read_top"]


FRAMES: tuple[str, ...] = ("world", "body")
OUTPUT_SUFFIXES: tuple[str, ...] = TRAJECTORY_EXTENSIONS


# --- the body -----------------------------------------------------------------------------------
_EXPLICIT_BODY_KEYS = ("mass", "inertia", "center_of_mass")
_MESH_BODY_KEYS = ("mesh", "density", "mass", "unit", "allow_open", "union", "shell",
                   "fill_holes")
_BODY_EXAMPLE = ("body: {mesh: part.obj, density: 7850} or "
                 "body: {mass: 12.0, inertia: [[8, 0, 0], [0, 13, 0], [0, 0, 13]]}")


@dataclasses.dataclass(frozen=True)
class _MeshBodySpec:
    """A mesh body checked but not yet read: reading and integrating it is the slow part."""

    field: Field  # the ``mesh`` key: errors from the mesh modules are reported at its line
    path: Path
    unit: str
    allow_open: bool
    amount: dict[str, float]  # {"density": rho} or {"mass": m}
    repairs: dict = dataclasses.field(default_factory=dict)  # massprops.repair.RepairOptions


def _body_spec(field: Field, base_dir: Path) -> RigidBody | _MeshBodySpec:
    fields = read_mapping(field, tuple(dict.fromkeys(_MESH_BODY_KEYS + _EXPLICIT_BODY_KEYS)))
    if "mesh" in fields:
        return _mesh_body_spec(fields, base_dir)
    if "inertia" in fields:
        return _explicit_body(fields, field)
    raise field.error(f"expected a mesh or an explicit mass and inertia, e.g. {_BODY_EXAMPLE}")


def _refuse_keys(fields: dict[str, Field], allowed: Sequence[str], kind: str) -> None:
    for key, child in fields.items():
        if key not in allowed:
            raise child.error(f"{kind} takes only {', '.join(allowed)}; remove {key!r}")


def _explicit_body(fields: dict[str, Field], field: Field) -> RigidBody:
    _refuse_keys(fields, _EXPLICIT_BODY_KEYS, "an explicit body (no mesh:)")
    if "mass" not in fields:
        raise field.child(field.node, "mass").error("missing; an explicit body needs a mass (kg)")
    mass = read_positive(fields["mass"])
    inertia = read_matrix3(fields["inertia"])
    com = read_vector(fields["center_of_mass"]) if "center_of_mass" in fields else np.zeros(3)
    try:
        return RigidBody.from_inertia(mass, inertia, com)
    except UnphysicalInertiaError as exc:
        raise fields["inertia"].error(
            f"{exc}; give the tensor about the centre of mass in body axes, kg·m²") from exc


def _mesh_body_spec(fields: dict[str, Field], base_dir: Path) -> _MeshBodySpec:
    _refuse_keys(fields, _MESH_BODY_KEYS, "a mesh body")
    if "density" in fields and "mass" in fields:
        raise fields["mass"].error("give density or mass, not both")
    path = _existing_file(fields["mesh"], base_dir)
    unit = _unit(fields["unit"]) if "unit" in fields else "m"
    allow_open = read_boolean(fields["allow_open"]) if "allow_open" in fields else False
    if "mass" in fields:
        amount = {"mass": read_positive(fields["mass"])}
    else:  # the same default as ``inspect``
        amount = {"density": read_positive(fields["density"]) if "density" in fields else 1.0}
    repairs: dict[str, bool | float] = {key: read_boolean(fields[key])
                                        for key in ("union", "fill_holes") if key in fields}
    if "shell" in fields:
        repairs["shell"] = read_positive(fields["shell"])  # metres, as every scene value
    return _MeshBodySpec(fields["mesh"], path, unit, allow_open, amount, repairs)


def _existing_file(field: Field, base_dir: Path) -> Path:
    """A path relative to the scene file's folder (or absolute) that names an existing file."""
    path = base_dir / read_string(field, "a file name")
    problem = file_problem(path)
    if problem is not None:
        raise field.error(f"{path} {problem}; relative paths start at the scene file's folder")
    return path


def _unit(field: Field) -> str:
    from massprops.io import UNITS  # the readers' own table, as for the CLI's --unit

    return read_choice(field, tuple(UNITS), "unit")


def _mesh_body(spec: _MeshBodySpec) -> tuple[RigidBody, tuple[str, ...]]:
    """Read, check and integrate the mesh: the body and the health check's warnings. Errors keep
    their class, prefixed with our place."""
    # Imported here: the mesh pipeline is heavy and only mesh bodies need it.
    from massprops.inspection.file import inspect_mesh
    from massprops.io import read_mesh
    from massprops.repair import RepairOptions

    try:
        result = inspect_mesh(read_mesh(spec.path, unit=spec.unit), allow_open=spec.allow_open,
                              repairs=RepairOptions(**spec.repairs), **spec.amount)
        mesh, health, props = result.mesh, result.health, result.properties
    except InputError as exc:
        raise _with_place(exc, spec.field) from exc
    axes = np.asarray(props.principal_axes, dtype=np.float64)
    inertia = (axes * np.asarray(props.principal_moments, dtype=np.float64)) @ axes.T
    try:  # the same checks as an explicit body: an open mesh (allow_open) can fail them
        body = RigidBody.from_inertia(float(props.mass), inertia, props.center_of_mass)
    except UnphysicalInertiaError as exc:
        raise _with_place(type(exc)(f"{spec.path.name}: {exc.template}"), spec.field) from exc
    used = mesh.vertices[np.unique(mesh.faces)]
    bounding_radius = float(np.linalg.norm(used - body.center_of_mass, axis=1).max())
    source = MeshSource(str(spec.path), spec.unit, props.center_of_mass, props.uncertainty)
    return (dataclasses.replace(body, size=max(bounding_radius, body.size), mesh=source),
            tuple(health.warnings))


def _mesh_files(path: Path) -> tuple[Path, ...]:
    """The files a mesh body reads: a ``.vtx``/``.fac`` pair is two (the reader finds the other)."""
    pair = {".vtx": ".fac", ".fac": ".vtx"}.get(path.suffix)
    return (path,) if pair is None else (path, path.with_suffix(pair))


def _as_scene_key(name: str) -> str:
    """A setting an error refers to (`massprops.errors.setting_ref`), as a mesh body's key."""
    return f"{name}: true" if name in ("allow_open", "fill_holes", "union") else name


def _with_place(exc: InputError, field: Field,
                say: Callable[[str], str] = _as_scene_key) -> InputError:
    """The same error class (so callers can still tell an open mesh from a bad scene), its
    message prefixed with the scene file, line and key path, the settings it names said by
    ``say`` (default: as a mesh body's keys)."""
    message = one_line(field.where() + exc.render(say))
    try:
        return type(exc)(message)
    except TypeError:  # a subclass with a different constructor
        return SceneError(message)


# --- initial state, forces, time, output ---------------------------------------------------------
def _quaternion(field: Field, notes: list[str] | None = None) -> np.ndarray:
    """(4,) unit quaternion [w, x, y, z]; a zero one refused, a non-unit one normalised, and
    said in ``notes`` (placed) where its norm misses 1 by more than QUATERNION_UNIT_RTOL."""
    q = np.array(read_vector(field, 4))
    largest = float(np.abs(q).max())
    if largest == 0:
        raise field.error("expected a non-zero quaternion [w, x, y, z], got zero; "
                          "the identity is [1, 0, 0, 0]")
    unit = q / largest
    unit = unit / float(np.linalg.norm(unit))
    norm = largest * float(np.linalg.norm(q / largest))
    if notes is not None and not abs(norm - 1.0) <= tolerances.QUATERNION_UNIT_RTOL:
        shown_q = ", ".join(f"{c:.6g}" for c in unit)
        notes.append(one_line(f"{field.where()}normalised to [{shown_q}] (its norm was "
                              f"{norm:.6g}; a rotation's quaternion has norm 1)"))
    return readonly_array(unit.tolist())


_INITIAL_KEYS = ("position", "orientation", "velocity", "angular_velocity",
                 "angular_velocity_frame", "project_initial")


def _initial(field: Field | None, notes: list[str]) -> InitialState:
    fields = read_optional_mapping(field, _INITIAL_KEYS)
    values: dict[str, Any] = {k: read_vector(fields[k]) for k in
                                 ("position", "velocity", "angular_velocity") if k in fields}
    if "orientation" in fields:
        values["orientation"] = _quaternion(fields["orientation"], notes)
    if "angular_velocity_frame" in fields:
        frame = read_choice(fields["angular_velocity_frame"], FRAMES, "frame")
        values["angular_velocity_frame"] = frame
    read_project(fields)  # checked here too: a scene without joints still gets a typo refused
    return InitialState(**values)


def _frame(fields: dict[str, Field]) -> dict[str, Any]:
    return {"frame": read_choice(fields["frame"], FRAMES, "frame")} if "frame" in fields else {}


def _point(fields: dict[str, Field]) -> dict[str, Any]:
    return {"point": read_vector(fields["point"])} if "point" in fields else {}


def _window(fields: dict[str, Field]) -> dict[str, Any]:
    """start/end (s) of a force or torque; absent means always (an infinite bound)."""
    start = read_number(fields["start"]) if "start" in fields else -INF
    end = read_number(fields["end"]) if "end" in fields else INF
    if start >= end:
        # one of the two is given: start < end holds for both bounds infinite
        where = cast(Field, fields.get("end", fields.get("start")))
        raise where.error(f"expected start < end, got start {start!r} and end {end!r}")
    return {"start": start, "end": end}


def _gravity_fields(item: Field) -> dict[str, Any]:
    fields = read_mapping(item, ("type", "g"), {"g": "g: [0, 0, -9.81]"})
    return {"g": read_vector(fields["g"])}


def _point_force_fields(item: Field) -> dict[str, Any]:
    fields = read_mapping(item, ("type", "vector", "frame", "point", "start", "end"),
                          {"vector": "vector: [1, 0, 0]"})
    return {"vector": read_vector(fields["vector"]), **_frame(fields), **_point(fields),
            **_window(fields)}


def _torque_fields(item: Field) -> dict[str, Any]:
    fields = read_mapping(item, ("type", "vector", "frame", "start", "end"),
                          {"vector": "vector: [0, 0, 1]"})
    return {"vector": read_vector(fields["vector"]), **_frame(fields), **_window(fields)}


def _spring_fields(item: Field) -> dict[str, Any]:
    fields = read_mapping(item, ("type", "anchor", "point", "stiffness", "rest_length", "damping"),
                          {"anchor": "anchor: [0, 0, 1]", "stiffness": "stiffness: 100"})
    values: dict[str, Any] = {"anchor": read_vector(fields["anchor"]),
                                 "stiffness": read_non_negative(fields["stiffness"]),
                                 **_point(fields)}
    for key in ("rest_length", "damping"):
        if key in fields:
            values[key] = read_non_negative(fields[key])
    return values


def _drag_fields(item: Field) -> dict[str, Any]:
    fields = read_mapping(item, ("type", "linear", "angular"))
    return {key: read_non_negative(fields[key]) for key in ("linear", "angular") if key in fields}


FORCE_TYPES: dict[str, tuple[type[ForceTerm], Callable[[Field], dict[str, Any]]]] = {
    "gravity": (Gravity, _gravity_fields),
    "force": (PointForce, _point_force_fields),
    "torque": (Torque, _torque_fields),
    "spring": (Spring, _spring_fields),
    "drag": (Drag, _drag_fields),
}
"""YAML ``type`` -> (model class, parser of the item's other keys into that class's arguments).
A new kind of force is one entry here."""


def _force(item: Field) -> ForceTerm:
    known = tuple(FORCE_TYPES)
    name = read_type(item, known, "force type",
                     expected="expected a mapping such as {type: gravity, g: [0, 0, -9.81]}",
                     missing="missing; every force needs a type, one of: ")
    cls, parse_fields = FORCE_TYPES[name]
    return cls(**parse_fields(item))


def _forces(field: Field | None) -> tuple[ForceTerm, ...]:
    if field is None or is_null(field):
        return ()
    if not isinstance(field.node, yaml.SequenceNode):
        raise field.error(f"expected a list of forces, one '- {{type: ...}}' line each, "
                          f"got {shown(field.node)}")
    return tuple(_force(field.child(node, i)) for i, node in enumerate(field.node.value))


TIME_KEYS = ("duration", "integrator", "rtol", "step")
"""The keys of a scene's ``time:`` (one body and systems alike)."""


def _time(field: Field, known_integrators: Sequence[str], static: bool = False) -> TimeSettings:
    """``time:``; ``static``: a duration of 0 is allowed (a system's start-pose reactions)."""
    fields = read_mapping(field, TIME_KEYS,
                          {"duration": "duration: 10.0 (seconds)"})
    read = read_non_negative if static else read_positive
    values: dict[str, Any] = {"duration": read(fields["duration"])}
    if "integrator" in fields:
        values["integrator"] = read_choice(fields["integrator"], known_integrators, "integrator")
    if "rtol" in fields:
        rtol = read_number(fields["rtol"])
        if not 0 < rtol < 1:
            raise fields["rtol"].error(f"expected a number in (0, 1) such as 1.0e-9, got {rtol!r}")
        if rtol < tolerances.RTOL_FLOOR:
            raise fields["rtol"].error(
                f"{rtol!r} asks for more digits than float64 has (a step is rounded to "
                f"{tolerances.EPS / 2:.2g} relative); the smallest rtol accepted is "
                f"{tolerances.RTOL_FLOOR:g}")
        values["rtol"] = rtol
    if "step" in fields:
        values["step"] = read_positive(fields["step"])
    return TimeSettings(**values)


def _output(field: Field | None, base_dir: Path) -> OutputSettings:
    fields = read_optional_mapping(field, ("every", "file"))
    every = read_positive(fields["every"]) if "every" in fields else None
    path = None
    if "file" in fields:
        path = base_dir / read_string(fields["file"], "a file name ending in .csv or .npz")
        if path.suffix.lower() not in OUTPUT_SUFFIXES:
            raise fields["file"].error(f"expected a name ending in .csv or .npz, got {path.name!r}")
        if not path.parent.is_dir():
            raise fields["file"].error(f"folder {path.parent} does not exist; create it first "
                                       "(relative paths start at the scene file's folder)")
    return OutputSettings(every, path)


# --- the document ---------------------------------------------------------------------------------
ONE_BODY_KEYS = ("body", "initial", "forces", "joints", "time", "output")
SYSTEM_KEYS = ("bodies", "joints", "initial", "forces", "time", "output")
MODEL_KEYS = ("model", "package_path", "xacro_args", "inertials", "base", "initial", "forces",
              "time", "output")
"""The top-level keys of the three kinds of scene: one body (``body:``, read here), a system
(``bodies:``, `systems.scene`) and a robot description (``model:``, `systems.robot_scene`)."""

_KINDS = {"body": ONE_BODY_KEYS, "bodies": SYSTEM_KEYS, "model": MODEL_KEYS}
_KINDS_SAID = ("a scene has body: (one body), bodies: (a system of bodies, with joints:) or "
               "model: (a robot description, with inertials: and base:)")


def read_top(top: Field, kind: str, required: dict[str, str]) -> dict[str, Field]:
    """The top level of a scene of ``kind`` (the key that says what it is: body, bodies or
    model), read as `read_mapping` does; an unknown key's message may suggest a key of another
    kind and says what the kinds are, so a typo'd ``bodys:`` or a ``bodies:`` next to
    ``model:`` is told what a scene may hold, not only what this kind takes."""
    others = tuple(k for name, keys in _KINDS.items() if name != kind for k in keys)
    return read_mapping(top, _KINDS[kind], required, elsewhere=others, alternatives=_KINDS_SAID)


def parse_scene(text: str, *, source: str, base_dir: Path,
                known_integrators: Sequence[str] | None = None) -> Scene:
    """Parse and validate a whole scene.

    text : the YAML document. source : the name used in messages (usually the file's path).
    base_dir : folder that relative ``body.mesh`` and ``output.file`` paths start from.
    known_integrators : names ``time.integrator`` may take; default: the integrator registry's
        (``integrator_names()``), so the scene and the registry cannot disagree.
    Raises SceneError (one line: ``source:line: key.path: problem``) for any invalid input; errors
    of the mesh modules (InputError subclasses) keep their class, with the same prefix.
    """
    base_dir = Path(base_dir)
    root = compose(text, source)
    if root is None:
        raise SceneError(f"{source}:1: the file is empty; a scene needs at least "
                         f"{_BODY_EXAMPLE} and time: {{duration: 10.0}}")
    top = Field(root, "", source)
    if not isinstance(root, yaml.MappingNode):
        raise top.error(f"expected a mapping with keys {', '.join(ONE_BODY_KEYS)} at the top "
                        f"level, got {shown(root)}")
    fields = read_top(top, "body", {"body": _BODY_EXAMPLE, "time": "time: {duration: 10.0}"})
    body = _body_spec(fields["body"], base_dir)
    notes: list[str] = []
    initial = _initial(fields.get("initial"), notes)
    forces = _forces(fields.get("forces"))
    joints, joint_fields = parse_joints(fields.get("joints"))
    if known_integrators is None:
        known_integrators = integrator_names()
    time = _time(fields["time"], known_integrators)
    output = _output(fields.get("output"), base_dir)
    if isinstance(body, _MeshBodySpec):
        body_source, inputs = str(body.path), _mesh_files(body.path)
        body, warnings = _mesh_body(body)
    else:
        body_source, inputs, warnings = "explicit", (), ()
    initial_fields = read_optional_mapping(fields.get("initial"), _INITIAL_KEYS)
    fast = too_fast(body.mass, float(body.principal_moments[-1]), initial.velocity,
                    initial.angular_velocity)
    if fast is not None:
        key, problem = fast
        raise initial_fields[key].error(problem)  # only a given speed can be too large
    scene = Scene(body, initial, forces, time, output, source=source, body_source=body_source,
                  input_files=inputs, warnings=warnings, joints=joints, notes=tuple(notes))
    if not joints:
        return scene
    return bind_scene(scene, project=read_project(initial_fields),
                      given=frozenset(initial_fields), joint_fields=joint_fields,
                      initial_fields=initial_fields, initial_field=fields.get("initial"))


def load_scene(path: str | os.PathLike[str], *,
               known_integrators: Sequence[str] | None = None) -> Scene:
    """Read and validate the scene file at ``path`` (UTF-8 YAML); see ``parse_scene``."""
    path = Path(path)
    return parse_scene(scene_text(path), source=os.fspath(path), base_dir=path.parent,
                       known_integrators=known_integrators)


def scene_text(path: str | os.PathLike[str]) -> str:
    """The text of the scene file at ``path`` (UTF-8, a byte-order mark dropped); SceneError if
    it is missing, unreadable, not a regular file (`massprops.files`) or not UTF-8."""
    source = os.fspath(path)
    try:
        data = read_input(path, what="a scene file (YAML)")
    except MeshFileError as exc:
        if isinstance(exc.__cause__, FileNotFoundError):
            raise SceneError(f"{source}: scene file not found; check the path") from exc
        raise SceneError(exc.template) from exc
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise SceneError(f"{source}: not UTF-8 text (byte {exc.start}); save it as UTF-8") from exc
