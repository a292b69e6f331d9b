"""Shared test helpers: the CLI runner and small meshes written as text (no writer involved)."""

from __future__ import annotations

import json
import math
import os
import time
from fractions import Fraction
from pathlib import Path
from typing import NamedTuple

import numpy as np
import pytest
from click.testing import CliRunner

from massprops.cli import cli

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = ROOT / "sample_meshes"

KERNELS_TIMEOUT_S = 1800
"""The most the suite's start waits for the kernels (~2 min of two idle cores to compile)."""


def pytest_configure(config):
    """Before any test (and before xdist starts its workers), load or compile every dynamics
    kernel of this checkout into the kernels' cache, so that no test's time limit ever includes
    a compile, whatever the machine's load. A cached kernel loads in seconds; the suite's workers
    then load them too (the cache is shared by every copy of the same sources: compiled.cache)."""
    if hasattr(config, "workerinput") or config.option.collectonly or config.option.help:
        return
    from massprops.dynamics.compiled.compiling import ready_side_by_side

    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        p for p in (str(ROOT), os.environ.get("PYTHONPATH")) if p))
    start = time.perf_counter()
    compiled = ready_side_by_side(jobs=2, timeout=KERNELS_TIMEOUT_S, env=env)
    if compiled:
        print(f"massprops: compiled {compiled} kernel functions once for this checkout in "
              f"{time.perf_counter() - start:.0f} s, before the tests (later runs load them)")


# Unit cube [0,1]³: corners indexed x + 2y + 4z, quads counter-clockwise from outside.
CUBE_VERTS = [[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)]
CUBE_QUADS = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]


def vf_text(verts, faces) -> str:
    """A mesh in the native .vf format (1-based, as CONTRACT.md describes it)."""
    lines = [str(len(verts))] + [" ".join(repr(float(c)) for c in v) for v in verts]
    lines += [str(len(faces))] + [" ".join(str(i + 1) for i in f) for f in faces]
    return "\n".join(lines) + "\n"


def box_vf(path: Path, size=(1.0, 1.0, 1.0), offset=(0.0, 0.0, 0.0), faces=None) -> Path:
    verts = (np.array(CUBE_VERTS, float) * size + offset).tolist()
    path.write_text(vf_text(verts, CUBE_QUADS if faces is None else faces))
    return path


def rot_z(deg: float) -> np.ndarray:
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@pytest.fixture
def run():
    """run(*args, input=None) -> click Result with .exit_code, .stdout, .stderr."""
    runner = CliRunner()

    def _run(*args, input=None):
        return runner.invoke(cli, [str(a) for a in args], input=input, catch_exceptions=False)

    return _run


def json_lines(text: str) -> list[dict]:
    return [json.loads(line) for line in text.splitlines() if line.strip()]


# --- dynamics test helpers (integrator and splitting tests) ------------------------------------
def body(moments=(1.0, 2.0, 3.0), mass=2.0):
    """A body whose principal axes are its body axes (principal frame = body frame, COM origin)."""
    from massprops.dynamics.model import RigidBody

    return RigidBody(float(mass), np.array(moments, float), np.eye(3), np.zeros(3), 1.0)


_SCENES: dict[int, tuple] = {}
"""id(program) -> (program, its scene) of every `program_for`: `integrate` runs the scene on the
systems engine (the program is kept so that its id is not reused)."""


def program_for(forces, rigid=None):
    """The compiled force program of ``forces`` acting on ``rigid`` (default `body()`)."""
    from massprops.dynamics.model import InitialState, OutputSettings, Scene, TimeSettings
    from massprops.dynamics.program import compile_forces

    scene = Scene(rigid or body(), InitialState(), tuple(forces), TimeSettings(1.0),
                  OutputSettings())
    program = compile_forces(scene)
    _SCENES[id(program)] = (program, scene)
    return program


def scene_of(program):
    """The scene `program_for` made ``program`` of."""
    return _SCENES[id(program)][1]


def state(r=(0, 0, 0), v=(0, 0, 0), q=(1, 0, 0, 0), w=(0, 0, 0)) -> np.ndarray:
    """(13,) [r, v, q principal->world, omega principal]."""
    return np.concatenate([r, v, q, w]).astype(np.float64)


class Run(NamedTuple):
    """What `integrate` returns: the final state, the dense output, stats, the summed kernel err,
    and the time reached."""

    y: np.ndarray
    y_out: np.ndarray
    stats: np.ndarray
    err: float
    t_reached: float


def integrate(name, program, y0, duration, setting, t_out=(), rot_only=False) -> Run:
    """Walk [0, duration] segment by segment, split at the force windows' edges, as simulate
    does: a one-body kernel's registry entry ``name`` called directly, a time-stepping method
    on the systems engine's step loop (`_on_the_engine`), no simulate machinery in between.
    States are the principal-frame [r, v, q, ω] (``rot_only``: [q, ω]) of `state`."""
    from massprops.dynamics.integrators import INTEGRATORS, SYSTEM_METHODS
    from massprops.dynamics.integrators.base import STATUS

    t_out = np.asarray(t_out, dtype=np.float64)
    if name in SYSTEM_METHODS:
        return _on_the_engine(name, program, y0, duration, setting, t_out, rot_only)
    spec = INTEGRATORS[name]
    y = y0.copy()
    y_out = np.full((t_out.size, y.size), np.nan)
    stats = np.zeros(5, dtype=np.int64)
    edges = [0.0, *program.breakpoints(0.0, duration).tolist(), duration]
    err, t_reached = 0.0, 0.0
    for t0, t1 in zip(edges[:-1], edges[1:]):
        sel = np.flatnonzero(((t_out >= t0) if t0 == 0 else (t_out > t0)) & (t_out <= t1))
        ys = np.empty((sel.size, y.size))
        arrays = (program.active(0.5 * (t0 + t1)), program.codes, program.params, program.mass,
                  program.inertia)
        e, t_reached = spec.run_segment(y, t0, t1, setting, arrays, rot_only, t_out[sel], ys,
                                        stats)
        y_out[sel] = ys
        err += e
        if stats[STATUS] or t_reached < t1:
            break
    return Run(y, y_out, stats, err, t_reached)


def _on_the_engine(name, program, y0, duration, setting, t_out, rot_only) -> Run:
    """`integrate` for a method of the systems engine: the program's scene from ``y0`` as the
    system of one body, stepped by `systems.integrate.integrate` (the loop `simulate` runs),
    its samples turned back into principal-frame states (the test bodies' principal axes are
    their body axes); a failed run ends at its last finite sample. ``err`` is 0 (the engine
    keeps no summed local estimate); stats are [steps, evaluations, rejected, 0, 1 if the run
    failed]."""
    import dataclasses

    from massprops.dynamics.model import InitialState, TimeSettings
    from massprops.dynamics.systems.integrate import integrate as step_loop
    from massprops.dynamics.systems.one_body import as_system
    from massprops.dynamics.systems.outputs import evaluate_states
    from massprops.dynamics.systems.run import error_floors, load_windows, prepare

    scene = scene_of(program)
    assert np.array_equal(scene.body.principal_axes, np.eye(3)), "principal axes = body axes"
    full = np.concatenate([np.zeros(6), y0]) if rot_only else np.asarray(y0, np.float64)
    initial = InitialState(full[0:3].copy(), full[6:10].copy(), full[3:6].copy(),
                           full[10:13].copy(), "body")
    scene = dataclasses.replace(scene, initial=initial, time=TimeSettings(float(duration)))
    system_scene = as_system(scene)
    system, y_start, _ = prepare(system_scene)
    times = np.unique(np.append(t_out, float(duration)))
    run = step_loop(system, y_start, times, float(setting), error_floors(system, duration),
                    load_windows(system_scene), method=name)

    def states(t, y):
        """(n, 13) principal-frame states of the engine's (n, ny) states at times t."""
        s = evaluate_states(system, t, y)
        q, w_world = s.orientation[:, 0], s.angular_velocity[:, 0]
        w_body = np.einsum("nji,nj->ni", rotation_matrices(q), w_world)
        return np.hstack([s.position[:, 0], s.velocity[:, 0], q, w_body])

    good = np.isfinite(run.y_out).all(axis=1)
    y_all = np.full((times.size, 13), np.nan)
    if good.any():
        y_all[good] = states(times[good], run.y_out[good])
    failed = run.failure is not None
    # a failed run: reached as far as its last finite sample (the engine's samples stop there)
    last = int(np.flatnonzero(good)[-1]) if good.any() else 0
    t_reached = float(times[last]) if failed else float(duration)
    y_end = y_all[last] if failed else y_all[-1]
    keep = slice(6, 13) if rot_only else slice(0, 13)
    rows = np.searchsorted(times, t_out)
    stats = np.array([run.steps, run.nfev, run.rejected, 0, int(failed)], dtype=np.int64)
    return Run(y_end[keep].copy(), y_all[rows][:, keep], stats, 0.0, t_reached)


def quat_axis_angle(axis, angle) -> np.ndarray:
    """[w, x, y, z] of a rotation by ``angle`` about ``axis`` (normalised here; textbook)."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    return np.concatenate([[math.cos(angle / 2)], math.sin(angle / 2) * axis])


def rotation_matrices(q: np.ndarray) -> np.ndarray:
    """(n, 3, 3) from (n, 4) unit quaternions [w, x, y, z] (textbook formula, written here)."""
    w, x, y, z = q.T
    return np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], -2)


# --- the exact oracle: every float is a rational, so the integral of a float mesh is exact -------


def _as_integers(vertices) -> tuple[list[list[int]], int]:
    """Coordinates as integers times 2**e (one e for all), exactly."""
    flat = [float(x) for x in np.asarray(vertices, dtype=np.float64).ravel()]
    e = min((math.frexp(x)[1] - 53 for x in flat if x != 0.0), default=0)
    ints = [int(Fraction(x) / Fraction(2) ** e) for x in flat]
    return [ints[i:i + 3] for i in range(0, len(ints), 3)], e


def exact_mass_properties(vertices, faces):
    """Volume, COM (3) and inertia about the COM (3x3) at unit density, as Fractions, from the
    signed tetrahedra (0, a, b, c) in integer arithmetic."""
    pts, e = _as_integers(vertices)
    s0, s1, s2 = 0, [0, 0, 0], [[0] * 3 for _ in range(3)]
    for i, j, k in np.asarray(faces).tolist():
        a, b, c = pts[i], pts[j], pts[k]
        d = (a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2])
             + a[2] * (b[0] * c[1] - b[1] * c[0]))
        s = [a[t] + b[t] + c[t] for t in range(3)]
        s0 += d
        for p in range(3):
            s1[p] += d * s[p]
            for q in range(3):
                s2[p][q] += d * (a[p] * a[q] + b[p] * b[q] + c[p] * c[q] + s[p] * s[q])
    unit = Fraction(2) ** e
    volume = Fraction(s0, 6) * unit**3
    com = [Fraction(x, 24) * unit**4 / volume for x in s1]
    central = [[Fraction(s2[p][q], 120) * unit**5 - volume * com[p] * com[q] for q in range(3)]
               for p in range(3)]
    trace = sum(central[p][p] for p in range(3))
    inertia = [[(trace if p == q else 0) - central[p][q] for q in range(3)] for p in range(3)]
    return volume, com, inertia


def said_by_cli(message) -> str:
    """A library error (or its message) as the command line says it: the settings it names
    (`massprops.errors.setting_ref`) as options."""
    from massprops.cli.common import cli_text

    return cli_text(getattr(message, "template", message))
