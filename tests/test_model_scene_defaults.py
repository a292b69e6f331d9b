"""A `model:` scene as a robot builder expects it (issue 34 §3): the description's gravity unless
the scene names one, said in a note; `time.duration: 0` for the start pose's holding forces, as
`--duration 0` gives them; the JSON saying what `holding` is."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import ROOT

from massprops.dynamics import any_scene

ARM = ROOT / "sample_scenes" / "robot_arm.urdf"


def scene_file(tmp_path, extra: str = "", duration: str = "0"):
    path = tmp_path / "arm.yaml"
    path.write_text(f"model: {ARM}\n{extra}time: {{duration: {duration}}}\n")
    return path


def holding(result) -> np.ndarray:
    return np.array([j["holding"] for j in result.as_dict()["final"]["joints"].values()])


@pytest.mark.timeout(120)
def test_a_model_scene_without_gravity_takes_the_descriptions_and_says_so(tmp_path):
    scene = any_scene.load(scene_file(tmp_path))
    assert any("names no gravity" in n and "-9.81" in n for n in scene.notes)
    np.testing.assert_array_equal(scene.gravity, [0.0, 0.0, -9.81])
    # the same holding forces as the description run directly (its zero pose, its gravity)
    direct = any_scene.simulate(any_scene.load(ARM, 0.0))
    np.testing.assert_allclose(holding(any_scene.simulate(scene)), holding(direct),
                               rtol=0, atol=1e-12)


@pytest.mark.timeout(120)
def test_a_scene_that_names_gravity_keeps_its_own(tmp_path):
    off = any_scene.load(scene_file(tmp_path, "forces:\n  - {type: gravity, g: [0, 0, 0]}\n"))
    assert not any("names no gravity" in n for n in off.notes)
    np.testing.assert_array_equal(off.gravity, [0.0, 0.0, 0.0])
    np.testing.assert_allclose(holding(any_scene.simulate(off)), 0.0, atol=1e-15)
    moon = any_scene.load(scene_file(tmp_path, "forces:\n  - {type: gravity, g: [0, 0, -1.62]}\n"))
    earth = any_scene.load(ARM, 0.0)
    # holding at rest is linear in g: the moon's is 1.62 / 9.81 of the earth's
    np.testing.assert_allclose(holding(any_scene.simulate(moon)),
                               holding(any_scene.simulate(earth)) * 1.62 / 9.81, atol=1e-12)


@pytest.mark.timeout(120)
def test_duration_zero_in_the_scene_is_the_start_pose_and_says_what_holding_is(run, tmp_path):
    res = run("simulate", scene_file(tmp_path), "--json")
    assert res.exit_code == 0, res.stderr
    data = json.loads(res.stdout)
    assert data["steps"] == 0 and data["final"]["t"] == 0.0
    assert "spring" in data["diagnostics"]["holding"]
    one_body = tmp_path / "body.yaml"
    one_body.write_text("body: {mass: 1, inertia: [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}\n"
                        "time: {duration: 0}\n")
    refused = run("simulate", one_body)  # one body has no start-pose reactions to report
    assert refused.exit_code == 1
    assert "time.duration: expected a positive number, got 0" in refused.stderr
