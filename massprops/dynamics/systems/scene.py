"""The rules of a system scene (``bodies:`` instead of ``body:``) -> `SystemScene`.

Each body is read by the one-body reader (dynamics.scene: mesh or explicit) plus its placement;
every value goes through dynamics.yamlnodes, so each refusal is one line naming file, line and
key. The checks that need the whole system (a loop opened by initial positions, a rate on a joint
that cannot move) are made where the system is assembled (systems.assemble) with the places kept
here in ``SystemScene.places``.
"""

from __future__ import annotations

import dataclasses
import math
import os
from pathlib import Path

import numpy as np
import yaml

from massprops import tolerances
from massprops.dynamics.model import RigidBody, TimeSettings
from massprops.dynamics.scene import (
    TIME_KEYS,
    _body_spec,
    _mesh_body,
    _mesh_files,
    _MeshBodySpec,
    _output,
    _quaternion,
    _time,
    _window,
    read_top,
    scene_text,
)
from massprops.dynamics.systems.model import (
    ONE_AXIS,
    WORLD,
    BodyDrag,
    BodyForce,
    BodySpring,
    SystemBody,
    SystemInitial,
    SystemJoint,
    SystemScene,
)
from massprops.dynamics.yamlnodes import (
    Field,
    compose,
    is_null,
    is_str,
    read_boolean,
    read_choice,
    read_direction,
    read_mapping,
    read_non_negative,
    read_number,
    read_optional_mapping,
    read_string,
    read_type,
    read_vector,
    readonly_array,
    shown,
)
from massprops.errors import SceneError
from massprops.rotation import quat_to_matrix

__all__ = ["is_system_text", "load_system", "parse_system"]

_PLACEMENT = ("position", "orientation")
_JOINT_KEYS = {
    "spherical": ("point",), "revolute": ("point", "axis"), "prismatic": ("point", "axis"),
    "cylindrical": ("point", "axis"), "universal": ("point", "axes"), "fixed": ("point",),
    "distance": ("points",),
}
_ONE_AXIS_KEYS = ("damping", "stiffness", "rest", "torque", "force", "start", "end")


def is_system_text(text: str) -> bool:
    """True when the YAML document has a top-level ``bodies:`` or ``model:`` key (a system
    scene). Cheap: a line scan, so the one-body path stays as it was."""
    return any(line.startswith(("bodies:", "model:")) for line in text.splitlines())


def load_system(path: str | os.PathLike[str]) -> SystemScene:
    """Read and validate the system scene at ``path``; SceneError (one line) on bad input."""
    path = Path(path)
    return parse_system(scene_text(path), source=os.fspath(path), base_dir=path.parent)


def parse_system(text: str, *, source: str, base_dir: Path) -> SystemScene:
    """Parse and validate a whole system scene (see the contract). Raises SceneError."""
    root = compose(text, source)
    if root is None:
        raise SceneError(f"{source}:1: the file is empty")
    top = Field(root, "", source)
    fields = read_top(top, "bodies", {"bodies": "bodies: {crank: {mass: 1, ...}}",
                                      "time": "time: {duration: 10.0}"})
    places: dict[str, str] = {}
    notes: list[str] = []
    specs, names = _bodies(fields["bodies"], base_dir, places, notes)
    index = {name: i for i, name in enumerate(names)}
    joints = _joints(fields.get("joints"), index, places)
    gravity, forces, springs, drags = _forces(fields.get("forces"), index)
    initial = _initial(fields.get("initial"), index, {j.name for j in joints}, places)
    time = system_time(fields["time"])
    output = _output(fields.get("output"), base_dir)
    bodies: list[SystemBody] = []
    inputs: list[Path] = []
    warnings: list[str] = []
    for name, (spec, placement) in zip(names, specs):
        if isinstance(spec, _MeshBodySpec):
            body, said = _mesh_body(spec)
            inputs += _mesh_files(spec.path)
            warnings += [f"{name}: {w}" for w in said]
        else:
            body = spec
        bodies.append(_placed(name, body, placement))
    joints = tuple(_fixed_point(j, bodies) for j in joints)
    return SystemScene(tuple(bodies), joints, gravity, forces, springs, initial, time, output,
                       source=source, input_files=tuple(inputs), warnings=tuple(warnings),
                       places=places, drags=drags, notes=tuple(notes))


def system_time(field: Field) -> TimeSettings:
    """A system scene's ``time:`` (the one-body keys), its integrator one a system runs with:
    a one-body method named there is this file's mistake, said at its line (exit 1), where
    --integrator naming one is the command line's (exit 2, `run.simulate_system`). A duration
    of 0 asks for the start pose's reactions (and a description's holding forces), as
    ``--duration 0`` does."""
    # deferred: the registry is read only once the scene's other keys are known to be good
    from massprops.dynamics.integrators import integrator_names
    from massprops.dynamics.systems.methods import SYSTEM_INTEGRATORS

    time = _time(field, integrator_names(), static=True)
    if time.integrator not in SYSTEM_INTEGRATORS:
        named = read_mapping(field, TIME_KEYS)["integrator"]
        raise named.error(f"{time.integrator} steps one body's state only; a system runs with "
                          f"{', '.join(SYSTEM_INTEGRATORS)}")
    return time


def _fixed_point(joint: SystemJoint, bodies: list) -> SystemJoint:
    """A fixed joint written without a point gets one (any point serves a weld): the second
    body's centre of mass at t = 0, or the first's when the second is the world. Every later
    step (tree, cut rows, reactions) then reads ``point`` like any joint's."""
    if joint.kind != "fixed" or joint.point is not None:
        return joint
    body = bodies[joint.b if joint.b != WORLD else joint.a]
    return dataclasses.replace(joint, point=np.array(body.com0, float))


# --- bodies -------------------------------------------------------------------------------------
def _bodies(field: Field, base_dir: Path, places: dict, notes: list[str]):
    if not isinstance(field.node, yaml.MappingNode):
        raise field.error(f"expected a mapping name -> body, got {shown(field.node)}")
    if not field.node.value:
        raise field.error("the mapping is empty: a system needs at least one body, e.g. "
                          "bodies: {crank: {mass: 1.0, inertia: [[...]], position: [0, 0, 0]}}")
    specs, names = [], []
    for key_node, value_node in field.node.value:
        name = key_node.value if is_str(key_node) else None
        item = field.child(value_node, str(key_node.value))
        if name is None or name == "world":
            raise item.error("expected a body name other than 'world' (the ground)")
        if name in names:
            raise item.error("duplicate body name; give each body its own name")
        if not isinstance(value_node, yaml.MappingNode):
            raise item.error(f"expected a body mapping, got {shown(value_node)}")
        own = [(k, v) for k, v in value_node.value if not (is_str(k) and k.value in _PLACEMENT)]
        placed = {k.value: item.child(v, k.value) for k, v in value_node.value
                  if is_str(k) and k.value in _PLACEMENT}
        stripped = yaml.MappingNode(value_node.tag, own, value_node.start_mark,
                                    value_node.end_mark)
        spec = _body_spec(Field(stripped, item.path, item.source), base_dir)
        if not isinstance(spec, _MeshBodySpec) and "position" not in placed:
            raise item.child(value_node, "position").error(
                "missing; an explicit body needs the world position of its centre of mass "
                "at t = 0, e.g. position: [0, 0, 0]")
        placement = {}
        if "position" in placed:
            placement["position"] = read_vector(placed["position"])
        if "orientation" in placed:
            placement["orientation"] = _quaternion(placed["orientation"], notes)
        places[f"bodies.{name}"] = item.where()
        specs.append((spec, placement))
        names.append(name)
    return specs, names


def _placed(name: str, body: RigidBody, placement: dict) -> SystemBody:
    """The body in the assembly pose: a mesh without placement where its file puts it."""
    rot = (quat_to_matrix(placement["orientation"]) if "orientation" in placement
           else np.eye(3))
    if "position" in placement:
        com0 = np.asarray(placement["position"], float)
    else:  # the mesh frame is the world frame at t = 0
        com0 = rot @ body.center_of_mass
    return SystemBody(name, body.mass, body.inertia_body, rot, com0, body.size, body.mesh)


# --- joints -------------------------------------------------------------------------------------
def _body_ref(field: Field, index: dict, allow_world: bool = True) -> int:
    name = read_string(field, "a body name")
    if name == "world" and allow_world:
        return WORLD
    if name not in index:
        raise field.error(f"unknown body {name!r}; the bodies are: world, {', '.join(index)}")
    return index[name]


def _pair(field: Field, index: dict) -> tuple[int, int]:
    node = field.node
    if not isinstance(node, yaml.SequenceNode) or len(node.value) != 2:
        got = (f"a list of {len(node.value)}" if isinstance(node, yaml.SequenceNode)
               else shown(node))
        raise field.error(f"expected two bodies [first, second] (or [world, body]), got {got}")
    a, b = (_body_ref(field.child(n, i), index) for i, n in enumerate(node.value))
    if a == b:
        raise field.error("a joint joins two different bodies; name two")
    return a, b


def _two_axes(field: Field) -> np.ndarray:
    """(2, 3) a universal joint's two unit axes, which must not be parallel: its two turns
    would then be one, and its motion subspace [a0, a1] (the columns of S, whose singular values
    are √(1 ± cos α), α the angle between the axes) would lose a rank for good (turning about
    a0 keeps a1's angle to it). Refused like a singular pose: where σ_min / σ_max = tan(α' / 2),
    α' the acute angle between the axis lines, is within NEAR_SINGULAR_MARGIN (α' ≤ 2e-6 rad),
    the run's own test of a mechanism at rank loss; nearer than that the joint's mass matrix
    (condition ~1 / tan²) is not positive definite in float64."""
    if not (isinstance(field.node, yaml.SequenceNode) and len(field.node.value) == 2):
        raise field.error("expected two axes [[...], [...]]")
    axes = np.array([np.array(read_direction(field.child(n, k)))
                     for k, n in enumerate(field.node.value)])
    cos = min(abs(float(axes[0] @ axes[1])), 1.0)
    half_turn = float(np.linalg.norm(np.cross(axes[0], axes[1]))) / (1.0 + cos)  # tan(α'/2)
    if not half_turn > tolerances.NEAR_SINGULAR_MARGIN:
        angle = 2.0 * math.atan(half_turn)
        raise field.error(f"the two axes are parallel ({angle:.3g} rad apart as lines): a "
                          "universal joint turns about two different directions, at least "
                          f"{2.0 * math.atan(tolerances.NEAR_SINGULAR_MARGIN):.1g} rad apart "
                          "(typically perpendicular); for one axis use a revolute joint")
    return axes


def _joints(field: Field | None, index: dict, places: dict) -> tuple[SystemJoint, ...]:
    if field is None or is_null(field):
        return ()
    if not isinstance(field.node, yaml.SequenceNode):
        raise field.error(f"expected a list of joints, got {shown(field.node)}")
    out: list[SystemJoint] = []
    for i, node in enumerate(field.node.value):
        item = field.child(node, i)
        kind = read_type(item, tuple(_JOINT_KEYS), "joint type",
                         expected="expected a joint mapping", missing="missing; one of: ")
        keys = ("type", "name", "bodies", *_JOINT_KEYS[kind],
                *(_ONE_AXIS_KEYS if kind in ONE_AXIS else ()))
        required = {"bodies": "bodies: [world, crank]",
                    **{k: f"{k}: ..." for k in _JOINT_KEYS[kind] if k != "point"}}
        if kind != "fixed":
            required.update({k: f"{k}: [0, 0, 0]" for k in _JOINT_KEYS[kind]})
        fields = read_mapping(item, keys, required)
        name = read_string(fields["name"], "a joint name") if "name" in fields else f"j{i}"
        if any(j.name == name for j in out):
            raise (fields.get("name") or item).error(f"duplicate joint name {name!r}")
        a, b = _pair(fields["bodies"], index)
        values: dict = {"point": read_vector(fields["point"]) if "point" in fields else None,
                        "axes": np.zeros((0, 3))}
        if "axis" in fields:
            values["axes"] = np.array(read_direction(fields["axis"]))[None, :]
        if "axes" in fields:
            values["axes"] = _two_axes(fields["axes"])
        if "points" in fields:
            pts = fields["points"]
            if not (isinstance(pts.node, yaml.SequenceNode) and len(pts.node.value) == 2):
                raise pts.error("expected two points [[on first], [on second]]")
            values["points"] = np.array([read_vector(pts.child(n, k))
                                         for k, n in enumerate(pts.node.value)])
            if np.linalg.norm(values["points"][1] - values["points"][0]) == 0:
                raise pts.error("a distance joint's points must differ (use spherical)")
        for key in ("damping", "stiffness"):
            if key in fields:
                values[key] = read_non_negative(fields[key])
        if "rest" in fields:
            values["rest"] = read_number(fields["rest"])
        for key in ("torque", "force"):
            if key in fields:
                if (key == "torque") != (kind == "revolute"):
                    raise fields[key].error(f"a {kind} joint's drive is "
                                            f"{'torque' if kind == 'revolute' else 'force'}")
                values["drive"] = read_number(fields[key])
        if kind in ONE_AXIS:
            values.update(_window(fields))
        places[f"joints.{name}"] = item.where()
        out.append(SystemJoint(name, kind, a, b, **values))
    return tuple(out)


# --- forces -------------------------------------------------------------------------------------
def _forces(field: Field | None, index: dict):
    gravity = np.zeros(3)
    forces: list[BodyForce] = []
    springs: list[BodySpring] = []
    drags: list[BodyDrag] = []
    if field is None or is_null(field):
        return gravity, (), (), ()
    if not isinstance(field.node, yaml.SequenceNode):
        raise field.error(f"expected a list of forces, got {shown(field.node)}")
    for i, node in enumerate(field.node.value):
        item = field.child(node, i)
        kind = read_type(item, ("gravity", "force", "torque", "spring", "drag"), "force type",
                         expected="expected a force mapping", missing="missing; one of: ")
        if kind == "gravity":
            f = read_mapping(item, ("type", "g"), {"g": "g: [0, 0, -9.81]"})
            gravity = gravity + read_vector(f["g"])
        elif kind == "drag":  # on the named body, or on every body as gravity
            f = read_mapping(item, ("type", "body", "linear", "angular"))
            which = [_body_ref(f["body"], index, allow_world=False)] if "body" in f \
                else range(len(index))
            values = {key: read_non_negative(f[key]) for key in ("linear", "angular") if key in f}
            drags += [BodyDrag(b, **values) for b in which]
        elif kind in ("force", "torque"):
            keys = ("type", "body", "vector", "frame", "start", "end",
                    *(("point",) if kind == "force" else ()))
            f = read_mapping(item, keys, {"body": "body: crank", "vector": "vector: [1, 0, 0]"})
            frame = read_choice(f["frame"], ("world", "body"), "frame") if "frame" in f \
                else "world"
            point = read_vector(f["point"]) if "point" in f else None
            forces.append(BodyForce(kind, _body_ref(f["body"], index, allow_world=False),
                                    read_vector(f["vector"]), frame, point, **_window(f)))
        else:
            f = read_mapping(item, ("type", "bodies", "points", "stiffness", "rest_length",
                                    "damping"),
                             {"bodies": "bodies: [world, crank]", "points": "points: [[..], [..]]",
                              "stiffness": "stiffness: 100"})
            a, b = _pair(f["bodies"], index)
            pts = f["points"]
            if not (isinstance(pts.node, yaml.SequenceNode) and len(pts.node.value) == 2):
                raise pts.error("expected two points [[on first], [on second]]")
            points = np.array([read_vector(pts.child(n, k))
                               for k, n in enumerate(pts.node.value)])
            springs.append(BodySpring(a, b, points, read_non_negative(f["stiffness"]),
                                      read_non_negative(f["rest_length"])
                                      if "rest_length" in f else 0.0,
                                      read_non_negative(f["damping"]) if "damping" in f else 0.0))
    return readonly_array(gravity.tolist()), tuple(forces), tuple(springs), tuple(drags)


# --- initial ------------------------------------------------------------------------------------
def _values(field: Field) -> tuple[float, ...]:
    node = field.node
    if isinstance(node, yaml.SequenceNode):
        return tuple(read_number(field.child(n, k)) for k, n in enumerate(node.value))
    return (read_number(field),)


def _initial(field: Field | None, index: dict, joint_names: set, places: dict) -> SystemInitial:
    fields = read_optional_mapping(field, ("positions", "rates", "bodies", "project_initial"))
    out: dict = {"positions": {}, "rates": {}, "velocities": {}}
    for key in ("positions", "rates"):
        for name, child in read_optional_mapping(fields.get(key), sorted(joint_names)).items():
            out[key][name] = _values(child)
            places[f"initial.{key}.{name}"] = child.where()
    for name, child in read_optional_mapping(fields.get("bodies"), list(index)).items():
        f = read_mapping(child, ("velocity", "angular_velocity"))
        out["velocities"][name] = (
            read_vector(f["velocity"]) if "velocity" in f else np.zeros(3),
            read_vector(f["angular_velocity"]) if "angular_velocity" in f else np.zeros(3))
        places[f"initial.bodies.{name}"] = child.where()
    project = read_boolean(fields["project_initial"]) if "project_initial" in fields else False
    if field is not None:
        places["initial"] = field.where()
    return SystemInitial(out["positions"], out["rates"], out["velocities"], project)


def with_time(scene: SystemScene, **changes) -> SystemScene:
    """``scene`` with its time settings changed (duration, rtol, ...)."""
    return dataclasses.replace(scene, time=dataclasses.replace(scene.time, **changes))

