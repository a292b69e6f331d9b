"""sample_scenes/robot_arm.yaml and robot_arm.urdf against what their header says."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from massprops.dynamics.systems.robot_scene import load_any_system
from massprops.dynamics.systems.run import simulate_system

SCENES = Path(__file__).resolve().parent.parent / "sample_scenes"


def test_sample_arm_static_torques_in_closed_form(run):
    result = run("simulate", SCENES / "robot_arm.urdf", "--duration", "0", "--json")
    assert result.exit_code == 0, result.stderr
    joints = json.loads(result.stdout)["final"]["joints"]
    g = 9.81
    # level along +x: upper arm 2 kg at 0.2 m, forearm 1 kg at 0.4 + 0.15, slider 0.5 kg at
    # 0.4 + 0.3 + 0.05 from the shoulder; the elbow carries the last two from 0.4 m out
    assert joints["shoulder"]["holding"][0] == pytest.approx(-g * (2 * 0.2 + 1 * 0.55
                                                                   + 0.5 * 0.75), rel=1e-14)
    assert joints["elbow"]["holding"][0] == pytest.approx(-g * (1 * 0.15 + 0.5 * 0.35),
                                                          rel=1e-14)
    assert joints["yaw"]["holding"] == [0.0]
    assert abs(joints["extend"]["holding"][0]) < 1e-14
    assert result.stderr.count("not enforced") == 1


def test_the_start_pose_summary_says_nothing_was_integrated(run):
    """At duration 0 there is no motion, so no estimate to miss: the summary says so, not that
    companion runs failed (as it once did)."""
    result = run("simulate", SCENES / "robot_arm.urdf", "--duration", "0")
    assert result.exit_code == 0, result.stderr
    head = result.stdout.splitlines()[0]
    assert head.endswith("t = 0 s in 0 steps; error estimate none (the start pose: no motion "
                         "integrated)")
    assert "shoulder (revolute)" in result.stdout and "holding" in result.stdout


def test_sample_arm_scene_loses_energy_only_to_its_damper():
    scene = load_any_system(SCENES / "robot_arm.yaml")
    assert [b.name for b in scene.bodies] == ["turret", "upper_arm", "forearm", "slider"]
    assert {j.name: j.damping for j in scene.joints}["yaw"] == 0.05
    result = simulate_system(scene, every=0.05, estimate=False)
    # the energy of the states, gravity included, computed here from the samples
    s = result.samples
    masses = np.array([b.mass for b in scene.bodies])
    inertia = [b.inertia for b in scene.bodies]
    energy = []
    for k in range(len(s.t)):
        e = 0.0
        for i, m in enumerate(masses):
            q = s.orientation[k, i]
            w, x, y, z = q
            r = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                          [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                          [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
            wb = r.T @ s.angular_velocity[k, i]
            e += 0.5 * m * s.velocity[k, i] @ s.velocity[k, i] + 0.5 * wb @ inertia[i] @ wb
            e += m * 9.81 * s.position[k, i, 2]
        energy.append(e)
    steps = np.diff(energy)
    assert np.all(steps <= 1e-9 * max(map(abs, energy)))
    assert steps.sum() < 0
