"""An MJCF model as a mechanism: hinge, slide, ball and free joints, a universal and a
cylindrical joint made of two joints, a welded body, default classes; against MuJoCo. A loop
closed by ``<equality><connect>``: against the same mechanism written as a ``bodies:`` scene by
hand, its constraint residual, and MuJoCo with a stiff connect (MuJoCo's constraint is soft)."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from massprops.dynamics.systems.description import describe
from massprops.dynamics.systems.model import SystemInitial
from massprops.dynamics.systems.robot_scene import description_scene, load_any_system
from massprops.dynamics.systems.run import simulate_system
from massprops.errors import RobotModelError

MULTI = """<mujoco>
  <option timestep="1e-4" integrator="RK4"><flag contact="disable"/></option>
  <compiler angle="radian"/>
  <default><default class="arm"><joint axis="0 1 0"/></default></default>
  <worldbody>
    <body name="torso" pos="0 0 1" euler="0.1 0.2 0.3">
      <freejoint name="root"/>
      <inertial pos="0.01 0.02 0" mass="3" diaginertia="0.05 0.06 0.07"/>
      <body name="pend" pos="0.2 0 0" childclass="arm">
        <joint name="hinge" pos="0 0 0.05"/>
        <inertial pos="0.1 0 0" mass="0.5" diaginertia="0.001 0.004 0.004"/>
        <body name="bob" pos="0.2 0 0" axisangle="0 0 1 0.5">
          <joint name="ball" type="ball" pos="0 0 0.02"/>
          <inertial pos="0.05 0.01 0" mass="0.3" fullinertia="0.0005 0.0007 0.0009 0.0001 0 0"/>
        </body>
      </body>
      <body name="piston" pos="-0.1 0 0">
        <joint name="slide" type="slide" axis="0 0.6 0.8"/>
        <inertial pos="0 0 -0.05" mass="0.4" diaginertia="0.002 0.002 0.001"/>
      </body>
      <frame pos="0 0.1 0">
        <body name="gimbal" pos="0 0.1 0">
          <joint name="g1" axis="1 0 0" pos="0 0 0.01"/>
          <joint name="g2" axis="0 0 1" pos="0 0 0.01"/>
          <inertial pos="0.03 0.05 0" mass="0.6" diaginertia="0.003 0.002 0.004"/>
        </body>
      </frame>
      <body name="screw" pos="0 -0.2 0">
        <joint name="c1" axis="0 1 0"/><joint name="c2" type="slide" axis="0 1 0"/>
        <inertial pos="0.04 0 0.02" mass="0.5" diaginertia="0.002 0.003 0.002"/>
      </body>
      <body name="welded" pos="0 0 -0.1">
        <inertial pos="0 0 -0.02" mass="1" diaginertia="0.004 0.004 0.004"/>
      </body>
    </body>
  </worldbody>
</mujoco>"""

LOOP = """<mujoco>
  <option timestep="1e-4" integrator="RK4"><flag contact="disable"/></option>
  <compiler angle="radian"/>
  <worldbody>
    <body name="crank">
      <joint name="A" axis="0 1 0"/>
      <inertial pos="0.1 0 0" mass="1" diaginertia="0.001 0.004 0.004"/>
      <body name="coupler" pos="0.2 0 0">
        <joint name="B" axis="0 1 0"/>
        <inertial pos="0.2 0 0.05" mass="1" diaginertia="0.002 0.01 0.01"/>
      </body>
    </body>
    <body name="rocker" pos="0.5 0 0">
      <joint name="C" axis="0 1 0"/>
      <inertial pos="0 0 0.1" mass="0.5" diaginertia="0.002 0.002 0.0005"/>
    </body>
  </worldbody>
  <equality><connect name="D" body1="coupler" body2="rocker" anchor="0.3 0 0.2"{soft}/>
  </equality>
</mujoco>"""

LOOP_BY_HAND = """bodies:
  crank: {mass: 1, inertia: [[0.001, 0, 0], [0, 0.004, 0], [0, 0, 0.004]], position: [0.1, 0, 0]}
  coupler: {mass: 1, inertia: [[0.002, 0, 0], [0, 0.01, 0], [0, 0, 0.01]],
            position: [0.4, 0, 0.05]}
  rocker: {mass: 0.5, inertia: [[0.002, 0, 0], [0, 0.002, 0], [0, 0, 0.0005]],
           position: [0.5, 0, 0.1]}
joints:
  - {name: A, type: revolute, bodies: [world, crank], point: [0, 0, 0], axis: [0, 1, 0]}
  - {name: B, type: revolute, bodies: [crank, coupler], point: [0.2, 0, 0], axis: [0, 1, 0]}
  - {name: C, type: revolute, bodies: [world, rocker], point: [0.5, 0, 0], axis: [0, 1, 0]}
  - {name: D, type: spherical, bodies: [rocker, coupler], point: [0.5, 0, 0.2]}
forces: [{type: gravity, g: [0, 0, -9.81]}]
time: {duration: 0.3}
"""


def test_mjcf_joints_are_read(tmp_path):
    (tmp_path / "m.xml").write_text(MULTI)
    desc = describe(tmp_path / "m.xml")
    assert [b.name for b in desc.bodies] == ["torso", "pend", "bob", "piston", "gimbal", "screw"]
    kinds = {j.name: j.kind for j in desc.joints}
    assert kinds == {"hinge": "revolute", "ball": "spherical", "slide": "prismatic",
                     "g1+g2": "universal", "c1+c2": "cylindrical"}
    assert desc.bodies[0].mass == 4.0  # torso and the welded body: one body


@pytest.mark.slow
def test_mjcf_tree_moves_as_mujoco_moves_it(tmp_path):
    mujoco = pytest.importorskip("mujoco")
    (tmp_path / "m.xml").write_text(MULTI)
    model = mujoco.MjModel.from_xml_string(MULTI)
    data = mujoco.MjData(model)
    data.qvel[:] = np.random.default_rng(3).uniform(-1, 1, model.nv)
    mujoco.mj_forward(model, data)

    def dofs(name):
        j = model.joint(name)
        n = {0: 6, 1: 3, 2: 1, 3: 1}[int(model.jnt_type[j.id])]
        return data.qvel[j.dofadr[0]:j.dofadr[0] + n].copy()

    def body(name):
        return model.body(name).id

    # MuJoCo's rates -> the contract's: a free joint's (v of the body origin, world; ω body
    # axes) -> v of the lumped centre of mass and ω, world; a ball's ω (child axes) -> world
    rot = data.xmat[body("torso")].reshape(3, 3)
    omega = rot @ dofs("root")[3:]
    mt, mw = model.body_mass[body("torso")], model.body_mass[body("welded")]

    def lumped_com():
        return (mt * data.xipos[body("torso")] + mw * data.xipos[body("welded")]) / (mt + mw)

    v_com = dofs("root")[:3] + np.cross(omega, lumped_com() - data.xpos[body("torso")])
    rates = {"hinge": tuple(dofs("hinge")), "slide": tuple(dofs("slide")),
             "ball": tuple(data.xmat[body("bob")].reshape(3, 3) @ dofs("ball")),
             "g1+g2": (dofs("g1")[0], dofs("g2")[0]), "c1+c2": (dofs("c1")[0], dofs("c2")[0])}
    scene = description_scene(tmp_path / "m.xml", duration=0.5)
    scene = dataclasses.replace(scene, initial=SystemInitial({}, rates,
                                                             {"torso": (v_com, omega)}),
                                time=dataclasses.replace(scene.time, rtol=1e-10))
    final = simulate_system(scene, estimate=False).as_dict()["final"]["bodies"]
    for _ in range(5000):
        mujoco.mj_step(model, data)
    # measured: positions within 2e-12 m, orientations within 2e-11
    assert np.allclose(final["torso"]["position"], lumped_com(), atol=1e-9, rtol=0)
    for name in ("torso", "pend", "bob", "piston", "gimbal", "screw"):
        q = data.xquat[body(name)] * np.sign(data.xquat[body(name)][0])
        assert np.allclose(final[name]["orientation"], q, atol=1e-9, rtol=0), name
        if name != "torso":
            assert np.allclose(final[name]["position"], data.xipos[body(name)], atol=1e-9,
                               rtol=0), name


@pytest.mark.slow
def test_connect_loop_against_a_hand_written_scene(tmp_path):
    (tmp_path / "loop.xml").write_text(LOOP.format(soft=""))
    (tmp_path / "model.yaml").write_text("model: loop.xml\n"
                                         "forces: [{type: gravity, g: [0, 0, -9.81]}]\n"
                                         "time: {duration: 0.3}\n")
    (tmp_path / "hand.yaml").write_text(LOOP_BY_HAND)
    mine = simulate_system(load_any_system(tmp_path / "model.yaml"), estimate=False).as_dict()
    hand = simulate_system(load_any_system(tmp_path / "hand.yaml"), estimate=False).as_dict()
    for name in "ABC":
        assert mine["final"]["joints"][name]["coordinates"][0] == pytest.approx(
            hand["final"]["joints"][name]["coordinates"][0], abs=1e-9)
    assert mine["diagnostics"]["constraint_residual"]["position"] < 1e-12
    assert mine["diagnostics"]["degrees_of_freedom"] == 1
    # the loop joint is the cut one: its holding is zero, the hinges carry the pose
    assert mine["final"]["joints"]["D"]["holding"] == [0.0, 0.0, 0.0]


@pytest.mark.slow
def test_connect_loop_against_mujoco_with_a_stiff_constraint(tmp_path):
    mujoco = pytest.importorskip("mujoco")
    (tmp_path / "loop.xml").write_text(LOOP.format(soft=""))
    joints = simulate_system(description_scene(tmp_path / "loop.xml", duration=0.5),
                             estimate=False).as_dict()["final"]["joints"]
    # MuJoCo's equality is soft; with solref 0.5 ms and solimp 0.999 it comes within ~3e-7 rad
    # (0.05 rad at its defaults: measured, so this bounds its softness, not massprops)
    stiff = LOOP.format(soft=' solref="0.0005 1" solimp="0.999 0.9999 0.001"')
    model = mujoco.MjModel.from_xml_string(stiff)
    data = mujoco.MjData(model)
    for _ in range(5000):
        mujoco.mj_step(model, data)
    for i, name in enumerate("ABC"):
        assert joints[name]["coordinates"][0] == pytest.approx(data.qpos[i], abs=1e-5)


def test_loop_holding_torques_hold_the_pose(tmp_path):
    """With a loop the split is minimum-norm; whichever split, applied as drives on the hinges
    the torques keep the mechanism at rest."""
    (tmp_path / "loop.xml").write_text(LOOP.format(soft=""))
    scene = description_scene(tmp_path / "loop.xml", duration=0)
    held = {k: v["holding"] for k, v in simulate_system(scene).as_dict()["final"][
        "joints"].items()}
    # the minimum-norm choice: the motors' torques are orthogonal to what the loop can carry,
    # i.e. they cannot be made smaller; here simply check they hold the pose
    joints = tuple(dataclasses.replace(j, drive=held[j.name][0]) if j.kind == "revolute" else j
                   for j in scene.joints)
    scene = dataclasses.replace(scene, joints=joints,
                                time=dataclasses.replace(scene.time, duration=0.2))
    final = simulate_system(scene, estimate=False).as_dict()["final"]["joints"]
    for name in "ABC":
        assert abs(final[name]["coordinates"][0]) < 1e-9
        assert abs(final[name]["rates"][0]) < 1e-9


@pytest.mark.parametrize("body, needle", [
    ('<body name="b"><freejoint/><joint type="slide" axis="0 1 0"/>'
     '<inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body>', "only joint"),
    ('<body name="b"><joint name="h"/><body name="c"/></body>', "no mass"),
])
def test_mjcf_refusals_are_one_line(tmp_path, run, body, needle):
    (tmp_path / "bad.xml").write_text(f"<mujoco><worldbody>\n{body}\n</worldbody></mujoco>")
    with pytest.raises(RobotModelError, match=needle):
        describe(tmp_path / "bad.xml")
    result = run("simulate", tmp_path / "bad.xml", "--duration", "0")
    assert result.exit_code == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "bad.xml:2" in lines[0], result.stderr


def test_mjcf_option_gravity_is_used(tmp_path, run):
    (tmp_path / "g.xml").write_text(
        '<mujoco><option gravity="0 0 -1.62"/><worldbody><body name="b">'
        '<joint name="h" axis="0 1 0"/>'
        '<inertial pos="0.5 0 0" mass="2" diaginertia="0.1 0.1 0.1"/></body></worldbody>'
        '</mujoco>')
    result = run("simulate", tmp_path / "g.xml", "--duration", "0", "--json")
    assert result.exit_code == 0, result.stderr
    # weight 2 x 1.62 N at 0.5 m: the motor holds with -1.62 N·m about +y
    held = json.loads(result.stdout)["final"]["joints"]["h"]["holding"][0]
    assert held == pytest.approx(-1.62, rel=1e-14)


def test_compiler_mass_rules_reach_the_bodies_as_mujoco_compiles_them(tmp_path, monkeypatch):
    """<compiler settotalmass boundmass boundinertia> change the inertials MuJoCo simulates;
    the mechanism's bodies carry the same (against MuJoCo's compiled body_mass, body_inertia)."""
    mujoco = pytest.importorskip("mujoco")
    monkeypatch.chdir(tmp_path)  # MuJoCo logs settotalmass's deprecation to ./MUJOCO_LOG.TXT
    path = tmp_path / "rules.xml"
    path.write_text("""<mujoco><compiler settotalmass="10" boundmass="0.5" boundinertia="0.002"/>
  <worldbody><body name="a" pos="0 0 1"><joint type="hinge" axis="0 1 0"/>
    <inertial pos="0.5 0 0" mass="1" diaginertia="0.1 0.1 0.01"/>
    <body name="b" pos="1 0 0"><joint type="hinge" axis="0 1 0"/>
      <inertial pos="0.5 0 0" mass="3" diaginertia="0.1 0.15 0.06"/></body>
    <body name="c" pos="0 1 0"><joint type="hinge" axis="1 0 0"/>
      <inertial pos="0 0.1 0" mass="0.1" diaginertia="0.001 0.001 0.001"/></body>
  </body></worldbody></mujoco>""")
    ours = {b.name: b for b in describe(path).bodies}
    model = mujoco.MjModel.from_xml_path(str(path))
    for name in ("a", "b", "c"):
        k = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
        assert abs(ours[name].mass - model.body_mass[k]) < 1e-12 * model.body_mass[k]
        moments = np.linalg.eigvalsh(ours[name].inertia)
        assert np.allclose(np.sort(moments), np.sort(model.body_inertia[k]), rtol=1e-12)
    assert abs(sum(b.mass for b in ours.values()) - 10.0) < 1e-12
