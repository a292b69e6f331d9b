"""Joint couplings (URDF/SDF <mimic>, MJCF joint and fixed-tendon equalities): a linear relation
Σ c_i q_i = constant between joints' coordinates, enforced as a constraint row like a loop's.

Truth is independent of the program: a gear pair driven by a constant torque has the closed form
θ(t) = ½ τ / (I₁ + r² I₂) t² (the coupled pair is one rotor of that inertia); two identical
pendulums on one pivot made to move as one (mimic, multiplier 1) are one pendulum, whose run
without the coupling is the reference; the bearings carry no torque about their axes (the
coupling's torque is a motor's, not a reaction).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from massprops.dynamics.compiled.systems_step import project, rhs, workspace
from massprops.dynamics.systems import tree as tr
from massprops.dynamics.systems.robot_scene import load_any_system
from massprops.dynamics.systems.run import prepare, simulate_system
from massprops.errors import RobotModelError

ROOT = Path(__file__).resolve().parents[1]


def _link(name: str, mass: float, izz: float, at=(0.0, 0.0, 0.0)) -> str:
    x, y, z = at
    return (f'<link name="{name}"><inertial><origin xyz="{x} {y} {z}"/><mass value="{mass}"/>'
            f'<inertia ixx="{izz / 2}" iyy="{izz / 2}" izz="{izz}" ixy="0" ixz="0" iyz="0"/>'
            "</inertial></link>")


def _gears(multiplier: float, offset: float, extra: str = "") -> str:
    """Two wheels on vertical axles (gravity along them: no torque), the second mimicking the
    first: q2 = multiplier q1 + offset."""
    return f"""<robot name="gears">
  <link name="base"/>
  {_link("wheel1", 1.0, 0.2)}
  {_link("wheel2", 0.5, 0.05)}
  <joint name="lead" type="continuous"><parent link="base"/><child link="wheel1"/>
    <origin xyz="0 0 0"/><axis xyz="0 0 1"/></joint>
  <joint name="follow" type="continuous"><parent link="base"/><child link="wheel2"/>
    <origin xyz="1 0 0"/><axis xyz="0 0 1"/>
    <mimic joint="lead" multiplier="{multiplier}" offset="{offset}"/>{extra}</joint>
</robot>"""


def _scene(tmp_path: Path, robot: str, body: str = "", name: str = "r.urdf",
           duration: float = 2.0, positions: str = "{lead: 0.0}") -> Path:
    (tmp_path / name).write_text(robot)
    forces = "[{type: gravity, g: [0, 0, -9.81]}" + (
        f", {{type: torque, body: {body}, vector: [0, 0, 0.7], frame: world}}]" if body else "]")
    scene = tmp_path / "scene.yaml"
    scene.write_text(f"model: {name}\ninitial: {{positions: {positions}}}\nforces: {forces}\n"
                     f"time: {{duration: {duration}}}\n")
    return scene


@pytest.mark.parametrize("multiplier", [-2.0, 0.5])
def test_a_driven_gear_pair_turns_as_one_rotor(tmp_path, multiplier):
    """θ₁(t) = ½ α t², α = τ / (I₁ + r² I₂); θ₂ = r θ₁ + offset throughout (the zero pose
    breaks the offset: the start moves the follower only); no axial bearing torque (the
    coupling drives, the bearings only hold)."""
    scene = load_any_system(_scene(tmp_path, _gears(multiplier, 0.3), body="wheel1",
                                   positions="{}"))
    result = simulate_system(scene, rtol=1e-12)
    s = result.samples
    t = s.t
    alpha = 0.7 / (0.2 + multiplier ** 2 * 0.05)
    lead, follow = (s.coordinates[k][:, 0] for k in range(2))
    assert np.abs(lead - 0.5 * alpha * t ** 2).max() <= 1e-10 * 0.5 * alpha * t[-1] ** 2
    assert np.abs(follow - multiplier * lead - 0.3).max() <= 1e-12 and lead[0] == 0.0
    for k, weight in ((0, 1.0 * 9.81), (1, 0.5 * 9.81)):
        torque, force = s.torque[:, k], s.force[:, k]
        assert np.abs(torque).max() <= 1e-9 * 0.7
        assert np.abs(force - [0.0, 0.0, weight]).max() <= 1e-9 * weight
    assert result.diagnostics["degrees_of_freedom"] == 1
    assert result.diagnostics["constraint_residual"]["position"] <= 1e-12


def _pendulums(coupled: bool) -> str:
    arm = '<origin xyz="0 0 0"/><axis xyz="0 1 0"/>'
    second = f"""{_link("rod2", 1.5, 0.02, at=(0.4, 0.0, 0.0))}
  <joint name="follow" type="continuous"><parent link="base"/><child link="rod2"/>{arm}
    {'<mimic joint="lead"/>' if coupled else ''}</joint>""" if coupled else ""
    return f"""<robot name="pendulums">
  <link name="base"/>
  {_link("rod1", 1.5, 0.02, at=(0.4, 0.0, 0.0))}
  <joint name="lead" type="continuous"><parent link="base"/><child link="rod1"/>{arm}</joint>
  {second}
</robot>"""


def test_two_pendulums_made_one_swing_as_one(tmp_path):
    """Two identical pendulums on one pivot, one mimicking the other: the single pendulum's
    motion, and each bearing the single one's reaction force."""
    one = simulate_system(load_any_system(_scene(tmp_path, _pendulums(False), name="one.urdf",
                                                 duration=1.5)), rtol=1e-12).samples
    two = simulate_system(load_any_system(_scene(tmp_path, _pendulums(True), name="two.urdf",
                                                 duration=1.5)), rtol=1e-12).samples
    assert np.abs(one.coordinates[0][:, 0]).max() > 1.0  # it swings (horizontal start)
    for k in range(2):
        assert np.abs(two.coordinates[k] - one.coordinates[0]).max() <= 1e-9
        assert np.abs(two.force[:, k] - one.force[:, 0]).max() <= 1e-8 * 1.5 * 9.81
        assert np.abs(two.torque[:, k, 1]).max() <= 1e-8  # none about the hinge


def test_compiled_right_hand_side_and_projection_with_a_coupling_equal_numpy(tmp_path):
    scene = load_any_system(_scene(tmp_path, _gears(-2.0, 0.3), body="wheel1"))
    system, y0, _ = prepare(scene)
    assert system.m == 1
    ws = workspace(system.program)
    rng = np.random.default_rng(3)
    for _ in range(4):
        y = y0 + 0.1 * rng.standard_normal(y0.size)
        sol = system.solve(0.5, y, check=False, full=False)
        want = np.concatenate([tr.qdot(system.tree, y[:system.nq], y[system.nq:]), sol.udot])
        got = np.zeros_like(y)
        assert rhs(system.program, ws, 0.5, y, got, -1) == 0
        assert np.abs(got - want).max() <= 1e-12 * max(1.0, float(np.abs(want).max()))
        want_y = system.project(y)[0]
        got_y, moved = y.copy(), np.zeros(3)
        assert project(system.program, ws, got_y, 12, moved) == 0
        assert np.abs(got_y - want_y).max() <= 1e-12


MJCF = """<mujoco>
  <option gravity="0 0 -9.81"/>
  <worldbody>
    <body name="wheel1"><joint name="lead" type="hinge" axis="0 0 1"/>
      <inertial pos="0 0 0" mass="1" diaginertia="0.1 0.1 0.2"/></body>
    <body name="wheel2" pos="1 0 0"><joint name="follow" type="hinge" axis="0 0 1" ref="{ref}"/>
      <inertial pos="0 0 0" mass="0.5" diaginertia="0.025 0.025 0.05"/></body>
  </worldbody>
  <tendon><fixed name="t1"><joint joint="lead" coef="1"/></fixed>
          <fixed name="t2"><joint joint="follow" coef="0.5"/></fixed></tendon>
  <equality>{equality}</equality>
</mujoco>"""


@pytest.mark.parametrize("equality, ratio", [
    ('<joint joint1="follow" joint2="lead" polycoef="0.3 -2 0 0 0"/>', -2.0),
    ('<tendon tendon1="t2" tendon2="t1" polycoef="0.15 -1 0 0 0"/>', -2.0),
])
def test_mjcf_joint_and_tendon_equalities_are_gears(tmp_path, equality, ratio):
    """MuJoCo's y − y0 = a0 + a1 (x − x0) about qpos0 (ref): ``follow`` counts from its ref,
    so the closed form holds in massprops' coordinates whatever the ref."""
    robot = MJCF.format(equality=equality, ref="0.4")
    scene = load_any_system(_scene(tmp_path, robot, body="wheel1", name="g.xml"))
    s = simulate_system(scene, rtol=1e-12).samples
    alpha = 0.7 / (0.2 + ratio ** 2 * 0.05)
    lead, follow = s.coordinates[0][:, 0], s.coordinates[1][:, 0]
    assert np.abs(lead - 0.5 * alpha * s.t ** 2).max() <= 1e-10 * 0.5 * alpha * s.t[-1] ** 2
    assert np.abs(follow - ratio * lead - 0.3).max() <= 1e-12


@pytest.mark.parametrize("robot, error, words", [
    (_gears(1.0, 0.0).replace('joint="lead"', 'joint="leed"'), RobotModelError,
     ["'leed'", "check the spelling"]),
    (_gears(1.0, 0.0).replace('<mimic joint="lead"', '<mimic'), RobotModelError,
     ['needs joint="..."']),
    (MJCF.format(equality='<joint joint1="follow" joint2="lead" polycoef="0 1 0.5 0 0"/>',
                 ref="0"), RobotModelError, ["not linear"]),
    (MJCF.format(equality='<tendon tendon1="t9" tendon2="t1"/>', ref="0"), RobotModelError,
     ["'t9'"]),
])
def test_a_coupling_that_cannot_be_is_refused_at_its_line(tmp_path, robot, error, words):
    name = "r.xml" if robot.startswith("<mujoco") else "r.urdf"
    with pytest.raises(error) as info:
        load_any_system(_scene(tmp_path, robot, name=name))
    message = str(info.value)
    assert all(w in message for w in words) and f"{name}:" in message


def test_cli_simulates_a_mimic_robot_and_says_nothing_of_mimic(tmp_path):
    (tmp_path / "g.urdf").write_text(_gears(-1.0, 0.0))
    out = subprocess.run([sys.executable, "-m", "massprops", "simulate", "g.urdf",
                          "--duration", "0.5", "--json"], cwd=tmp_path, capture_output=True,
                         text=True, timeout=300, env={"PYTHONPATH": str(ROOT),
                                                      "PATH": "/usr/bin:/bin"})
    assert out.returncode == 0, out.stderr
    assert "mimic" not in out.stderr and "Traceback" not in out.stderr
    final = json.loads(out.stdout)["final"]["joints"]
    assert final["follow"]["coordinates"][0] == pytest.approx(
        -final["lead"]["coordinates"][0], abs=1e-12)


def test_a_fixed_joint_in_a_coupling_counts_as_zero(tmp_path):
    """A reduced model welds joints that mimic tags still name: a fixed leader's coordinate is
    0, so its follower is held at the offset; a fixed follower has nothing to move: the
    coupling is left out, said in one warning line."""
    held = _gears(-2.0, 0.3).replace('name="lead" type="continuous"', 'name="lead" type="fixed"')
    scene = load_any_system(_scene(tmp_path, held, body="wheel2", positions="{}"))
    follow = simulate_system(scene, rtol=1e-12).samples.coordinates[0][:, 0]
    assert np.abs(follow - 0.3).max() <= 1e-13
    welded = _gears(-2.0, 0.3).replace('name="follow" type="continuous"',
                                       'name="follow" type="fixed"')
    scene = load_any_system(_scene(tmp_path, welded, body="wheel1", positions="{}"))
    said = [w for w in scene.warnings if "left out" in w]
    assert len(said) == 1 and "'follow'" not in said[0] and "follow" in said[0]
    samples = simulate_system(scene, rtol=1e-12).samples
    lead, t = samples.coordinates[0][:, 0], samples.t
    assert np.abs(lead - 0.5 * (0.7 / 0.2) * t ** 2).max() <= 1e-9  # wheel1 alone


def test_an_mjcf_joint_equality_without_joint2_holds_the_joint(tmp_path):
    """<joint joint1> alone: y − y0 = a0, the joint held at a0 from its ref; the other wheel then
    turns alone under the torque (α = τ / I₁)."""
    robot = MJCF.format(equality='<joint joint1="follow" polycoef="0.3 0 0 0 0"/>', ref="0.4")
    scene = load_any_system(_scene(tmp_path, robot, body="wheel1", name="h.xml"))
    s = simulate_system(scene, rtol=1e-12).samples
    lead, follow = s.coordinates[0][:, 0], s.coordinates[1][:, 0]
    assert np.abs(follow - 0.3).max() <= 1e-13
    assert np.abs(lead - 0.5 * (0.7 / 0.2) * s.t ** 2).max() <= 1e-10 * 0.5 * 3.5 * s.t[-1] ** 2


def test_a_mimic_joint_has_no_motor_its_leader_holds_both(tmp_path):
    """Holding forces (static torques) of two pendulums, one mimicking the other: the mimic
    joint has no motor (0), the leader's holds both, twice the single pendulum's own (whose
    closed form is m g x at the horizontal start)."""
    results = []
    for name, coupled in (("one.urdf", False), ("two.urdf", True)):
        (tmp_path / name).write_text(_pendulums(coupled))
        results.append(simulate_system(load_any_system(tmp_path / name, duration=0.0)))
    one, two = results
    single = one.holding[0][0]
    assert abs(abs(single) - 1.5 * 9.81 * 0.4) <= 1e-12 * 6
    assert two.holding[0][0] == pytest.approx(2 * single, rel=1e-13)
    assert abs(two.holding[1][0]) <= 1e-13
