"""A URDF arm as a mechanism: its motion against MuJoCo on the same arm written as MJCF, its
holding torques against Pinocchio's RNEA and a closed form, and the CLI's `simulate ROBOT`."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
import robot_arms as ra

from massprops.dynamics.systems.description import describe
from massprops.dynamics.systems.model import SystemInitial
from massprops.dynamics.systems.robot_scene import description_scene, load_any_system
from massprops.dynamics.systems.run import simulate_system

Q0 = {"yaw": 0.3, "shoulder": -0.4, "elbow": 0.7, "slide": 0.05, "wrist": 0.2}
U0 = {"yaw": 0.5, "shoulder": 0.1, "elbow": -0.3, "slide": 0.2, "wrist": 1.0}


def _static(path, positions) -> dict:
    """The holding forces of the description at ``positions`` (duration 0), name -> list."""
    scene = description_scene(path, duration=0)
    scene = dataclasses.replace(scene, initial=SystemInitial({k: (v,) for k, v in
                                                              positions.items()}))
    joints = simulate_system(scene).as_dict()["final"]["joints"]
    return {name: j["holding"] for name, j in joints.items()}


def test_fixed_frames_are_lumped_and_the_base_is_the_world(tmp_path):
    path = tmp_path / "arm.urdf"
    path.write_text(ra.urdf())
    desc = describe(path)
    # base_footprint, base and world are welded (the world); tool rides on the hand
    assert [b.name for b in desc.bodies] == ["turret", "upper", "fore", "sleeve", "hand"]
    assert [j.name for j in desc.joints] == [j[0] for j in ra.JOINTS]
    hand = desc.bodies[-1]
    assert hand.mass == ra.LINKS["hand"][0]  # the massless tool adds nothing
    # the yaw joint's point in the world: mount (0) + foot (0.01 up) + its origin
    assert np.allclose(desc.joints[0].point, [0.0, 0.0, 0.13], atol=1e-15)
    assert any("not enforced" in w for w in desc.warnings)
    assert sum("out of scope" in w for w in desc.warnings) == 1


@pytest.mark.slow
def test_urdf_arm_moves_as_mujoco_moves_it(tmp_path):
    pytest.importorskip("mujoco")
    (tmp_path / "arm.urdf").write_text(ra.urdf())
    (tmp_path / "arm.yaml").write_text(
        "model: arm.urdf\n"
        f"initial: {{positions: {json.dumps(Q0)}, rates: {json.dumps(U0)}}}\n"
        "forces: [{type: gravity, g: [0, 0, -9.81]}]\n"
        "time: {duration: 0.5, rtol: 1.0e-10}\n")
    result = simulate_system(load_any_system(tmp_path / "arm.yaml"), estimate=False)
    mine = {k: v["coordinates"][0] for k, v in result.as_dict()["final"]["joints"].items()}
    # MuJoCo's RK4 at 1e-4 s, contacts off, no armature: measured agreement ~2e-11 rad
    reference = ra.run_mujoco(ra.mjcf(), Q0, U0, 0.5)
    worst = max(abs(mine[k] - reference[k]) for k in mine)
    assert worst < 1e-8


@pytest.mark.slow
def test_damping_as_mujoco_damps(tmp_path):
    pytest.importorskip("mujoco")
    damping = {"shoulder": 0.8, "slide": 2.0}
    (tmp_path / "arm.urdf").write_text(ra.urdf(damping=damping))
    scene = description_scene(tmp_path / "arm.urdf", duration=0.3)
    scene = dataclasses.replace(
        scene, initial=SystemInitial({k: (v,) for k, v in Q0.items()},
                                     {k: (v,) for k, v in U0.items()}),
        time=dataclasses.replace(scene.time, rtol=1e-10))
    joints = simulate_system(scene, estimate=False).as_dict()["final"]["joints"]
    reference = ra.run_mujoco(ra.mjcf(damping=damping), Q0, U0, 0.3)
    assert max(abs(joints[k]["coordinates"][0] - reference[k]) for k in joints) < 1e-8


def test_holding_torques_match_pinocchio_rnea(tmp_path):
    pin = pytest.importorskip("pinocchio")
    (tmp_path / "arm.urdf").write_text(ra.urdf())
    held = _static(tmp_path / "arm.urdf", Q0)
    model = pin.buildModelFromXML(ra.urdf())
    data = model.createData()
    names = list(model.names)[1:]
    q = np.array([Q0[n] for n in names])
    tau = pin.rnea(model, data, q, np.zeros(model.nv), np.zeros(model.nv))
    # measured: within 6e-15 N·m
    for name, t in zip(names, tau):
        assert held[name][0] == pytest.approx(t, abs=1e-12)


TWO_LINK = """<robot name="planar">
  <link name="base"/>
  <link name="a"><inertial><origin xyz="{h1} 0 0"/><mass value="{m1}"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.02"/></inertial></link>
  <link name="b"><inertial><origin xyz="{h2} 0 0"/><mass value="{m2}"/>
    <inertia ixx="0.001" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>
  <joint name="q1" type="continuous"><parent link="base"/><child link="a"/>
    <axis xyz="0 1 0"/></joint>
  <joint name="q2" type="continuous"><parent link="a"/><child link="b"/>
    <origin xyz="{l1} 0 0"/><axis xyz="0 1 0"/></joint>
</robot>"""


@pytest.mark.parametrize("q1, q2", [(0.0, 0.0), (0.4, -1.1), (-2.0, 0.5)])
def test_two_link_holding_torques_closed_form(tmp_path, q1, q2):
    m1, m2, l1, l2, g = 2.0, 1.5, 0.6, 0.5, 9.81
    path = tmp_path / "planar.urdf"
    path.write_text(TWO_LINK.format(m1=m1, m2=m2, l1=l1, h1=l1 / 2, h2=l2 / 2))
    held = _static(path, {"q1": q1, "q2": q2})
    # a turn q about +y takes the link's x axis to (cos q, 0, -sin q): the weight at x·cos q
    # (horizontal reach) turns the link by +m g x cos q; the motor holds with the opposite
    c1, c12 = math.cos(q1), math.cos(q1 + q2)
    tau2 = -m2 * g * (l2 / 2) * c12
    tau1 = -g * (m1 * (l1 / 2) * c1 + m2 * (l1 * c1 + (l2 / 2) * c12))
    assert held["q2"][0] == pytest.approx(tau2, rel=1e-13, abs=1e-13)
    assert held["q1"][0] == pytest.approx(tau1, rel=1e-13, abs=1e-13)


def test_holding_torques_hold_the_pose(tmp_path):
    """Applied as constant drives, the holding torques keep the arm at rest (a check that
    needs no other program)."""
    (tmp_path / "arm.urdf").write_text(ra.urdf())
    held = _static(tmp_path / "arm.urdf", Q0)
    scene = description_scene(tmp_path / "arm.urdf", duration=0.2)
    joints = tuple(dataclasses.replace(j, drive=held[j.name][0]) for j in scene.joints)
    scene = dataclasses.replace(scene, joints=joints, initial=SystemInitial(
        {k: (v,) for k, v in Q0.items()}))
    final = simulate_system(scene, estimate=False).as_dict()["final"]["joints"]
    for name, j in final.items():
        assert j["coordinates"][0] == pytest.approx(Q0[name], abs=1e-9)
        assert abs(j["rates"][0]) < 1e-9


def test_cli_duration_zero_gives_static_torques(tmp_path, run):
    path = tmp_path / "planar.urdf"
    path.write_text(TWO_LINK.format(m1=2.0, m2=1.5, l1=0.6, h1=0.3, h2=0.25))
    result = run("simulate", path, "--duration", "0", "--json")
    assert result.exit_code == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["final"]["t"] == 0.0
    q2 = data["final"]["joints"]["q2"]
    assert q2["holding"][0] == pytest.approx(-1.5 * 9.81 * 0.25, rel=1e-13)
    assert "out of scope" in result.stderr and result.stderr.count("out of scope") == 1


def test_cli_runs_a_description_for_a_while(tmp_path, run):
    path = tmp_path / "planar.urdf"
    path.write_text(TWO_LINK.format(m1=2.0, m2=1.5, l1=0.6, h1=0.3, h2=0.25))
    result = run("simulate", path, "--duration", "0.2", "--json")
    assert result.exit_code == 0, result.stderr
    data = json.loads(result.stdout)
    assert data["final"]["t"] == pytest.approx(0.2)
    assert data["diagnostics"]["energy_rel_drift"] < 1e-8
    # falling from horizontal: both joints turn down (+y turns x toward -z)
    assert data["final"]["joints"]["q1"]["coordinates"][0] > 0


BOX_ARM = """<robot name="boxes">
  <link name="base"/>
  <link name="arm">
    <inertial><origin xyz="0.9 0 0"/><mass value="3"/>
      <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
    <collision><origin xyz="0.25 0 0"/><geometry><box size="0.5 0.1 0.1"/></geometry></collision>
  </link>
  <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
</robot>"""


def test_inertials_stated_or_computed(tmp_path):
    (tmp_path / "boxes.urdf").write_text(BOX_ARM)
    for inertials, reach in (("stated", 0.9), ("computed", 0.25)):
        (tmp_path / "s.yaml").write_text(f"model: boxes.urdf\ninertials: {inertials}\n"
                                         "forces: [{type: gravity, g: [0, 0, -9.81]}]\n"
                                         "time: {duration: 1}\n")
        scene = load_any_system(tmp_path / "s.yaml")
        body = scene.bodies[0]
        assert body.mass == 3.0 and body.com0[0] == pytest.approx(reach, rel=1e-14)
        if inertials == "computed":  # a uniform 0.5 x 0.1 x 0.1 box of 3 kg
            assert body.inertia[1, 1] == pytest.approx(3 * (0.5**2 + 0.1**2) / 12, rel=1e-12)
        scene = dataclasses.replace(scene, time=dataclasses.replace(scene.time, duration=0))
        held = simulate_system(scene).as_dict()["final"]["joints"]["hinge"]["holding"][0]
        assert held == pytest.approx(-3 * 9.81 * reach, rel=1e-13)


@pytest.mark.slow
def test_floating_base_falls_with_its_centre_of_mass_at_g(tmp_path):
    """base: floating frees the root: whatever the joints do inside, the whole arm's centre of
    mass moves as a stone thrown, c0 + v0 t + g t²/2 (no other external force)."""
    (tmp_path / "arm.urdf").write_text(ra.urdf())
    (tmp_path / "f.yaml").write_text(
        f"model: arm.urdf\nbase: floating\ninitial: {{rates: {json.dumps(U0)}}}\n"
        "forces: [{type: gravity, g: [0, 0, -9.81]}]\ntime: {duration: 0.3}\n")
    scene = load_any_system(tmp_path / "f.yaml")
    assert scene.bodies[0].name == "base_footprint"  # the lumped base floats
    result = simulate_system(scene, estimate=False)
    masses = np.array([b.mass for b in scene.bodies])
    s = result.samples
    com = (masses[:, None] * s.position).sum(axis=1) / masses.sum()
    v0 = (masses[:, None] * s.velocity[0]).sum(axis=0) / masses.sum()  # the joints' share
    t = s.t[:, None]
    expected = com[0] + v0 * t + np.array([0.0, 0.0, -9.81]) * t**2 / 2
    assert np.abs(com - expected).max() < 1e-9
