"""Joint scenes: the ``joints:`` list, the combinations that hold a body, the initial state
checked against the joints (refused with one line saying by how much and what would be
consistent, or projected on request), and the CLI's exit code and stderr line."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from massprops.dynamics.joints.model import RevoluteJoint, SphericalJoint
from massprops.dynamics.model import InitialState, OutputSettings, RigidBody, Scene, TimeSettings
from massprops.dynamics.scene import parse_scene
from massprops.dynamics.simulate import simulate
from massprops.errors import SceneError
from massprops.rotation import quat_from_axis_angle, quat_to_matrix

BODY = "body: {mass: 2.0, inertia: [[0.1, 0, 0], [0, 0.1, 0], [0, 0, 0.02]]}\n"
TIME = "time: {duration: 1.0}\n"


def parse(text: str) -> Scene:
    return parse_scene(text, source="scene.yaml", base_dir=Path("."))


def marked_line(text: str) -> int:
    lines = [i for i, line in enumerate(text.splitlines(), start=1) if "# <-" in line]
    assert len(lines) == 1, "a test scene marks exactly one line"
    return lines[0]


def refused(text: str, key_path: str) -> str:
    """The scene is refused in one line naming the file, the marked line and the key path."""
    with pytest.raises(SceneError) as info:
        parse(text)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"scene.yaml:{marked_line(text)}: {key_path}:"), message
    return message


# --- reading --------------------------------------------------------------------------------------
def test_both_joint_types_round_trip_into_the_model():
    scene = parse(BODY + """\
joints:
  - {type: revolute, point: [0, 0, 0.5], axis: [2, 0, 0], anchor: [1, 2, 3],
     world_axis: [0, 3, 0], damping: 0.25, torque: 1.5, start: 0.1, end: 0.2}
initial: {orientation: [0.7071067811865476, 0, 0, 0.7071067811865476]}
""" + TIME)
    (j,) = scene.joints
    assert isinstance(j, RevoluteJoint)
    assert j.axis.tolist() == [1.0, 0.0, 0.0] and j.world_axis.tolist() == [0.0, 1.0, 0.0]
    assert (j.point.tolist(), j.anchor.tolist()) == ([0.0, 0.0, 0.5], [1.0, 2.0, 3.0])
    assert (j.damping, j.torque, j.start, j.end) == (0.25, 1.5, 0.1, 0.2)
    scene = parse(BODY + "joints: [{type: spherical, anchor: [1, 2, 3]}]\n" + TIME)
    (j,) = scene.joints
    assert isinstance(j, SphericalJoint) and j.point is None  # the centre of mass


def test_an_absent_position_and_velocity_are_derived_from_the_joint():
    q = quat_from_axis_angle([0.0, 1.0, 0.0], 0.3)
    w = np.array([0.2, -0.4, 0.9])
    scene = parse(BODY + f"""\
joints: [{{type: spherical, point: [0.1, 0.2, -0.4], anchor: [1, 2, 3]}}]
initial: {{orientation: {q.tolist()}, angular_velocity: {w.tolist()}}}
""" + TIME)
    lever = quat_to_matrix(q) @ -np.array([0.1, 0.2, -0.4])  # centre of mass from the point
    assert np.allclose(scene.initial.position, np.array([1, 2, 3]) + lever, rtol=0, atol=1e-15)
    assert np.allclose(scene.initial.velocity, np.cross(w, lever), rtol=0, atol=1e-15)
    assert scene.notes == ()


def test_a_consistent_state_typed_with_ten_digits_is_accepted():
    text = BODY + """\
joints: [{type: spherical, point: [0, 0, 0.5], anchor: [0, 0, 0]}]
initial: {orientation: [0.8660254038, 0.5, 0, 0], position: [0, 0.4330127019, -0.25]}
""" + TIME
    assert parse(text).notes == ()


def test_a_position_off_the_joint_is_refused_with_the_consistent_value():
    message = refused(BODY + """\
joints: [{type: spherical, point: [0, 0, 0.5], anchor: [0, 0, 0]}]
initial:
  position: [0, 0, 0.5]  # <-
""" + TIME, "initial.position")
    assert "1 m off" in message and "[0, 0, -0.5]" in message
    assert "project_initial: true" in message


def test_a_velocity_the_joint_forbids_is_refused():
    message = refused(BODY + """\
joints: [{type: spherical, point: [0, 0, 0.5], anchor: [0, 0, 0]}]
initial:
  angular_velocity: [1, 0, 0]
  velocity: [0, 0, 0]  # <-
""" + TIME, "initial.velocity")
    assert "0.5 m/s off" in message and "[0, 0.5, 0]" in message  # ω × (c - anchor)


def test_a_hinge_axis_off_its_world_axis_is_refused():
    message = refused(BODY + """\
joints: [{type: revolute, axis: [1, 0, 0], anchor: [0, 0, 0], world_axis: [0, 1, 0]}]
initial:
  orientation: [1, 0, 0, 0]  # <-
""" + TIME, "initial.orientation")
    assert "1.57 rad off" in message
    assert "[0.7071067812, 0, 0, 0.7071067812]" in message  # a quarter turn about z


def test_an_angular_velocity_across_a_hinge_is_refused():
    message = refused(BODY + """\
joints: [{type: revolute, axis: [1, 0, 0], anchor: [0, 0, 0]}]
initial:
  angular_velocity: [3, 4, 0]  # <-
""" + TIME, "initial.angular_velocity")
    assert "4 rad/s off" in message and "[3, 0, 0]" in message


def test_project_initial_moves_the_state_onto_the_joints_and_says_so():
    scene = parse(BODY + """\
joints: [{type: revolute, point: [0, 0, 0.5], axis: [1, 0, 0], anchor: [0, 0, 0],
          world_axis: [1, 0, 0]}]
initial:  # <-
  orientation: [1, 0, 0.01, 0]
  angular_velocity: [3, 4, 0]
  position: [0, 0, 0]
  project_initial: true
""" + TIME)
    normalised, note = scene.notes  # [1, 0, 0.01, 0] is not a unit quaternion: said first
    assert normalised.startswith("scene.yaml:5: initial.orientation: normalised"), normalised
    assert note.startswith("scene.yaml:5: initial: projected onto the joints: "), note
    for what in ("orientation", "angular velocity", "position"):
        assert what in note
    a = quat_to_matrix(scene.initial.orientation)
    assert np.allclose(a @ [1, 0, 0], [1, 0, 0], atol=1e-15)
    assert np.allclose(scene.initial.angular_velocity, [3, 0, 0], atol=1e-15)
    assert np.allclose(scene.initial.position, a @ [0, 0, -0.5], atol=1e-15)


def test_project_initial_must_be_a_boolean_even_without_joints():
    refused(BODY + "initial:\n  project_initial: yes please  # <-\n" + TIME,
            "initial.project_initial")


# --- bad joints -----------------------------------------------------------------------------------
@pytest.mark.parametrize(("joints", "key_path", "words"), [
    ("  - {type: sperical, anchor: [0, 0, 0]}  # <-\n", "joints[0].type", "did you mean"),
    ("  - {type: spherical}  # <-\n", "joints[0].anchor", "missing"),
    ("  - {type: spherical, anchor: [0, 0, 0], axis: [1, 0, 0]}  # <-\n", "joints[0].axis",
     "unknown key"),
    ("  - {type: revolute, axis: [0, 0, 0], anchor: [0, 0, 0]}  # <-\n", "joints[0].axis",
     "non-zero"),
    ("  - {type: revolute, axis: [1, 0, 0], anchor: [0, 0, 0], damping: -1}  # <-\n",
     "joints[0].damping", "non-negative"),
    ("  - {type: revolute, axis: [1, 0, 0], anchor: [0, 0, 0], start: 2, end: 1}  # <-\n",
     "joints[0].end", "start < end"),
    ("  - [0, 0, 0]  # <-\n", "joints[0]", "expected a mapping"),
    ("  - {type: spherical, point: [0, 0, 0.5], anchor: [0, 0, 0]}\n"
     "  - {type: spherical, point: [0, 0, 0.5], anchor: [0, 0, 0]}  # <-\n", "joints[1]",
     "same body point"),
    ("  - {type: spherical, point: [0, 0, 0.5], anchor: [0, 0, 0]}\n"
     "  - {type: spherical, point: [0, 0, -0.5],\n"
     "     anchor: [0, 0, 2]}  # <-\n", "joints[1].anchor", "cannot reach both"),
    ("  - {type: spherical, point: [0, 0, 0.5], anchor: [0, 0, 0]}\n"
     "  - {type: spherical, point: [0, 0, -0.5], anchor: [0, 0, -1]}\n"
     "  - {type: spherical, point: [0, 0, 0], anchor: [0, 0, -0.5]}  # <-\n", "joints[2]",
     "adds no constraint"),
    ("  - {type: spherical, point: [0, 0, 0.5], anchor: [0, 0, 0]}\n"
     "  - {type: spherical, point: [0, 0, -0.5], anchor: [0, 0, -1]}\n"
     "  - {type: spherical, point: [0.1, 0, 0], anchor: [0.1, 0, -0.5]}  # <-\n", "joints[2]",
     "locks the body"),
    ("  - {type: revolute, axis: [1, 0, 0], point: [0, 0, 0.5], anchor: [0, 0, 0]}\n"
     "  - {type: spherical, point: [0.3, 0, 0.5], anchor: [0.3, 0, 0]}  # <-\n", "joints[1]",
     "adds no constraint"),
    ("  - {type: revolute, axis: [1, 0, 0], point: [0, 0, 0.5], anchor: [0, 0, 0]}\n"
     "  - {type: spherical, point: [0, 0, -0.5], anchor: [0, 0, -1]}  # <-\n", "joints[1]",
     "locks the body"),
    ("  - {type: revolute, axis: [1, 0, 0], anchor: [0, 0, 0]}\n"
     "  - {type: revolute, axis: [-2, 0, 0], anchor: [0, 0, 0]}  # <-\n", "joints[1]",
     "adds no constraint"),
    ("  - {type: revolute, axis: [1, 0, 0], anchor: [0, 0, 0]}\n"
     "  - {type: revolute, axis: [0, 1, 0], anchor: [0, 0, 0]}  # <-\n", "joints[1]",
     "lock the body"),
], ids=["type-typo", "no-anchor", "unknown-key", "zero-axis", "negative-damping",
        "window", "not-a-mapping", "same-point", "anchors-apart", "collinear-third",
        "third-off-line", "hinge-plus-point-on-axis", "hinge-plus-point-off-axis",
        "coaxial-hinges", "crossed-hinges"])
def test_bad_joints_are_refused_in_one_line(joints, key_path, words):
    message = refused(BODY + "joints:\n" + joints + TIME, key_path)
    assert words in message


def test_two_spherical_joints_make_a_hinge_whose_world_axis_joins_the_anchors():
    scene = parse(BODY + """\
joints:
  - {type: spherical, point: [0, 0, 0.5], anchor: [1, 0, 0]}
  - {type: spherical, point: [0, 0, -0.5], anchor: [1, 0, -1]}
initial: {angular_velocity: [0, 0, 2.0]}
""" + TIME)
    assert np.allclose(scene.initial.position, [1, 0, -0.5])
    message = refused(BODY + """\
joints:
  - {type: spherical, point: [0, 0, 0.5], anchor: [1, 0, 0]}
  - {type: spherical, point: [0, 0, -0.5], anchor: [1, 0, -1]}
initial:
  angular_velocity: [1, 0, 2.0]  # <-
""" + TIME, "initial.angular_velocity")
    assert "[0, 0, 2]" in message


def test_a_scene_built_in_code_is_checked_when_it_runs():
    body = RigidBody.from_inertia(2.0, np.diag([0.1, 0.1, 0.02]))
    joint = SphericalJoint(anchor=np.zeros(3), point=np.array([0.0, 0.0, 0.5]))
    scene = Scene(body=body, initial=InitialState(), forces=(), time=TimeSettings(1.0),
                  output=OutputSettings(), source="built", joints=(joint,))
    with pytest.raises(SceneError, match=r"^built: initial.position: .*\[0, 0, -0.5\]"):
        simulate(scene)


# --- the command line -----------------------------------------------------------------------------
def test_bad_joint_input_is_one_stderr_line_and_exit_1(run, tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_text(BODY + "joints:\n  - {type: spherical, point: [0, 0, 0.5], anchor: [0, 0, 0]}"
                    "\n  - {type: spherical, point: [0, 0, 0.5], anchor: [0, 0, 0]}\n" + TIME)
    result = run("simulate", path, "--json")
    assert result.exit_code == 1
    assert result.stdout == ""
    (line,) = result.stderr.splitlines()
    assert line.startswith(f"massprops: error: {path}:4: joints[1]: a second spherical joint")


def test_a_projection_is_a_warning_line_and_the_run_goes_on(run, tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_text(BODY + "joints: [{type: spherical, point: [0, 0, 0.5], anchor: [0, 0, 0]}]\n"
                    "initial: {position: [0, 0, 0], project_initial: true}\n" + TIME)
    result = run("simulate", path, "--json")
    assert result.exit_code == 0, result.stderr
    (line,) = result.stderr.splitlines()
    assert line == (f"massprops: warning: {path}:3: initial: projected onto the "
                    "joints: position by 0.5 m")
    assert math.isclose(json_final(result)["position"][2], -0.5, abs_tol=1e-15)


def json_final(result) -> dict:
    import json

    return json.loads(result.stdout)["final"]


@pytest.mark.slow
def test_simulate_json_plot_and_trajectory_of_a_hinge(run, tmp_path):
    pytest.importorskip("matplotlib")
    path = tmp_path / "scene.yaml"
    path.write_text(BODY + "joints: [{type: revolute, point: [0, 0, 0.5], axis: [1, 0, 0], "
                    "anchor: [0, 0, 0]}]\ninitial: {angular_velocity: [2.0, 0, 0]}\n"
                    "forces: [{type: gravity, g: [0, 0, -9.81]}]\n" + TIME)
    result = run("simulate", path, "--json", "--plot", tmp_path / "p.png", "--output",
                 tmp_path / "t.csv", "--every", "0.1")
    assert result.exit_code == 0, result.stderr
    import json

    out = json.loads(result.stdout)
    (joint,) = out["final"]["joints"]
    assert joint["type"] == "revolute" and len(joint["torque_world"]) == 3
    assert out["diagnostics"]["constraint_drift"] < 1e-14
    assert (tmp_path / "p.png").stat().st_size > 0
    header = (tmp_path / "t.csv").read_text().splitlines()[0]
    assert "j0_fz [N]" in header and "j0_tz_body [N*m]" in header


def test_a_free_body_reports_no_joints_and_a_null_constraint_drift(run, tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_text(BODY + "initial: {angular_velocity: [0.1, 2.0, 0]}\n" + TIME)
    result = run("simulate", path, "--json")
    import json

    out = json.loads(result.stdout)
    assert out["final"]["joints"] == [] and out["diagnostics"]["constraint_drift"] is None


def test_exact_is_refused_for_a_held_body_without_a_closed_form(run, tmp_path):
    path = tmp_path / "scene.yaml"
    path.write_text(BODY + "joints: [{type: revolute, point: [0, 0, 0.5], axis: [1, 0, 0], "
                    "anchor: [0, 0, 0]}]\nforces: [{type: gravity, g: [0, 0, -9.81]}]\n" + TIME)
    result = run("simulate", path, "--integrator", "exact")
    assert result.exit_code == 2
    (line,) = result.stderr.splitlines()
    assert "heavy symmetric top" in line
