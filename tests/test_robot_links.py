"""Every link a number or a reason: visual geometry for links without collision geometry,
stated-only links, repairs applied per mesh (--fill-holes), and xacro descriptions with
arguments."""

from __future__ import annotations

import pytest
from conftest import CUBE_QUADS, box_vf, json_lines

from massprops.robot.analyze import analyze_model

OPEN_QUADS = CUBE_QUADS[1:]  # the unit cube without its bottom face: one hole, 1/6 of the area


def _urdf(tmp_path):
    box_vf(tmp_path / "closed.vf", size=(0.1, 0.2, 0.3))
    box_vf(tmp_path / "open.vf", size=(0.1, 0.2, 0.3), faces=OPEN_QUADS)
    box_vf(tmp_path / "big.vf", size=(1.0, 1.0, 1.0))
    p = tmp_path / "r.urdf"
    inertial = ('<inertial><mass value="{}"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" '
                'izz="1"/></inertial>')
    p.write_text(
        '<robot name="r">\n'
        '<link name="seen">' + inertial.format(6.0) + '<visual><geometry><mesh filename='
        '"closed.vf"/></geometry></visual></link>\n'
        '<link name="both">' + inertial.format(6.0) + '<visual><geometry><mesh filename='
        '"big.vf"/></geometry></visual><collision><geometry><mesh filename="closed.vf"/>'
        '</geometry></collision></link>\n'
        '<link name="open">' + inertial.format(6.0) + '<collision><geometry><mesh filename='
        '"open.vf"/></geometry></collision></link>\n'
        '<link name="sensor">' + inertial.format(0.5) + '</link>\n'
        '<link name="frame"/>\n'
        '</robot>\n')
    return p


def test_visual_only_link_is_computed_from_its_visual_with_a_note(tmp_path):
    r = {x.name: x for x in analyze_model(_urdf(tmp_path), allow_open=True).links}
    seen = r["seen"]
    assert seen.status == "computed" and seen.link.source == "visual"
    assert any("source: visual" in w for w in seen.warnings)
    assert seen.computed.center_of_mass == pytest.approx([0.05, 0.1, 0.15], rel=1e-15)
    # a link with both keeps its collision geometry (the 0.1 x 0.2 x 0.3 box, not the 1 m cube)
    assert r["both"].link.source == "collision"
    assert r["both"].computed.volume == pytest.approx(0.006, rel=1e-14)


def test_from_forces_one_source(tmp_path):
    r = {x.name: x for x in analyze_model(_urdf(tmp_path), source="collision",
                                          allow_open=True).links}
    assert r["seen"].status == "stated-only"
    r = {x.name: x for x in analyze_model(_urdf(tmp_path), source="visual").links}
    assert r["both"].computed.volume == pytest.approx(1.0, rel=1e-14)


def test_stated_only_and_frame_links_are_not_errors(tmp_path):
    report = analyze_model(_urdf(tmp_path), allow_open=True)
    r = {x.name: x for x in report.links}
    assert r["sensor"].status == "stated-only" and not r["sensor"].error
    assert r["frame"].status == "skipped" and not r["frame"].error


def test_fill_holes_per_mesh_reported_per_link(run, tmp_path):
    """The open box (bottom missing: 1/6 of its area) is refused, then with --fill-holes
    --max-hole 0.5 capped into the closed box: COM at the box's centre, J = m/12 (b²+c², ...)."""
    p = _urdf(tmp_path)
    res = run("model", "--json", p)
    assert res.exit_code == 1
    line = next(x for x in res.stderr.splitlines() if "'open'" in x)
    assert "--fill-holes" in line and "r.urdf:4" in line
    res = run("model", "--json", "--fill-holes", "--max-hole", "0.5", p)
    assert res.exit_code == 0, res.stderr
    rows = {d["link"]: d for d in json_lines(res.stdout)}
    d = rows["open"]
    assert d["status"] == "computed" and "fill_holes" in d["repairs"]["open.vf"]
    assert d["computed"]["center_of_mass"] == pytest.approx([0.05, 0.1, 0.15], rel=1e-14)
    j = d["computed"]["inertia"]
    m, a, b, c = 6.0, 0.1, 0.2, 0.3
    assert [j[0][0], j[1][1], j[2][2]] == pytest.approx(
        [m * (b * b + c * c) / 12, m * (a * a + c * c) / 12, m * (a * a + b * b) / 12],
        rel=1e-13)
    assert rows["seen"]["source"] == "visual"   # closed: its record says 0 holes, as inspect's
    assert rows["seen"]["repairs"]["closed.vf"]["fill_holes"]["holes"] == 0
    assert rows["sensor"]["status"] == "stated-only"


XACRO = """<?xml version="1.0"?>
<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="arm">
  <xacro:arg name="length" default="0.5"/>
  <xacro:property name="mass" value="2.0"/>
  <xacro:macro name="segment" params="name length">
    <link name="${name}">
      <inertial><mass value="${mass}"/>
        <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial>
      <collision><origin xyz="0 0 ${length/2}"/>
        <geometry><box size="0.1 0.1 ${length}"/></geometry></collision>
    </link>
  </xacro:macro>
  <xacro:segment name="upper" length="$(arg length)"/>
  <xacro:segment name="lower" length="${2*$(arg length)}"/>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="lower"/></joint>
</robot>
"""


def test_xacro_with_arguments(run, tmp_path):
    """Two box segments from one macro, lengths from the argument: the COM of each at half its
    length, J_xx = m (0.1² + L²) / 12."""
    pytest.importorskip("xacro")
    p = tmp_path / "arm.urdf.xacro"
    p.write_text(XACRO)
    for args, length in (((), 0.5), (("--xacro-arg", "length:=0.25"), 0.25)):
        res = run("model", "--json", *args, p)
        assert res.exit_code == 0, res.stderr
        rows = {d["link"]: d for d in json_lines(res.stdout)}
        for name, size in (("upper", length), ("lower", 2 * length)):
            c = rows[name]["computed"]
            assert c["center_of_mass"] == pytest.approx([0, 0, size / 2], abs=1e-15)
            assert c["inertia"][0][0] == pytest.approx(2.0 * (0.01 + size**2) / 12, rel=1e-14)


def test_xacro_errors_say_the_lines_are_the_expanded_files(run, tmp_path):
    pytest.importorskip("xacro")
    p = tmp_path / "bad.urdf.xacro"
    p.write_text(XACRO.replace('<box size="0.1 0.1 ${length}"/>', '<box size="0.1 ${length}"/>'))
    res = run("model", "--json", p)
    assert res.exit_code == 1
    assert "bad.urdf.xacro (expanded by xacro):" in res.stderr and "<box>" in res.stderr
    res = run("model", "--json", "--xacro-arg", "oops", p)
    assert res.exit_code == 2 and "NAME:=VALUE" in res.stderr
    q = tmp_path / "undefined.urdf.xacro"
    q.write_text(XACRO.replace("${mass}", "${nomass}"))
    res = run("model", "--json", q)
    assert res.exit_code == 1 and "xacro failed" in res.stderr and "nomass" in res.stderr


# robosuite's sawyer robot.xml, body right_l0: seven visual meshes, one of them (l0_4.obj) five
# loose flat quads. --fill-holes caps each quad with its own mirror: a closed sheet of zero
# volume. Beside the body's other geometry it adds nothing (MuJoCo gives it ~1e-7 kg of the
# body's 5.46); alone it is still refused.
def _sheets_obj() -> str:
    out = []
    for k in range(5):
        x = 0.3 + 0.01 * k
        out += [f"v {x} 0 0", f"v {x} 0.004 0", f"v {x} 0 0.004", f"v {x} 0.004 0.004"]
        out += [f"f {4 * k + 1} {4 * k + 2} {4 * k + 3}", f"f {4 * k + 2} {4 * k + 4} {4 * k + 3}"]
    return "\n".join(out) + "\n"


def _mjcf_with_sheet(tmp_path, box: bool):
    (tmp_path / "sheets.obj").write_text(_sheets_obj())
    geom = '<geom type="box" size="0.05 0.1 0.15" pos="0 0 0.2"/>' if box else ""
    p = tmp_path / "r.xml"
    p.write_text('<mujoco><asset><mesh name="s" file="sheets.obj"/></asset><worldbody>'
                 f'<body name="l0">{geom}<geom type="mesh" mesh="s"/></body>'
                 '</worldbody></mujoco>')
    return p


def test_a_sheet_beside_other_geometry_adds_nothing(tmp_path):
    from massprops.repair import RepairOptions

    repairs = RepairOptions(fill_holes=True, max_hole=0.5)
    r, = analyze_model(_mjcf_with_sheet(tmp_path, box=True), repairs=repairs).links
    assert r.status == "computed"
    # the box alone, MuJoCo's default density 1000 kg/m³: 0.1 x 0.2 x 0.3 m
    m = 1000 * 0.1 * 0.2 * 0.3
    assert r.computed.mass == pytest.approx(m, rel=1e-12)
    assert r.computed.center_of_mass == pytest.approx([0, 0, 0.2], abs=1e-12)
    assert r.computed.principal_moments == pytest.approx(
        sorted(m / 12 * x for x in (0.2**2 + 0.3**2, 0.1**2 + 0.3**2, 0.1**2 + 0.2**2)),
        rel=1e-12)
    said = [w for w in r.warnings if "encloses no volume" in w]
    assert len(said) == 1 and said[0].startswith("sheets.obj: ")
    alone, = analyze_model(_mjcf_with_sheet(tmp_path, box=False), repairs=repairs).links
    assert alone.status == "skipped" and alone.error and "encloses no volume" in alone.reason
