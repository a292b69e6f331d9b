"""Shared test helpers: the CLI runner and small meshes written as text (no writer involved)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from massprops.cli import cli

ROOT = Path(__file__).resolve().parent.parent
SAMPLES = ROOT / "sample_meshes"

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


def program_for(forces, rigid=None):
    """The compiled force program of ``forces`` acting on ``rigid`` (default `body()`)."""
    from massprops.dynamics.forces import compile_forces
    from massprops.dynamics.model import InitialState, OutputSettings, Scene, TimeSettings

    scene = Scene(rigid or body(), InitialState(), tuple(forces), TimeSettings(1.0),
                  OutputSettings())
    return compile_forces(scene)


def state(r=(0, 0, 0), v=(0, 0, 0), q=(1, 0, 0, 0), w=(0, 0, 0)) -> np.ndarray:
    """(13,) [r, v, q principal->world, omega principal]."""
    return np.concatenate([r, v, q, w]).astype(np.float64)
