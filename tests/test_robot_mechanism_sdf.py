"""SDF joint frames (1.6: the joint pose in the child link frame, ``use_parent_model_frame``;
1.7: ``relative_to`` and ``expressed_in``) against hand computations, and refusals of bad
joints: one line naming file and line, exit 1."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from massprops.dynamics.systems.description import describe
from massprops.dynamics.systems.robot_scene import description_scene
from massprops.errors import SceneError

INERTIAL = ("<inertial>{pose}<mass>{m}</mass><inertia><ixx>0.01</ixx><ixy>0</ixy><ixz>0</ixz>"
            "<iyy>0.01</iyy><iyz>0</iyz><izz>0.01</izz></inertia></inertial>")


def _sdf(version: str, joint_pose: str, axis: str, a_yaw: float = 0.0) -> str:
    return f"""<sdf version="{version}"><model name="m">
  <link name="A"><pose>0 0 1 0 0 {a_yaw!r}</pose>{INERTIAL.format(pose="", m=1)}</link>
  <link name="B"><pose>1 0 1 0 0 {math.pi / 2!r}</pose>
    {INERTIAL.format(pose="<pose>0.2 0 0 0 0 0</pose>", m=2)}</link>
  <joint name="fix" type="fixed"><parent>world</parent><child>A</child></joint>
  <joint name="j" type="revolute"><parent>A</parent><child>B</child>{joint_pose}
    <axis>{axis}<limit><lower>-1e16</lower><upper>1e16</upper></limit></axis></joint>
</model></sdf>"""


def _joint(tmp_path, text):
    path = tmp_path / "m.sdf"
    path.write_text(text)
    desc = describe(path)
    assert [b.name for b in desc.bodies] == ["B"]  # A is welded to the world
    return desc.joints[0]


def test_sdf16_joint_pose_is_in_the_child_frame(tmp_path):
    j = _joint(tmp_path, _sdf("1.6", "<pose>0 0.5 0 0 0 0</pose>", "<xyz>1 0 0</xyz>", 0.5))
    # B at (1, 0, 1) turned 90° about z: its (0, 0.5, 0) is world (-0.5, 0, 0) from B
    assert np.allclose(j.point, [0.5, 0.0, 1.0], atol=1e-15)
    assert np.allclose(j.axes[0], [0.0, 1.0, 0.0], atol=1e-15)  # B's x axis


def test_sdf16_use_parent_model_frame(tmp_path):
    axis = "<xyz>1 0 0</xyz><use_parent_model_frame>true</use_parent_model_frame>"
    j = _joint(tmp_path, _sdf("1.6", "<pose>0 0.5 0 0 0 0</pose>", axis))
    assert np.allclose(j.axes[0], [1.0, 0.0, 0.0], atol=1e-15)


def test_sdf17_relative_to_and_expressed_in(tmp_path):
    yaw = 0.5
    j = _joint(tmp_path, _sdf("1.7", '<pose relative_to="A">0 0.5 0 0 0 0</pose>',
                              "<xyz>1 0 0</xyz>", yaw))
    # the joint frame is A's (turned by yaw), placed at A's (0, 0.5, 0)
    assert np.allclose(j.point, [-0.5 * math.sin(yaw), 0.5 * math.cos(yaw), 1.0], atol=1e-15)
    assert np.allclose(j.axes[0], [math.cos(yaw), math.sin(yaw), 0.0], atol=1e-15)
    j = _joint(tmp_path, _sdf("1.7", '<pose relative_to="A">0 0.5 0 0 0 0</pose>',
                              '<xyz expressed_in="__model__">1 0 0</xyz>', yaw))
    assert np.allclose(j.axes[0], [1.0, 0.0, 0.0], atol=1e-15)


def test_sdf_holding_torque_by_hand(tmp_path, run):
    (tmp_path / "m.sdf").write_text(_sdf("1.6", "<pose>0 0.5 0 0 0 0</pose>",
                                         "<xyz>1 0 0</xyz>"))
    result = run("simulate", tmp_path / "m.sdf", "--duration", "0", "--json")
    assert result.exit_code == 0, result.stderr
    # B's centre of mass (1, 0.2, 1), 2 kg, about the axis +y through (0.5, 0, 1): the weight
    # turns it by +0.5 m x 2 kg x 9.81 about +y; the motor holds with the opposite
    held = json.loads(result.stdout)["final"]["joints"]["j"]["holding"][0]
    assert held == pytest.approx(-0.5 * 2 * 9.81, rel=1e-14)
    assert "not enforced" not in result.stderr  # ±1e16: SDF's "no limit"


URDF_BASE = """<robot name="r">
  <link name="a"><inertial><mass value="1"/>
    <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <link name="b"><inertial><mass value="1"/>
    <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  {joint}
</robot>"""


@pytest.mark.parametrize("name, text, needle", [
    ("r.urdf", URDF_BASE.format(joint='<joint name="j" type="revolute"><parent link="nope"/>'
                                      '<child link="b"/></joint>'), "no link named 'nope'"),
    ("r.urdf", URDF_BASE.format(joint='<joint name="j" type="planar"><parent link="a"/>'
                                      '<child link="b"/><axis xyz="0 0 0"/></joint>'),
     "axis is zero"),
    ("r.urdf", URDF_BASE.format(joint='<joint name="j" type="hinge"><parent link="a"/>'
                                      '<child link="b"/></joint>'), "not a URDF joint type"),
    ("r.urdf", URDF_BASE.format(joint='<joint name="j" type="revolute"><parent link="a"/>'
                                      '<child link="b"/><axis xyz="0 0 0"/></joint>'),
     "axis is zero"),
    ("m.sdf", '<sdf version="1.7"><model name="m"><link name="a"/><link name="b"/>\n'
              '<joint name="j" type="revolute"><parent>a</parent><child>b</child></joint>'
              '</model></sdf>', "needs <axis><xyz>"),
    ("m.sdf", '<sdf version="1.7"><model name="m"><link name="a"/><link name="b"/>\n'
              '<joint name="j" type="screw"><parent>a</parent><child>b</child></joint>'
              '</model></sdf>', "type 'screw'"),
    ("m.sdf", '<sdf version="1.7"><model name="m"><link name="a"/><link name="b"/>\n'
              '<joint name="j" type="fixed"><parent>x</parent><child>b</child></joint>'
              '</model></sdf>', "no link named 'x'"),
])
def test_bad_joints_are_one_line_exit_1(tmp_path, run, name, text, needle):
    path = tmp_path / name
    path.write_text(text)
    result = run("simulate", path, "--duration", "0")
    assert result.exit_code == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and needle in lines[0] and f"{name}:" in lines[0], result.stderr


def test_massless_link_moved_by_a_joint_is_refused(tmp_path, run):
    path = tmp_path / "r.urdf"
    path.write_text('<robot name="r"><link name="a"/><link name="tool"/>\n'
                    '<joint name="j" type="revolute"><parent link="a"/><child link="tool"/>'
                    '<axis xyz="0 0 1"/></joint></robot>')
    result = run("simulate", path, "--duration", "0")
    assert result.exit_code == 1
    assert "'tool'" in result.stderr and "'j'" in result.stderr and "r.urdf:2" in result.stderr


def test_singular_mass_matrix_is_refused(tmp_path, run):
    path = tmp_path / "r.urdf"
    path.write_text('<robot name="r"><link name="a"/><link name="mid"/><link name="arm">'
                    '<inertial><origin xyz="0.5 0 0"/><mass value="1"/><inertia ixx="0.01" '
                    'ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>'
                    '<joint name="j1" type="continuous"><parent link="a"/><child link="mid"/>'
                    '<axis xyz="0 1 0"/></joint><joint name="j2" type="continuous">'
                    '<parent link="mid"/><child link="arm"/><axis xyz="0 1 0"/></joint></robot>')
    result = run("simulate", path, "--duration", "0")
    assert result.exit_code == 1
    assert "singular" in result.stderr and "j1, j2" in result.stderr


def test_one_body_scene_takes_duration(tmp_path, run):
    """--duration overrides a one-body scene's time.duration too (0 only means something for a
    system: its start pose's reactions)."""
    import json

    scene = tmp_path / "s.yaml"
    scene.write_text("body: {mass: 1, inertia: [[1, 0, 0], [0, 2, 0], [0, 0, 3]]}\n"
                     "initial: {velocity: [1, 0, 0]}\ntime: {duration: 1}\n")
    result = run("simulate", scene, "--duration", "0.5", "--json")
    assert result.exit_code == 0
    final = json.loads(result.stdout)["final"]
    assert final["t"] == 0.5 and abs(final["position"][0] - 0.5) < 1e-12  # free drift 1 m/s
    result = run("simulate", scene, "--duration", "0")
    assert result.exit_code == 2 and "--duration" in result.stderr


def test_sdf_ball_universal_nested_and_static(tmp_path):
    link = "<link name='{}'><pose>{}</pose>" + INERTIAL.format(pose="", m=1) + "</link>"
    text = f"""<sdf version="1.7"><model name="outer"><pose>0 0 1 0 0 0</pose>
  {link.format("a", "0 0 0 0 0 0")}
  <joint name="ball" type="ball"><parent>inner::c</parent><child>a</child>
    <pose>0 0 0.5 0 0 0</pose></joint>
  <model name="inner"><pose>1 0 0 0 0 0</pose>
    {link.format("b", "0 2 0 0 0 0")}
    {link.format("c", "0 0 0 0 0 0")}
    <joint name="u" type="universal"><parent>b</parent><child>c</child>
      <axis><xyz>1 0 0</xyz></axis><axis2><xyz>0 1 0</xyz></axis2></joint>
  </model>
</model></sdf>"""
    (tmp_path / "n.sdf").write_text(text)
    desc = describe(tmp_path / "n.sdf")
    joints = {j.name: j for j in desc.joints}
    assert joints["ball"].kind == "spherical"
    # a at the outer model's (0, 0, 1); the ball's pose is in a's (the child's) frame
    assert np.allclose(joints["ball"].point, [0, 0, 1.5], atol=1e-15)
    # c sits in the inner model, placed at (1, 0, 0) in the outer one; b is the root (welded)
    u = joints["outer::inner::u"]
    assert u.kind == "universal"
    assert np.allclose(u.point, [1, 0, 1], atol=1e-15)
    assert np.allclose(u.axes, [[1, 0, 0], [0, 1, 0]], atol=1e-15)
    assert [b.name for b in desc.bodies] == ["a", "outer::inner::c"]
    (tmp_path / "s.sdf").write_text(text.replace("<pose>0 0 1 0 0 0</pose>",
                                                 "<static>true</static><pose>0 0 1 0 0 0</pose>",
                                                 1))
    with pytest.raises(SceneError, match="nothing moves"):
        description_scene(tmp_path / "s.sdf", duration=0)


@pytest.mark.parametrize("name, text, root", [
    ("e.urdf", '<robot name="r"/>', "<robot>"),
    ("e.sdf", '<sdf version="1.7"><model name="m"/></sdf>', "<sdf>"),
    ("e.xml", "<mujoco><worldbody/></mujoco>", "<mujoco>")])
def test_description_without_links_is_one_line_naming_its_root(tmp_path, run, name, text, root):
    path = tmp_path / name
    path.write_text(text)
    result = run("simulate", path, "--duration", "0")
    assert result.exit_code == 1 and result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and f"{name}:1: {root}: no links" in lines[0]
