"""One sample of a sweep: its values drawn, its scene built, run, and its outputs read.

Sample i's generator is ``numpy.random.default_rng([seed, i])``: its draws depend on the seed
and i alone, so any number of workers, in any order, give the same rows. The scene's own values
(``forces[0].stiffness``) are written into its document, which is then read as the file would
be; a body's mass properties (``body.mass``, ``bodies.upper.inertia``) are changed on the body
read, as `inertials` says (for a robot's links too, which no scene text holds).

A body's centre of mass (``body.center_of_mass[i]``, ``bodies.NAME.center_of_mass[i]``, or
``--bars``) moves within the body, the body itself staying where it is: its frame, its joints'
points and every body point keep their places and velocities at t = 0, so the COM's start moves
with it (x' = x + R0 δ, v' = v + ω × R0 δ for a shift δ in body axes, R0 the body's turn at
t = 0). A one-body scene's joint written without a point (at the centre of mass) keeps the
nominal centre as its point; a force written without one stays at the (moved) centre of mass.
A system body's centre in its body frame is its mesh's centre of mass in the mesh frame (an
explicit body or a robot link: 0, its frame's origin being its centre of mass at ``position``).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import os
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import yaml

from massprops.dynamics import any_scene
from massprops.dynamics.yamlnodes import compose
from massprops.errors import MassPropsError, SceneError, UsageError, error_message
from massprops.rotation import quat_to_matrix
from massprops.sweep import keys
from massprops.sweep.inertials import (
    MASS_KEYS,
    Bars,
    MassChange,
    draw_valid,
    prefix,
    shape_bounds,
)
from massprops.sweep.specs import Spec


@dataclass(frozen=True)
class Vary:
    """One ``--vary KEY=SPEC``: its path's steps and, for a body's mass or inertia, which."""

    key: str
    steps: tuple[keys.Step, ...]
    spec: Spec
    mass: MassChange | None = None


@dataclass(frozen=True)
class Plan:
    """Everything a worker needs to run any sample (picklable, hashable: a worker reads the
    scene once per plan). ``text`` is the scene file's (None: a robot description, read from
    ``path``); ``grid`` the grid keys' combinations, each run ``draws`` times (sample i is
    combination i // draws); ``options`` the run's keyword arguments for `any_scene.simulate`."""

    path: str
    text: str | None
    varies: tuple[Vary, ...]
    seed: int
    draws: int
    grid: tuple[tuple[float, ...], ...]
    outputs: tuple[str, ...]
    options: tuple[tuple[str, Any], ...] = ()
    description: tuple[tuple[str, Any], ...] = ()
    folder: str = "."
    """The scene file's folder, absolute: where its relative paths start, for a worker in any
    directory (a Dask worker's is its own)."""
    series_every: float | None = None
    """Where set, each run is sampled every this many seconds and its rows carry each output's
    values over time (``Row.series``, for ``--plot``)."""
    bars: float | None = None
    """``--bars-scale`` K where ``--bars`` is given (every mesh body drawn within K times
    inspect's bars, `inertials.Bars`), else None."""
    bar_bodies: tuple[str | None, ...] = ()
    """The bodies ``--bars`` draws (None: a ``body:`` scene's one), found by `check_plan`."""

    @property
    def count(self) -> int:
        return len(self.grid) * self.draws

    @property
    def grid_keys(self) -> tuple[Vary, ...]:
        return tuple(v for v in self.varies if v.spec.is_grid)

    @property
    def value_keys(self) -> tuple[tuple[str, str], ...]:
        """Every key a row's ``values`` holds, in column order, with its shape: "scalar",
        "vector" (a ``--bars`` centre of mass, (3,) m body frame) or "tensor" (an inertia,
        (3, 3) kg·m² about the COM, body axes)."""
        out = [(v.key, "tensor" if v.mass is not None and v.mass.what == "inertia"
                else "scalar") for v in self.varies]
        for body in self.bar_bodies:
            out += [(f"{prefix(body)}.mass", "scalar"),
                    (f"{prefix(body)}.center_of_mass", "vector"),
                    (f"{prefix(body)}.inertia", "tensor")]
        return tuple(out)


@dataclass
class Row:
    """One sample's result: the contract's row (`as_dict`) and the mass-property redraws."""

    sample: int
    values: dict[str, Any]
    status: str = "ok"
    error: str | None = None
    outputs: dict[str, Any] | None = None
    error_estimate: float | None = None
    wall_time_s: float = 0.0
    redrawn: int = field(default=0)
    times: list[float] | None = None
    series: dict[str, list] | None = None  # output -> its value at each of ``times``

    def as_dict(self) -> dict[str, Any]:
        return {"sample": self.sample, "values": self.values, "status": self.status,
                "error": self.error, "outputs": self.outputs,
                "error_estimate": self.error_estimate, "wall_time_s": self.wall_time_s}


def mass_change(key: str, steps: tuple[keys.Step, ...]) -> MassChange | None:
    """The body and quantity of a mass-property key (``body.mass``, ``bodies.NAME.inertia``,
    ``body.center_of_mass[2]``), else None; UsageError for a centre of mass without a valid
    component."""
    if len(steps) >= 2 and steps[0] == "body" and steps[1] in MASS_KEYS:
        body, rest = None, steps[1:]
    elif len(steps) >= 3 and steps[0] == "bodies" and isinstance(steps[1], str) \
            and steps[2] in MASS_KEYS:
        body, rest = steps[1], steps[2:]
    else:
        return None
    if rest[0] != "center_of_mass":
        return MassChange(key, body, str(rest[0])) if len(rest) == 1 else None
    if len(rest) != 2 or not isinstance(rest[1], int) or rest[1] > 2:
        raise UsageError(f"--vary {key}: a centre of mass varies by component, "
                         f"{keys.show_path(steps[:len(steps) - len(rest) + 1])}[i] with i "
                         "0, 1 or 2 (body axes, m)")
    return MassChange(key, body, "center_of_mass", rest[1])


# --- a worker's copy of the scene -------------------------------------------------------------
@dataclass(frozen=True)
class _Nominal:
    scene: Any
    bounds: dict  # body (None: the one) -> its mesh's shape (`inertials.shape_bounds`)
    bars: dict  # body -> its `inertials.Bars` (``--bars``)


def load(plan: Plan) -> Any:
    """The scene as written (no value varied)."""
    if plan.text is None:
        opts = dict(plan.description)
        here = plan.path if os.path.exists(plan.path) else os.path.join(  # a worker elsewhere
            plan.folder, os.path.basename(plan.path))
        return any_scene.load(here, opts.get("duration"),
                              package_paths=opts.get("package_paths", ()),
                              xacro_args=opts.get("xacro_args"))
    return any_scene.parse(plan.text, source=plan.path, base_dir=plan.folder)


def mesh_bodies(scene: Any) -> dict[str | None, tuple[Any, np.ndarray]]:
    """The scene's mesh bodies: body (None: a ``body:`` scene's) -> (its `MeshSource`, its
    inertia (3, 3) kg·m² about the COM, body axes = mesh axes)."""
    if any_scene.is_system(scene):
        return {b.name: (b.mesh, b.inertia) for b in scene.bodies if b.mesh is not None}
    body = scene.body
    return {None: (body.mesh, body.inertia_body)} if body.mesh is not None else {}


@functools.lru_cache(maxsize=2)
def _nominal(plan: Plan) -> _Nominal:
    scene = load(plan)
    meshes = mesh_bodies(scene)
    varied = {v.mass.body for v in plan.varies if v.mass is not None} | set(plan.bar_bodies)
    bounds = {body: shape_bounds(source.path, source.unit)
              for body, (source, _) in meshes.items() if body in varied}
    bars = {body: Bars.of(meshes[body][0], meshes[body][1], plan.bars)
            for body in plan.bar_bodies if plan.bars is not None}
    return _Nominal(scene, bounds, bars)


# --- one sample -------------------------------------------------------------------------------
def run_sample(plan: Plan, index: int) -> Row:
    """Sample ``index`` (0 <= index < plan.count): a failed one is a row with its error."""
    start = time.perf_counter()
    rng = np.random.default_rng([plan.seed, index])
    row = Row(index, {})
    try:
        scene, row.redrawn = _scene(plan, grid_values(plan, index), rng, row.values)
        options = dict(plan.options)
        if plan.series_every is not None:
            options["every"] = plan.series_every
        result = any_scene.simulate(scene, **options)
        found = result.as_dict()
        row.outputs = {name: _number(keys.read_output(found, keys.parse_path(name)))
                       for name in plan.outputs}
        row.error_estimate = found["diagnostics"].get("error_estimate")
        if plan.series_every is not None:
            row.times, row.series = _series(result, plan.outputs)
    except (MassPropsError, KeyError) as exc:
        row.status, row.error = "failed", error_message(exc) if isinstance(
            exc, MassPropsError) else f"output {exc} missing from this run"
    row.wall_time_s = time.perf_counter() - start
    return row


def _series(result: Any, outputs: tuple[str, ...]) -> tuple[list[float], dict[str, list]]:
    """The run's sample times and each output's value at them (a ``final.`` output read from
    each sample's state; any other output, e.g. a diagnostic, has its one value)."""
    states = [result.row(n) for n in range(any_scene.sample_count(result))]
    series = {}
    for name in outputs:
        steps = keys.parse_path(name)
        if steps[0] == "final":
            series[name] = [_number(keys.read_output(state, steps[1:])) for state in states]
    return [state["t"] for state in states], series


def run_chunk(plan: Plan, indices: list[int]) -> list[Row]:
    """Samples ``indices`` in order (a worker's task)."""
    return [run_sample(plan, i) for i in indices]


def _number(value: Any) -> Any:
    """A JSON-ready output: floats stay, non-finite become None (a run that ran away)."""
    if isinstance(value, list):
        return [_number(v) for v in value]
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def scene_value(plan: Plan, vary: Vary) -> float | None:
    """The value the scene writes at ``vary``'s key (a body's mass as read), None for an
    inertia tensor."""
    if vary.mass is not None:
        if vary.mass.what == "inertia":
            return None
        scene = _nominal(plan).scene
        body = scene.body if vary.mass.body is None else next(
            b for b in scene.bodies if b.name == vary.mass.body)
        if vary.mass.what == "mass":
            return float(body.mass)
        return float(_body_com(body)[vary.mass.axis])
    root = compose(plan.text or "", plan.path)
    assert root is not None
    return keys.value_at(keys.find(root, vary.steps, plan.path))


def grid_values(plan: Plan, index: int) -> dict[str, float]:
    """The grid keys' values of sample ``index`` (its design point)."""
    return dict(zip((v.key for v in plan.grid_keys), plan.grid[index // plan.draws]))


def run_at(plan: Plan, values: dict[str, float]) -> Row:
    """The scene run with every key at ``values`` (nothing drawn): `linear`'s runs."""
    start = time.perf_counter()
    row = Row(-1, {})
    scene, _ = _scene(plan, values, np.random.default_rng(0), row.values, bars=False)
    found = any_scene.simulate(scene, **dict(plan.options)).as_dict()
    row.outputs = {name: keys.read_output(found, keys.parse_path(name)) for name in plan.outputs}
    row.error_estimate = found["diagnostics"].get("error_estimate")
    row.wall_time_s = time.perf_counter() - start
    return row


def _scene(plan: Plan, fixed: dict[str, float], rng: np.random.Generator,
           said: dict, bars: bool = True) -> tuple[Any, int]:
    """The scene with the keys in ``fixed`` at those values and the others drawn (``bars``:
    ``--bars`` too, else its bodies as written), and its mass-property redraws; every key's
    value into ``said``."""
    nominal = _nominal(plan)
    text_varies = [v for v in plan.varies if v.mass is None]
    scene = nominal.scene
    if text_varies:
        scene = _rewritten(plan, text_varies, fixed, rng, said)
    changes: dict[str | None, list] = {}
    for v in plan.varies:
        if v.mass is not None:
            changes.setdefault(v.mass.body, []).append(
                (v.mass, _GridValue(fixed[v.key]) if v.key in fixed else v.spec))
    for body in plan.bar_bodies if bars else ():
        changes.setdefault(body, []).append(
            (MassChange(prefix(body), body, "bars"), nominal.bars[body]))
    redrawn = 0
    for body, body_changes in changes.items():
        scene, n = _with_body(scene, body, body_changes, rng, nominal.bounds.get(body), said)
        redrawn += n
    return scene, redrawn


@dataclass(frozen=True)
class _GridValue:
    """A given value where a Spec is drawn (the mass of a grid over masses)."""

    value: float

    def draw(self, rng: np.random.Generator, nominal: float) -> float:
        return self.value


def _rewritten(plan: Plan, varies: list[Vary], fixed: dict, rng, said: dict) -> Any:
    root = compose(plan.text or "", plan.path)
    assert root is not None
    for v in varies:
        place = keys.find(root, v.steps, plan.path)
        value = fixed[v.key] if v.key in fixed else v.spec.draw(rng, keys.value_at(place))
        keys.set_value(place, value)
        said[v.key] = value
    text = yaml.serialize(root)
    return any_scene.parse(text, source=f"{plan.path} (sample values)",
                           base_dir=plan.folder)


def _body_com(body: Any) -> np.ndarray:
    """A body's centre of mass (3,) m in its body frame (the module's rule)."""
    if hasattr(body, "center_of_mass"):  # a one-body scene's RigidBody
        return np.asarray(body.center_of_mass, dtype=np.float64)
    return np.array(body.mesh.center_of_mass if body.mesh is not None else np.zeros(3),
                    dtype=np.float64)


def _moved_start(scene: Any, com: np.ndarray, shift: np.ndarray) -> Any:
    """The one-body ``scene`` whose centre of mass moved by ``shift`` (3,) m, body axes, from
    ``com``: its start and its point-less joints as the module says."""
    ini = scene.initial
    turn = quat_to_matrix(np.asarray(ini.orientation, dtype=np.float64))
    moved = turn @ shift
    omega = np.asarray(ini.angular_velocity, dtype=np.float64)
    if ini.angular_velocity_frame == "body":
        omega = turn @ omega
    initial = dataclasses.replace(ini, position=np.asarray(ini.position) + moved,
                                  velocity=np.asarray(ini.velocity) + np.cross(omega, moved))
    joints = tuple(dataclasses.replace(j, point=com.copy()) if j.point is None else j
                   for j in scene.joints)
    return dataclasses.replace(scene, initial=initial, joints=joints)


def _with_body(scene: Any, body: str | None, changes, rng, bounds, said: dict) -> tuple[Any, int]:
    """``scene`` with one body's mass properties drawn (`inertials.draw_valid`)."""
    if body is None:
        rigid = scene.body
        com = _body_com(rigid)
        m, j, c, values, n = draw_valid(rng, changes, rigid.mass, rigid.inertia_body, com,
                                        bounds)
        said.update(values)
        new = type(rigid).from_inertia(m, j, c, size=rigid.size)
        scene = dataclasses.replace(scene, body=new)
        if np.any(c != com):
            scene = _moved_start(scene, com, c - com)
        return scene, n
    names = [b.name for b in scene.bodies] if any_scene.is_system(scene) else []
    if body not in names:
        raise SceneError(f"{scene.source}: sweep key bodies.{body}: the scene has no body "
                         f"{body!r}" + (f" (its bodies: {', '.join(names)})" if names else ""))
    k = names.index(body)
    b = scene.bodies[k]
    com = _body_com(b)
    m, j, c, values, n = draw_valid(rng, changes, b.mass, b.inertia, com, bounds)
    said.update(values)
    moved = np.asarray(b.rotation0, dtype=np.float64) @ (c - com)
    bodies = list(scene.bodies)
    bodies[k] = dataclasses.replace(b, mass=m, inertia=j, com0=np.asarray(b.com0) + moved)
    initial = scene.initial
    if body in initial.velocities:  # a floating body: its points keep their velocities
        v, w = initial.velocities[body]
        initial = dataclasses.replace(initial, velocities={
            **initial.velocities, body: (np.asarray(v) + np.cross(w, moved), w)})
    return dataclasses.replace(scene, bodies=tuple(bodies), initial=initial), n


def check_plan(plan: Plan) -> Any:
    """The scene read and every key found, before any sample runs: SceneError (exit 1) for a
    scene or key that is not there, UsageError (exit 2) for a spec a key cannot take. Returns
    the scene as written."""
    nominal = _nominal(plan).scene
    text_varies = [v for v in plan.varies if v.mass is None]
    if text_varies and plan.text is None:
        raise SceneError(f"{plan.path}: a robot description's own values cannot be varied by "
                         f"key ({text_varies[0].key}); vary its links' mass or inertia "
                         "(bodies.LINK.mass, bodies.LINK.inertia), or write a model: scene")
    if text_varies:
        root = compose(plan.text or "", plan.path)
        for v in text_varies:
            keys.find(root, v.steps, plan.path)
    for v in plan.varies:
        if v.mass is None:
            continue
        if v.mass.what == "inertia" and v.spec.kind != "relative":
            raise UsageError(f"--vary {v.key}: an inertia tensor varies by relative:P only")
        if v.mass.body is None and any_scene.is_system(nominal):
            raise SceneError(f"{plan.path}: sweep key {v.key}: a system's bodies are "
                             "bodies.NAME")
        if v.mass.body is not None:
            _with_body(nominal, v.mass.body, [], None, None, {})  # names the missing body
    return nominal


def bar_bodies(plan: Plan, scene: Any) -> tuple[str | None, ...]:
    """The bodies ``--bars`` draws: every mesh body of ``scene`` (the plan's, as written);
    UsageError (exit 2) when it has none or a --vary varies one of theirs too."""
    found = tuple(mesh_bodies(scene))
    if not found:
        raise UsageError(f"--bars: {plan.path} has no mesh body (its mass properties are "
                         "given, without inspect's error bars); vary them with --vary "
                         "bodies.NAME.mass=... instead")
    for v in plan.varies:
        if v.mass is not None and v.mass.body in found:
            raise UsageError(f"--bars draws {prefix(v.mass.body)}'s mass properties; --vary "
                             f"{v.key} would draw them twice: give one")
    return found
