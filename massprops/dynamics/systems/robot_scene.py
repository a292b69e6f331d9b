"""System scenes that name a robot description (``model:``), and the description run alone.

The scene (contract, "simulate a robot description"):

    model: arm.urdf            # URDF, SDF or MJCF; relative to the scene file's folder
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
from pathlib import Path

import numpy as np

from massprops.dynamics.model import OutputSettings, TimeSettings
from massprops.dynamics.scene import _output, read_top
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
    parse_system,
    system_time,
    with_time,
)
from massprops.dynamics.yamlnodes import Field, compose, read_choice, read_string
from massprops.errors import SceneError

__all__ = ["DESCRIPTION_SUFFIXES", "description_scene", "is_description", "load_any_system",
           "parse_model_scene"]

DESCRIPTION_SUFFIXES = (".urdf", ".sdf", ".xml", ".xacro")
STANDARD_GRAVITY = (0.0, 0.0, -9.81)


def is_description(path: str | os.PathLike) -> bool:
    """True for a file ``simulate`` runs as a robot description (by its name)."""
    return Path(path).suffix.lower() in DESCRIPTION_SUFFIXES


def load_any_system(path: str | os.PathLike, duration: float | None = None) -> SystemScene:
    """A system scene file (``bodies:`` or ``model:``) or a robot description
    (`description_scene`), with its duration set to ``duration`` s where given (a
    description's default: 1 s). SceneError / RobotModelError, one line."""
    if is_description(path):
        return description_scene(path, duration=1.0 if duration is None else duration)
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise SceneError(f"{path}: cannot read the scene file: {exc.strerror}") from exc
    if any(line.startswith("model:") for line in text.splitlines()):
        scene = parse_model_scene(text, source=os.fspath(path), base_dir=path.parent)
    else:
        scene = parse_system(text, source=os.fspath(path), base_dir=path.parent)
    return scene if duration is None else with_time(scene, duration=duration)


def parse_model_scene(text: str, *, source: str, base_dir: Path) -> SystemScene:
    """A scene with ``model:`` (see the module doc). Raises SceneError, RobotModelError."""
    root = compose(text, source)
    fields = read_top(Field(root, "", source), "model",
                      {"model": "model: arm.urdf", "time": "time: {duration: 2.0}"})
    file = base_dir / read_string(fields["model"], "a URDF, SDF or MJCF file name")
    if not file.is_file():
        raise fields["model"].error(f"no such file {file} (relative paths start at the scene "
                                    "file's folder)")
    inertials = (read_choice(fields["inertials"], INERTIALS, "inertials")
                 if "inertials" in fields else "stated")
    base = read_choice(fields["base"], BASES, "base") if "base" in fields else None
    desc = describe(file, inertials=inertials, base=base)
    index = {b.name: i for i, b in enumerate(desc.bodies)}
    places: dict[str, str] = {}
    gravity, forces, springs, drags = _forces(fields.get("forces"), index)
    initial = _initial(fields.get("initial"), index, {j.name for j in desc.joints}, places)
    time = system_time(fields["time"])
    output = _output(fields.get("output"), base_dir)
    return _scene(desc, gravity, forces, springs, initial, time, output, source, places, drags)


def description_scene(path: str | os.PathLike, *, duration: float = 1.0) -> SystemScene:
    """``massprops simulate ROBOT``: the description with stated inertials, its own base, the
    standard gravity (or MJCF's ``<option gravity>``), from the zero pose at rest, for
    ``duration`` s (0: the start pose only)."""
    desc = describe(path)
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
