"""What `simulate` does with a description's stated inertials that no body can have, and with an
MJCF body whose mass MuJoCo takes from geoms massprops cannot read: one line naming the file,
the link and the problem; a point mass (zero inertia, or round-off below zero) is accepted."""

from __future__ import annotations

import json

import pytest

ARM = ('<robot name="r"><link name="base"/>\n'
       '<link name="arm"><inertial><origin xyz="0.3 0 0"/><mass value="{m}"/><inertia '
       'ixx="{ixx}" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="{izz}"/></inertial></link>\n'
       '<joint name="j" type="continuous"><parent link="base"/><child link="arm"/>'
       '<axis xyz="0 1 0"/></joint>\n'
       '<link name="tip"><inertial><mass value="0.5"/><inertia ixx="-5e-20" ixy="0" ixz="0" '
       'iyy="-5e-20" iyz="0" izz="0"/></inertial></link>\n'
       '<joint name="k" type="fixed"><parent link="arm"/><child link="tip"/>'
       '<origin xyz="0.6 0 0"/></joint></robot>')


@pytest.mark.parametrize("m, ixx, izz, needle", [
    ("1", "-0.01", "0.01", "negative principal moment"),
    ("-1", "0.01", "0.01", "negative or non-finite mass"),
])
def test_impossible_inertials_are_refused_in_one_line(tmp_path, run, m, ixx, izz, needle):
    (tmp_path / "r.urdf").write_text(ARM.format(m=m, ixx=ixx, izz=izz))
    result = run("simulate", tmp_path / "r.urdf", "--duration", "0")
    assert result.exit_code == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "r.urdf:2: link 'arm'" in lines[0] and needle in lines[0], \
        result.stderr


def test_triangle_breaking_inertia_is_said_and_point_masses_are_taken(tmp_path, run):
    """izz 0.05 > ixx + iyy = 0.02: warned, simulated; the tip's -5e-20 is a point mass's
    round-off (iCub writes such), no warning, no NaN. A link's negative moment that its welded
    neighbour outweighs (TIAGo's antennas on its base) is said, and the body simulated."""
    (tmp_path / "r.urdf").write_text(ARM.format(m="1", ixx="0.01", izz="0.05"))
    result = run("simulate", tmp_path / "r.urdf", "--duration", "0")
    assert result.exit_code == 0, result.stderr
    said = [line for line in result.stderr.splitlines() if "not physically valid" in line]
    assert len(said) == 1 and "'arm'" in said[0] and "'tip'" not in said[0]
    assert "Warning" not in result.stderr and "nan" not in result.stdout.lower()
    # static torque of the lumped arm (1 kg at 0.3 m, 0.5 kg at 0.6 m) about +y under -9.81 z
    (tmp_path / "ok.urdf").write_text(ARM.format(m="1", ixx="0.01", izz="0.01"))
    result = run("simulate", tmp_path / "ok.urdf", "--duration", "0", "--json")
    assert result.exit_code == 0 and "not physically valid" not in result.stderr
    held = json.loads(result.stdout)["final"]["joints"]["j"]["holding"][0]
    assert held == pytest.approx(-9.81 * (1 * 0.3 + 0.5 * 0.6), rel=1e-12)
    outweighed = ARM.format(m="1", ixx="0.01", izz="0.01").replace(
        'ixx="-5e-20" ixy="0" ixz="0" iyy="-5e-20"', 'ixx="-0.001" ixy="0" ixz="0" iyy="0.001"')
    (tmp_path / "w.urdf").write_text(outweighed)
    result = run("simulate", tmp_path / "w.urdf", "--duration", "0")
    assert result.exit_code == 0, result.stderr
    said = [line for line in result.stderr.splitlines() if "not physically valid" in line]
    assert len(said) == 1 and "'tip'" in said[0] and "'arm'" not in said[0]


def test_mjcf_body_with_unreadable_geoms_names_the_geom_not_a_singular_matrix(tmp_path, run):
    (tmp_path / "m.xml").write_text(
        '<mujoco><asset><mesh name="hull" file="missing.stl"/></asset>\n'
        '<worldbody><body name="b"><joint name="h" axis="0 1 0"/>\n'
        '<geom type="mesh" mesh="hull" pos="0.5 0 0"/></body></worldbody></mujoco>')
    result = run("simulate", tmp_path / "m.xml", "--duration", "0")
    assert result.exit_code == 1
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and "m.xml:2: link 'b'" in lines[0] and "missing.stl" in lines[0], \
        result.stderr


def test_mimic_couplings_are_enforced(tmp_path, run):
    """URDF <mimic> and SDF 1.11 <axis><mimic> are constraints (tests/test_systems_couplings.py
    checks the dynamics): after a run under gravity the follower still sits at multiplier ×
    the leader's coordinate (+ offset), and no warning says otherwise."""
    link = ('<link name="{n}"><inertial><origin xyz="0.1 0 0"/><mass value="1"/><inertia '
            'ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/></inertial></link>')
    (tmp_path / "m.urdf").write_text(
        '<robot name="r"><link name="base"/>' + link.format(n="a") + link.format(n="b")
        + '<joint name="ja" type="continuous"><parent link="base"/><child link="a"/>'
        '<axis xyz="0 1 0"/></joint><joint name="jb" type="prismatic"><parent link="base"/>'
        '<child link="b"/><axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" '
        'velocity="1"/><mimic joint="ja" multiplier="0.1" offset="0.05"/></joint></robot>')
    inertial = ('<inertial><pose>0.1 0 0 0 0 0</pose><mass>1</mass><inertia><ixx>0.01</ixx>'
                '<iyy>0.01</iyy><izz>0.01</izz></inertia></inertial>')
    (tmp_path / "m.sdf").write_text(
        f'<sdf version="1.11"><model name="m"><link name="a">{inertial}</link>'
        f'<link name="b">{inertial}</link>'
        '<joint name="ja" type="revolute"><parent>world</parent><child>a</child><axis>'
        '<xyz>0 1 0</xyz></axis></joint><joint name="jb" type="revolute"><parent>world</parent>'
        '<child>b</child><axis><xyz>0 1 0</xyz><mimic joint="ja"><multiplier>2</multiplier>'
        '<reference>0.1</reference></mimic></axis></joint></model></sdf>')
    for name, gain, constant in (("m.urdf", 0.1, 0.05), ("m.sdf", 2.0, -0.2)):
        result = run("simulate", tmp_path / name, "--duration", "0.5", "--json")
        assert result.exit_code == 0, result.stderr
        assert "<mimic>" not in result.stderr
        joints = json.loads(result.stdout)["final"]["joints"]
        ja, jb = joints["ja"]["coordinates"][0], joints["jb"]["coordinates"][0]
        assert abs(ja) > 0.1  # it moved under gravity
        assert jb == pytest.approx(gain * ja + constant, abs=1e-12)


def test_urdf_planar_joint_is_two_shifts_and_a_turn(tmp_path, run):
    """A planar joint normal to y (the x-z plane): e1 = z, e2 = x, the turn about y; a body
    falling from rest under gravity -z: name.x = -g t²/2, the rest stay 0 (gravity has no moment
    about the centre of mass)."""
    (tmp_path / "p.urdf").write_text(
        '<robot name="r"><link name="base"/><link name="slab"><inertial><origin xyz="0.2 0 0.1"/>'
        '<mass value="2"/><inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.015"/>'
        '</inertial></link><joint name="p" type="planar"><parent link="base"/>'
        '<child link="slab"/><origin xyz="0 0 1"/><axis xyz="0 1 0"/></joint></robot>')
    result = run("simulate", tmp_path / "p.urdf", "--duration", "0.5", "--json")
    assert result.exit_code == 0, result.stderr
    out = json.loads(result.stdout)
    assert out["diagnostics"]["degrees_of_freedom"] == 3
    joints = out["final"]["joints"]
    assert joints["p.x"]["coordinates"][0] == pytest.approx(-9.81 * 0.5**2 / 2, rel=1e-9)
    assert abs(joints["p.y"]["coordinates"][0]) < 1e-12
    assert abs(joints["p"]["coordinates"][0]) < 1e-12
