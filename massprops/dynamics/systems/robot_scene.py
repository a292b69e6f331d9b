"""System scenes that name a robot description (``model:``), and the description run alone.

The scene (contract, "simulate a robot description"):

    model: arm.urdf            # URDF, SDF, MJCF or .xacro; relative to the scene file's folder
    package_path: [../ros]     # folders for package:// and model:// (optional; as --package-path)
    xacro_args: [arm:=left]    # a .xacro's $(arg NAME) values (optional; as --xacro-arg)
    inertials: stated          # or computed
    base: fixed                # or floating; absent: the description's own
    initial: {positions: {shoulder: 0.3}, rates: {elbow: 1.0}}
    forces: [{type: gravity, g: [0, 0, -9.81]}]
    time: {duration: 2.0}
    output: {every: 0.01, file: arm.csv}

Bodies are named after links (a fixed group after its link nearest the base), joints keep the
description's names; ``initial`` and ``forces`` take them as in a ``bodies:`` scene.
`description_scene` is ``massprops simulate ROBOT``: stated inertials, the description's base,
gravity 9.81 m/s² down z (MJCF: its ``<option gravity>``), the zero pose at rest.
"""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np
import yaml

from massprops.dynamics.model import OutputSettings, TimeSettings
from massprops.dynamics.scene import _output, _with_place, read_top, scene_text
from massprops.dynamics.systems.description import (
    BASES,
    INERTIALS,
    Description,
    check_mass_matrix,
    describe,
)
from massprops.dynamics.systems.model import SystemInitial, SystemScene
from massprops.dynamics.systems.scene import (
    _forces,
    _initial,
    is_system_text,
    parse_system,
    system_time,
    with_time,
)
from massprops.dynamics.yamlnodes import (
    Field,
    compose,
    read_choice,
    read_string,
    read_strings,
)
from massprops.errors import InputError, SceneError, UsageError, setting_ref
from massprops.files import file_problem
from massprops.robot.formats.xacro_run import parse_xacro_arg

__all__ = ["DESCRIPTION_SUFFIXES", "check_description_settings", "description_scene",
           "is_description", "is_system_file", "load_any_system", "parse_any_system",
           "parse_model_scene"]

DESCRIPTION_SUFFIXES = (".urdf", ".sdf", ".xml", ".xacro")
STANDARD_GRAVITY = (0.0, 0.0, -9.81)
_SCENE_KEYS = {"package_path": "the scene key package_path:",
               "xacro_arg": "an entry of the scene key xacro_args:"}
"""How a `model:` scene says the settings a description's messages name (`setting_ref`)."""


def is_description(path: str | os.PathLike) -> bool:
    """True for a file ``simulate`` runs as a robot description (by its name)."""
    return Path(path).suffix.lower() in DESCRIPTION_SUFFIXES


def is_system_file(path: str | os.PathLike) -> bool:
    """True for a file the systems package runs: a robot description (by its name) or a scene
    with ``bodies:`` or ``model:``. False too when the file cannot be read: the one-body reader
    then says why, in one line."""
    if is_description(path):
        return True
    try:
        return is_system_text(scene_text(path))
    except SceneError:
        return False


def check_description_settings(path: str | os.PathLike, package_paths: Sequence = (),
                               xacro_args: Mapping | None = None) -> None:
    """UsageError unless ``path`` is a robot description or neither setting is given: a scene
    file names its own (a `model:` scene's keys package_path and xacro_args)."""
    given = [name for name, value in (("package_path", package_paths),
                                      ("xacro_arg", xacro_args)) if value]
    if given and not is_description(path):
        raise UsageError(f"{path}: {' and '.join(setting_ref(n) for n in given)} "
                         f"appl{'y' if len(given) > 1 else 'ies'} to a robot description given "
                         "directly; a scene with model: names its own (the keys package_path "
                         "and xacro_args)")


def load_any_system(path: str | os.PathLike, duration: float | None = None, *,
                    package_paths: Sequence[str | os.PathLike] = (),
                    xacro_args: Mapping[str, str] | None = None) -> SystemScene:
    """A system scene file (``bodies:`` or ``model:``) or a robot description
    (`description_scene`, with ``package_paths`` and ``xacro_args``), with its duration set to
    ``duration`` s where given (a description's default: 1 s). SceneError / RobotModelError,
    one line; UsageError for package_paths or xacro_args with a scene file (a `model:` scene
    names its own: package_path, xacro_args)."""
    if is_description(path):
        return description_scene(path, duration=1.0 if duration is None else duration,
                                 package_paths=package_paths, xacro_args=xacro_args)
    check_description_settings(path, package_paths, xacro_args)
    path = Path(path)
    scene = parse_any_system(scene_text(path), source=os.fspath(path), base_dir=path.parent)
    return scene if duration is None else with_time(scene, duration=duration)


def parse_any_system(text: str, *, source: str, base_dir: Path) -> SystemScene:
    """A system scene's text, ``bodies:`` or ``model:`` (SceneError, RobotModelError)."""
    if any(line.startswith("model:") for line in text.splitlines()):
        return parse_model_scene(text, source=source, base_dir=base_dir)
    return parse_system(text, source=source, base_dir=base_dir)


def parse_model_scene(text: str, *, source: str, base_dir: Path) -> SystemScene:
    """A scene with ``model:`` (see the module doc). Raises SceneError, RobotModelError."""
    root = compose(text, source)
    fields = read_top(Field(root, "", source), "model",
                      {"model": "model: arm.urdf", "time": "time: {duration: 2.0}"})
    file = base_dir / read_string(fields["model"], "a URDF, SDF or MJCF file name")
    problem = file_problem(file)
    if problem is not None:
        raise fields["model"].error(f"{file} {problem} (relative paths start at the scene "
                                    "file's folder)")
    inertials = (read_choice(fields["inertials"], INERTIALS, "inertials")
                 if "inertials" in fields else "stated")
    base = read_choice(fields["base"], BASES, "base") if "base" in fields else None
    folders = ([base_dir / p for _, p in read_strings(fields["package_path"], "a folder")]
               if "package_path" in fields else [])
    arguments = _xacro_args(fields.get("xacro_args"))
    try:
        desc = describe(file, inertials=inertials, base=base, package_paths=folders,
                        xacro_args=arguments)
    except InputError as exc:  # the description's own line, its fix said as scene keys
        raise _with_place(exc, fields["model"], lambda n: _SCENE_KEYS.get(n, n)) from exc
    index = {b.name: i for i, b in enumerate(desc.bodies)}
    places: dict[str, str] = {}
    gravity, forces, springs, drags = _forces(fields.get("forces"), index)
    notes = []
    if not _names_gravity(fields.get("forces")):  # the description's own, as simulate ROBOT
        gravity = np.array(STANDARD_GRAVITY) if desc.gravity is None else desc.gravity
        notes.append(f"{source}: forces: names no gravity: the description's applies, "
                     f"g = {[float(x) for x in gravity]} m/s² (a gravity entry with g: [0, 0, "
                     "0] turns it off)")
    initial = _initial(fields.get("initial"), index, {j.name for j in desc.joints}, places)
    time = system_time(fields["time"])
    output = _output(fields.get("output"), base_dir)
    scene = _scene(desc, gravity, forces, springs, initial, time, output, source, places, drags)
    return dataclasses.replace(scene, notes=(*scene.notes, *notes)) if notes else scene


def _names_gravity(field: Field | None) -> bool:
    """Whether the scene's ``forces:`` list has a gravity entry (read and checked by
    `systems.scene._forces`; here only looked at)."""
    if field is None or not isinstance(field.node, yaml.SequenceNode):
        return False
    return any(isinstance(item, yaml.MappingNode) and any(
        k.value == "type" and getattr(v, "value", None) == "gravity" for k, v in item.value)
        for item in field.node.value)


def _xacro_args(field: Field | None) -> dict[str, str]:
    """``xacro_args``: NAME:=VALUE strings, one or a list, as ``--xacro-arg`` takes them."""
    out: dict[str, str] = {}
    for item, text in ([] if field is None else read_strings(field, "NAME:=VALUE")):
        try:
            name, value = parse_xacro_arg(text)
        except ValueError as exc:
            raise item.error(str(exc)) from exc
        out[name] = value
    return out


def description_scene(path: str | os.PathLike, *, duration: float = 1.0,
                      package_paths: Sequence[str | os.PathLike] = (),
                      xacro_args: Mapping[str, str] | None = None,
                      inertials: str = "stated") -> SystemScene:
    """``massprops simulate ROBOT``: the description with its stated inertials (``inertials``
    "computed": from the geometry, as ``massprops model`` computes them), its own base, the
    standard gravity (or MJCF's ``<option gravity>``), from the zero pose at rest, for
    ``duration`` s (0: the start pose only); ``package_paths`` and ``xacro_args`` as for
    ``massprops model``."""
    desc = describe(path, inertials=inertials, package_paths=package_paths,
                    xacro_args=xacro_args)
    gravity = np.array(STANDARD_GRAVITY) if desc.gravity is None else desc.gravity
    return _scene(desc, gravity, (), (), SystemInitial(), TimeSettings(float(duration)),
                  OutputSettings(), os.fspath(path), {})


def _leaders_kept(desc: Description, positions: dict) -> dict:
    """``positions`` with each coupling's leaders named at their given (else zero) coordinate,
    where the scene names none of the coupling's joints and no coupling makes them follow:
    the start's projection then moves only the followers."""
    out = dict(positions)
    followers = {desc.joints[c.terms[0][0]].name for c in desc.couplings}
    for c in desc.couplings:
        names = [desc.joints[k].name for k, _ in c.terms]
        if not any(n in positions for n in names):
            out.update({n: (0.0,) for n in names[1:] if n not in followers})
    return out


def _scene(desc: Description, gravity, forces, springs, initial, time, output, source: str,
           places: dict, drags=()) -> SystemScene:
    if not desc.bodies:
        raise SceneError(f"{desc.path}: every link is welded to the world: nothing moves "
                         "(base: floating frees the base)")
    gravity = np.array(gravity, float)
    gravity.setflags(write=False)
    if desc.couplings:  # a coupling's offset breaks the zero pose: its follower moves to it
        initial = dataclasses.replace(initial, project=True,
                                      positions=_leaders_kept(desc, initial.positions))
    scene = SystemScene(desc.bodies, desc.joints, gravity, tuple(forces), tuple(springs),
                        initial, time, output, source=source, input_files=(desc.path,),
                        warnings=desc.warnings, places=places, robot=os.fspath(desc.path),
                        couplings=desc.couplings, drags=tuple(drags))
    check_mass_matrix(scene)
    return scene
