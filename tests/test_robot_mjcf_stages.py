"""An MJCF body with several joints that are not one universal or cylindrical pair (the planar
root of gym's and dm_control's walkers: slide x, slide z, hinge y; three hinges through one
point; a damped pair) is a chain of massless stages, one joint each, named as written; it moves
as MuJoCo moves it."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from massprops.dynamics.systems.description import describe
from massprops.dynamics.systems.model import SystemInitial
from massprops.dynamics.systems.robot_scene import description_scene
from massprops.dynamics.systems.run import simulate_system

PLANAR = """<mujoco>
  <option timestep="2e-5" integrator="RK4" gravity="0 0 -9.81"><flag contact="disable"/></option>
  <compiler angle="degree"/>
  <worldbody>
    <body name="torso" pos="0 0 1" euler="0 10 0">
      <joint name="rootx" type="slide" axis="1 0 0" damping="0.3"/>
      <joint name="rootz" type="slide" axis="0 0 1" stiffness="40" springref="0.05"/>
      <joint name="rooty" type="hinge" axis="0 1 0" pos="0.05 0 0.02" damping="0.1"/>
      <inertial pos="0.02 0 0.01" mass="2" diaginertia="0.02 0.03 0.04"/>
      <body name="thigh" pos="0.2 0 -0.1">
        <joint name="hip" axis="0 1 0" stiffness="5" springref="20"/>
        <inertial pos="0.05 0 -0.1" mass="0.7" diaginertia="0.004 0.005 0.002"/>
      </body>
      <body name="arm" pos="-0.1 0.1 0">
        <joint name="ax" axis="1 0 0"/><joint name="ay" axis="0 1 0"/>
        <joint name="az" axis="0 0 1" damping="0.02"/>
        <inertial pos="0.08 0.03 -0.05" mass="0.4" fullinertia="0.002 0.003 0.0025 1e-4 0 0"/>
      </body>
    </body>
  </worldbody>
</mujoco>"""

NAMES = ("rootx", "rootz", "rooty", "hip", "ax", "ay", "az")


def test_stages_keep_the_written_joints(tmp_path):
    (tmp_path / "p.xml").write_text(PLANAR)
    desc = describe(tmp_path / "p.xml")
    assert [j.name for j in desc.joints] == list(NAMES)
    masses = {b.name: b.mass for b in desc.bodies}
    assert masses["torso.rootx"] == masses["torso.rootz"] == 0.0
    assert masses["torso"] == 2.0 and masses["arm"] == 0.4
    damping = {j.name: j.damping for j in desc.joints}
    assert damping["rootx"] == 0.3 and damping["az"] == 0.02


@pytest.mark.slow
def test_stages_move_as_mujoco_moves_them(tmp_path):
    mujoco = pytest.importorskip("mujoco")
    (tmp_path / "p.xml").write_text(PLANAR)
    model = mujoco.MjModel.from_xml_string(PLANAR)
    data = mujoco.MjData(model)
    rates = np.random.default_rng(7).uniform(-1, 1, model.nv)
    data.qvel[:] = rates
    duration = 0.3
    scene = description_scene(tmp_path / "p.xml", duration=duration)
    scene = dataclasses.replace(
        scene, initial=SystemInitial({}, {n: (rates[model.joint(n).dofadr[0]],)
                                          for n in NAMES}, {}),
        time=dataclasses.replace(scene.time, rtol=1e-10))
    final = simulate_system(scene, estimate=False).as_dict()["final"]["joints"]
    for _ in range(round(duration / model.opt.timestep)):
        mujoco.mj_step(model, data)
    for n in NAMES:
        # MuJoCo's RK4 at 2e-5 s against the adaptive run at rtol 1e-10: measured within 1e-10
        assert final[n]["coordinates"][0] == pytest.approx(
            data.qpos[model.joint(n).qposadr[0]], abs=1e-8), n



REF = """<mujoco>
  <option timestep="2e-5" integrator="RK4"><flag contact="disable"/></option>
  <worldbody>
    <body name="arm" pos="0 0 1">
      <joint name="h" axis="0 1 0" ref="30" springref="10" stiffness="3" damping="0.05"/>
      <inertial pos="0.2 0 0" mass="0.5" diaginertia="0.001 0.004 0.004"/>
      <body name="slider" pos="0.3 0 0">
        <joint name="s" type="slide" axis="1 0 0" ref="0.1" stiffness="40"/>
        <inertial pos="0.05 0 0" mass="0.2" diaginertia="0.0005 0.0005 0.0005"/>
      </body>
    </body>
  </worldbody>
</mujoco>"""


@pytest.mark.slow
def test_ref_counts_coordinates_from_the_written_pose(tmp_path, run):
    """MuJoCo starts at qpos = ref (the pose as written) and its springs pull towards springref
    (h: 10° while written at 30°; s: 0 while written at 0.1): here the coordinates are MuJoCo's
    minus ref, and the motion is MuJoCo's."""
    mujoco = pytest.importorskip("mujoco")
    (tmp_path / "r.xml").write_text(REF)
    result = run("simulate", tmp_path / "r.xml", "--duration", "0.3", "--json")
    assert result.exit_code == 0, result.stderr
    assert "have a ref" in result.stderr
    final = json.loads(result.stdout)["final"]["joints"]
    model = mujoco.MjModel.from_xml_string(REF)
    data = mujoco.MjData(model)
    for _ in range(round(0.3 / model.opt.timestep)):
        mujoco.mj_step(model, data)
    ref = {"h": np.radians(30.0), "s": 0.1}
    for name in ("h", "s"):
        mine = final[name]["coordinates"][0]
        assert abs(mine) > 1e-2  # the springs moved it
        # measured: within 2e-9 (MuJoCo's RK4 at 2e-5 s against the adaptive run)
        assert mine == pytest.approx(data.qpos[model.joint(name).qposadr[0]] - ref[name],
                                     abs=1e-7), name


REPLICATE = """<mujoco>
  <option timestep="2e-5" integrator="RK4"><flag contact="disable"/></option>
  <worldbody>
    <replicate count="3" offset="0.3 0 0" euler="0 0 20" sep="-">
      <body name="pend" pos="0 0.1 1" euler="0 15 0">
        <joint name="h" axis="1 0 0" damping="0.01"/>
        <inertial pos="0 0.05 -0.2" mass="0.4" diaginertia="0.003 0.003 0.001"/>
      </body>
    </replicate>
  </worldbody>
</mujoco>"""


@pytest.mark.slow
def test_replicated_bodies_move_as_mujoco_moves_them(tmp_path, run):
    """<replicate>: each copy placed by the previous one's pose and offset/euler, names suffixed
    (pend-0, h-0, ...), as MuJoCo expands it."""
    mujoco = pytest.importorskip("mujoco")
    (tmp_path / "r.xml").write_text(REPLICATE)
    result = run("simulate", tmp_path / "r.xml", "--duration", "0.3", "--json")
    assert result.exit_code == 0, result.stderr
    out = json.loads(result.stdout)["final"]
    model = mujoco.MjModel.from_xml_string(REPLICATE)
    data = mujoco.MjData(model)
    for _ in range(round(0.3 / model.opt.timestep)):
        mujoco.mj_step(model, data)
    for i in range(3):
        mine = out["joints"][f"h-{i}"]["coordinates"][0]
        assert abs(mine) > 1e-2
        assert mine == pytest.approx(data.qpos[model.joint(f"h-{i}").qposadr[0]], abs=1e-7)
        assert out["bodies"][f"pend-{i}"]["position"] == pytest.approx(
            data.xipos[model.body(f"pend-{i}").id], abs=1e-7)


SITE_LOOP = """<mujoco>
  <worldbody>
    <body name="crank">
      <joint name="A" axis="0 1 0"/>
      <inertial pos="0.1 0 0" mass="1" diaginertia="0.001 0.004 0.004"/>
      <body name="coupler" pos="0.2 0 0">
        <joint name="B" axis="0 1 0"/>
        <inertial pos="0.2 0 0.05" mass="1" diaginertia="0.002 0.01 0.01"/>
        <site name="s1" pos="0.3 0 0.2"/>
      </body>
    </body>
    <body name="rocker" pos="0.5 0 0">
      <joint name="C" axis="0 1 0"/>
      <inertial pos="0 0 0.1" mass="0.5" diaginertia="0.002 0.002 0.0005"/>
      <frame pos="0 0 0.1"><site name="s2" pos="0 0 0.1"/></frame>
    </body>
  </worldbody>
  <equality>{connect}</equality>
</mujoco>"""


@pytest.mark.slow
def test_site_connect_is_the_body_connect_at_the_sites(tmp_path, run):
    """<connect site1 site2> with the sites meeting as written is <connect body1 body2 anchor>
    with the anchor at site1 (in body1's frame): one mechanism, one motion. Sites apart as
    written are refused in one line."""
    out = {}
    for name, connect in (("sites", '<connect site1="s1" site2="s2"/>'),
                          ("bodies", '<connect body1="coupler" body2="rocker" '
                                     'anchor="0.3 0 0.2"/>')):
        (tmp_path / f"{name}.xml").write_text(SITE_LOOP.format(connect=connect))
        result = run("simulate", tmp_path / f"{name}.xml", "--duration", "0.3", "--json")
        assert result.exit_code == 0, result.stderr
        out[name] = json.loads(result.stdout)
    assert out["sites"]["diagnostics"]["degrees_of_freedom"] == 1
    for name in "ABC":
        mine = out["sites"]["final"]["joints"][name]["coordinates"][0]
        assert abs(mine) > 1e-3
        assert mine == pytest.approx(out["bodies"]["final"]["joints"][name]["coordinates"][0],
                                     abs=1e-12)
    (tmp_path / "apart.xml").write_text(SITE_LOOP.format(
        connect='<connect site1="s1" site2="s2"/>').replace('pos="0 0 0.1"/></frame>',
                                                            'pos="0 0 0.15"/></frame>'))
    result = run("simulate", tmp_path / "apart.xml", "--duration", "0")
    assert result.exit_code == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "apart.xml:18" in lines[0] and "0.05 m apart" in lines[0], \
        result.stderr


def test_an_attached_first_body_does_not_make_the_mechanism_its_file(tmp_path, run):
    """The first body comes from <attach>: the mechanism is still read from the main file
    (where <attach> is refused in one line), never from the attached file alone."""
    (tmp_path / "arm.xml").write_text(
        '<mujoco><worldbody><body name="arm"><joint name="h"/>'
        '<inertial pos="0.1 0 0" mass="1" diaginertia="0.01 0.01 0.01"/></body></worldbody>'
        '</mujoco>')
    for first in ("attach", "body"):
        attach = '<attach model="arm" body="arm" prefix="a_"/>'
        own = ('<body name="base"><joint name="k" axis="0 1 0"/><inertial pos="0 0 -0.1" '
               'mass="2" diaginertia="0.02 0.02 0.02"/></body>')
        parts = (attach, own) if first == "attach" else (own, attach)
        (tmp_path / "main.xml").write_text(
            '<mujoco><asset><model name="arm" file="arm.xml"/></asset><worldbody>\n'
            + "\n".join(parts) + '\n</worldbody></mujoco>')
        result = run("simulate", tmp_path / "main.xml", "--duration", "0")
        assert result.exit_code == 1
        lines = result.stderr.strip().splitlines()
        line = 2 if first == "attach" else 3
        assert len(lines) == 1 and f"main.xml:{line}: <attach>" in lines[0], result.stderr


WELD = """<mujoco>
  <worldbody>
    <body name="upper" pos="0 0 1">
      <joint name="A" axis="0 1 0"/>
      <inertial pos="0.2 0 0" mass="1" diaginertia="0.001 0.01 0.01"/>
      <body name="lower" pos="0.4 0 0">
        {joint}
        <inertial pos="0.1 0 -0.1" mass="0.5" diaginertia="0.002 0.003 0.002"/>
      </body>
    </body>
  </worldbody>
  <equality>{weld}</equality>
</mujoco>"""


@pytest.mark.slow
def test_weld_holds_the_written_pose_like_a_rigid_body(tmp_path, run):
    """<weld body1 body2> across a hinge holds it at the written pose: the pendulum swings as
    the same bodies welded in the tree (no hinge); relpose and torquescale are refused."""
    out = {}
    for name, joint, weld in (("weld", '<joint name="B" axis="0 1 0"/>',
                               '<weld name="W" body1="lower" body2="upper" anchor="0.4 0 0"/>'),
                              ("rigid", "", "")):
        (tmp_path / f"{name}.xml").write_text(WELD.format(joint=joint, weld=weld))
        result = run("simulate", tmp_path / f"{name}.xml", "--duration", "0.4", "--json")
        assert result.exit_code == 0, result.stderr
        out[name] = json.loads(result.stdout)
    assert out["weld"]["diagnostics"]["degrees_of_freedom"] == 1
    a = out["weld"]["final"]["joints"]["A"]["coordinates"][0]
    assert abs(a) > 1e-2
    assert a == pytest.approx(out["rigid"]["final"]["joints"]["A"]["coordinates"][0], abs=1e-9)
    assert abs(out["weld"]["final"]["joints"]["B"]["coordinates"][0]) < 1e-9
    for bad, needle in (('relpose="0 0 0 1 0 0 0"', "relpose"),
                        ('torquescale="0.5"', "torquescale")):
        (tmp_path / "bad.xml").write_text(WELD.format(
            joint='<joint name="B" axis="0 1 0"/>',
            weld=f'<weld body1="lower" body2="upper" {bad}/>'))
        result = run("simulate", tmp_path / "bad.xml", "--duration", "0")
        assert result.exit_code == 1 and needle in result.stderr
        assert len(result.stderr.strip().splitlines()) == 1, result.stderr
