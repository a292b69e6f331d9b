"""System scenes: the bad inputs of issue 17 §6 are refused in one line naming file, line, key."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from massprops.dynamics.systems.run import prepare
from massprops.dynamics.systems.scene import is_system_text, parse_system
from massprops.errors import SceneError

ROD = "{mass: 1.0, inertia: [[0.0834, 0, 0], [0, 0.0834, 0], [0, 0, 0.001]], "
GOOD = f"""bodies:
  upper: {ROD}position: [0, 0, -0.5]}}
  lower: {ROD}position: [0, 0, -1.5]}}
joints:
  - {{name: shoulder, type: revolute, bodies: [world, upper], point: [0, 0, 0], axis: [0, 1, 0]}}
  - {{name: elbow, type: revolute, bodies: [upper, lower], point: [0, 0, -1], axis: [0, 1, 0]}}
time: {{duration: 1.0}}
"""


def _refused(text: str, tmp_path: Path) -> str:
    with pytest.raises(SceneError) as info:
        scene = parse_system(text, source="s.yaml", base_dir=tmp_path)
        prepare(scene)
    message = str(info.value)
    assert "\n" not in message and message.startswith("s.yaml:")
    return message


def test_good_scene_reads(tmp_path):
    scene = parse_system(GOOD, source="s.yaml", base_dir=tmp_path)
    assert [b.name for b in scene.bodies] == ["upper", "lower"]
    assert [j.name for j in scene.joints] == ["shoulder", "elbow"]
    assert is_system_text(GOOD) and not is_system_text("body: {mass: 1}\n")


@pytest.mark.parametrize("change, line, words", [
    (("bodies: [world, upper]", "bodies: [world, uper]"), 5, "unknown body 'uper'"),
    (("bodies: [upper, lower]", "bodies: [lower]"), 6, "two bodies"),
    (("position: [0, 0, -1.5]", "orientation: [1, 0, 0, 0]"), 3, "position"),
    (("axis: [0, 1, 0]}\n  - {name: elbow", "axis: [0, 0, 0]}\n  - {name: elbow"), 5,
     "zero-length axis"),
    (("name: elbow", "name: shoulder"), 6, "duplicate joint name"),
    (("{mass: 1.0", "{mass: -1.0"), 2, "positive"),
])
def test_refusals(tmp_path, change, line, words):
    text = GOOD.replace(*change, 1)
    message = _refused(text, tmp_path)
    assert message.startswith(f"s.yaml:{line}:") and words in message, message


def test_duplicate_body_refused(tmp_path):
    text = GOOD.replace("lower: {", "upper: {", 1)
    assert "duplicate body" in _refused(text, tmp_path)


FOUR_BAR = Path(__file__).resolve().parent.parent / "sample_scenes" / "four_bar.yaml"


def test_open_loop_refused_without_project(tmp_path):
    text = FOUR_BAR.read_text().replace("  project_initial: true\n", "")
    text = text.replace("rates: {A: 2.0}", "positions: {A: 0.2}")
    message = _refused(text, tmp_path)
    assert "open a closed loop" in message and "project_initial" in message
    assert "initial.positions.A" in message


def test_rate_on_fixed_joint_refused(tmp_path):
    text = GOOD.replace("type: revolute, bodies: [upper, lower], point: [0, 0, -1], "
                        "axis: [0, 1, 0]", "type: fixed, bodies: [upper, lower]")
    text = text.replace("time:", "initial: {rates: {elbow: 1.0}}\ntime:")
    message = _refused(text, tmp_path)
    assert "cannot move" in message and "initial.rates.elbow" in message


def test_cli_refusal_is_one_line_exit_1(tmp_path):
    path = tmp_path / "bad.yaml"
    path.write_text(GOOD.replace("bodies: [world, upper]", "bodies: [world, nobody]"))
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parent.parent)}
    done = subprocess.run([sys.executable, "-m", "massprops", "simulate", str(path), "--json"],
                          capture_output=True, text=True, env=env, timeout=60)
    assert done.returncode == 1
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "bad.yaml:5:" in lines[0] and "nobody" in lines[0]
    assert "Traceback" not in done.stderr


@pytest.mark.slow  # a fresh process: imports, the run and its error-estimate companion
def test_cli_json_contract(tmp_path):
    path = tmp_path / "dp.yaml"
    path.write_text(GOOD.replace("duration: 1.0", "duration: 0.2"))
    out = tmp_path / "traj.csv"
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).resolve().parent.parent)}
    done = subprocess.run([sys.executable, "-m", "massprops", "simulate", str(path), "--json",
                           "--output", str(out)], capture_output=True, text=True, env=env,
                          timeout=60)
    assert done.returncode == 0, done.stderr
    data = json.loads(done.stdout)
    assert set(data["final"]["bodies"]) == {"upper", "lower"}
    joint = data["final"]["joints"]["elbow"]
    assert set(joint) >= {"type", "bodies", "coordinates", "rates", "force", "torque"}
    assert joint["bodies"] == ["upper", "lower"]
    diag = data["diagnostics"]
    assert diag["degrees_of_freedom"] == 2 and diag["redundant_constraints"] == 0
    assert set(diag["constraint_residual"]) == {"position", "velocity"}
    assert diag["energy_rel_drift"] is not None and diag["error_estimate"] is not None
    header = out.read_text().splitlines()[0].split(",")
    assert header[:4] == ["t", "upper.x", "upper.y", "upper.z"]
    assert "elbow.q" in header and "elbow.u" in header and "elbow.tz" in header


# --- issue 30 -------------------------------------------------------------------------------
PENDULUM = f"""bodies:
  rod: {ROD}position: [0, 0, -0.5]}}
joints:
  - {{name: u, type: universal, bodies: [world, rod], point: [0, 0, 0], axes: AXES}}
forces: [{{type: gravity, g: [0, 0, -9.81]}}]
time: {{duration: 0.5}}
"""


@pytest.mark.parametrize("axes", ["[[1, 0, 0], [1, 0, 0]]", "[[1, 0, 0], [-2, 0, 0]]",
                                  "[[1, 0, 0], [1, 1.0e-7, 0]]"],
                         ids=["parallel", "anti-parallel", "1e-7-rad-apart"])
def test_a_universal_joint_with_parallel_axes_is_refused_at_its_key(tmp_path, axes):
    """Parallel axes make its two turns one: the joint's motion subspace loses a rank for good
    and its mass matrix is singular (the run ended in 'LinAlgError: Matrix is not positive
    definite', exit 3, no file named). Lines closer than 2e-6 rad (tan of half the angle
    within NEAR_SINGULAR_MARGIN) are refused as parallel."""
    message = _refused(PENDULUM.replace("AXES", axes), tmp_path)
    assert message.startswith("s.yaml:4: joints[0].axes:") and "parallel" in message


@pytest.mark.parametrize("axes", ["[[1, 0, 0], [1, 1.0e-5, 0]]", "[[1, 0, 0], [0, 1, 0]]",
                                  "[[1.0e300, 0, 0], [0, 0, 1.0e-200]]"],
                         ids=["1e-5-rad-apart", "perpendicular", "huge-and-tiny-lengths"])
def test_a_universal_joint_with_distinct_axes_reads(tmp_path, axes):
    scene = parse_system(PENDULUM.replace("AXES", axes), source="s.yaml", base_dir=tmp_path)
    a = scene.joints[0].axes
    assert np.linalg.norm(a, axis=1) == pytest.approx([1.0, 1.0], abs=1e-15)
    prepare(scene)


@pytest.mark.parametrize("axes, words", [("[[0, 0, 0], [0, 1, 0]]", "zero-length axis"),
                                         ("[[1, 0, 0]]", "two axes")])
def test_a_universal_joint_axis_of_no_direction_is_refused(tmp_path, axes, words):
    message = _refused(PENDULUM.replace("AXES", axes), tmp_path)
    assert message.startswith("s.yaml:4: joints[0].axes") and words in message


@pytest.mark.parametrize("command", ["simulate", "precision"])
def test_cli_parallel_universal_axes_exit_1_naming_the_file(tmp_path, run, command):
    path = tmp_path / "u.yaml"
    path.write_text(PENDULUM.replace("AXES", "[[1, 0, 0], [1, 0, 0]]"))
    res = run(command, str(path))
    assert res.exit_code == 1, res.stderr
    (line,) = res.stderr.strip().splitlines()
    assert "u.yaml:4: joints[0].axes" in line and "internal error" not in line


def test_an_empty_bodies_mapping_says_it_is_empty(tmp_path):
    message = _refused("bodies: {}\ntime: {duration: 1.0}\n", tmp_path)
    assert message.startswith("s.yaml:1: bodies:") and "empty" in message
    assert "got a mapping" not in message


@pytest.mark.parametrize("text, key", [
    (GOOD + "forcez: []\n", "forcez"),
    (GOOD.replace("bodies:", "model: arm.urdf\nbodies:", 1), "bodies"),
], ids=["system", "model"])
def test_an_unknown_top_level_key_of_a_system_names_every_kind(tmp_path, text, key):
    from massprops.dynamics.systems.robot_scene import parse_model_scene

    read = parse_model_scene if text.startswith("model:") else parse_system
    with pytest.raises(SceneError) as info:
        read(text, source="s.yaml", base_dir=tmp_path)
    message = str(info.value)
    assert f"{key}: unknown key '{key}'" in message and "did you mean 'body" not in message
    assert all(kind in message for kind in ("body:", "bodies:", "model:"))


def test_a_body_orientation_that_is_not_unit_is_said(tmp_path):
    text = GOOD.replace("position: [0, 0, -1.5]", "position: [0, 0, -1.5], "
                        "orientation: [2, 0, 0, 0]")
    scene = parse_system(text, source="s.yaml", base_dir=tmp_path)
    (note,) = scene.notes
    assert note.startswith("s.yaml:3: bodies.lower.orientation: normalised")
    assert "norm was 2" in note


def _gap_of_the_four_bar(qa: float, qc: float) -> float:
    """The largest component (m) of the cut joint D's miss when the crank is turned by qa from
    the assembly pose and the rocker by qc relative to the coupler, the coupler's own turn qb
    chosen to bring D's two copies closest: planar geometry in (x, z), turns about +y."""
    a, b = np.zeros(2), np.array([0.5000000000000001, 0.8660254037844386])
    c, d = np.array([3.016007650436934, 2.4999487505001956]), np.array([3.0, 0.0])

    def turn(t):
        return np.array([[math.cos(t), math.sin(t)], [-math.sin(t), math.cos(t)]])

    def miss(qb):
        b1 = a + turn(qa) @ (b - a)
        c1 = b1 + turn(qa + qb) @ (c - b)
        return c1 + turn(qa + qb + qc) @ (d - c) - d

    grid = np.linspace(-math.pi, math.pi, 20001)
    best = grid[np.argmin([np.linalg.norm(miss(q)) for q in grid])]
    fine = np.linspace(best - 1e-3, best + 1e-3, 20001)
    best = fine[np.argmin([np.linalg.norm(miss(q)) for q in fine])]
    return float(np.abs(miss(best)).max())


def test_a_loop_that_cannot_close_at_the_start_is_the_scene_s_mistake(tmp_path):
    """The four-bar with the crank and the rocker's relative turn both named: no turn of the
    coupler closes the loop (exit 3, 'the joints cannot be closed at t = 0 s', before). Said at
    the named positions' line, with the gap left (planar geometry: 0.285 m)."""
    text = FOUR_BAR.read_text().replace("rates: {A: 2.0}",
                                        "positions: {A: 0.5, C: 0.3}\n  rates: {A: 2.0}")
    message = _refused(text, tmp_path)
    assert "initial.positions.A" in message and "cannot be closed" in message
    assert "A = 0.5, C = 0.3" in message
    said = float(message.split("leave it open by ")[1].split(" m")[0])
    assert said == pytest.approx(_gap_of_the_four_bar(0.5, 0.3), abs=6e-4)


def test_cli_a_loop_that_cannot_close_exit_1(tmp_path, run):
    path = tmp_path / "fb.yaml"
    path.write_text(FOUR_BAR.read_text().replace(
        "rates: {A: 2.0}", "positions: {A: 0.5, C: 0.3}\n  rates: {A: 2.0}"))
    res = run("simulate", str(path))
    assert res.exit_code == 1, res.stderr
    (line,) = res.stderr.strip().splitlines()
    assert "fb.yaml:" in line and "initial.positions.A" in line


def test_a_joint_rate_too_fast_to_square_is_refused(tmp_path):
    """A hinge at 1e300 rad/s (numpy overflow warnings, then a run that did not end)."""
    text = GOOD.replace("time:", "initial: {rates: {elbow: 1.0e300}}\ntime:")
    message = _refused(text, tmp_path)
    assert "initial.rates.elbow" in message and "too large for float64" in message
    text = GOOD.replace("time:", "initial: {bodies: {free: {angular_velocity: [1.0e300, 0, 0]}}}"
                        "\ntime:").replace("  lower:", f"  free: {ROD}position: [5, 0, 0]}}\n"
                                           "  lower:")
    message = _refused(text, tmp_path)
    assert "initial.bodies.free" in message and "rad/s at most" in message


def test_a_ball_joint_position_that_is_not_unit_is_said(tmp_path):
    text = GOOD.replace("type: revolute, bodies: [upper, lower], point: [0, 0, -1], "
                        "axis: [0, 1, 0]", "type: spherical, bodies: [upper, lower], "
                        "point: [0, 0, -1]")
    text = text.replace("time:", "initial: {positions: {elbow: [0, 0, 3, 4]}}\ntime:")
    _, _, notes = prepare(parse_system(text, source="s.yaml", base_dir=tmp_path))
    (note,) = notes
    assert note.startswith("s.yaml:7: initial.positions.elbow: normalised to [0, 0, 0.6, 0.8]")
