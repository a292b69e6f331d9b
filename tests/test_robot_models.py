"""`massprops model` on the test robots of tests/robots/: every link against a tensor derived by
hand (closed forms, exact fractions, parallel axes written out here), round trips through
``--write``, ``--check`` failing with exit 4, and one line per bad input."""

from __future__ import annotations

import math
import os
import re
import shutil
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from conftest import json_lines

from massprops.robot.analyze import analyze_model

ROBOTS = Path(__file__).resolve().parent / "robots"
ARM = ROBOTS / "arm_description" / "urdf" / "arm.urdf"
BASE = ROBOTS / "base" / "mobile_base.sdf"
GRIPPER = ROBOTS / "gripper" / "gripper.xml"
CONTRACT_KEYS = {"model", "link", "status", "reason", "stated", "computed", "warnings"}


# --- hand-derived truth --------------------------------------------------------------------------
def box_j(m, a, b, c):
    """Solid box of full edges a, b, c about its centre: m/12 (b²+c², a²+c², a²+b²)."""
    return np.diag([m * (b * b + c * c) / 12, m * (a * a + c * c) / 12, m * (a * a + b * b) / 12])


def shift(m, d):
    """m (|d|² I - d dᵀ) for a point mass at d from the reference point."""
    d = np.asarray(d, dtype=float)
    return m * (float(d @ d) * np.eye(3) - np.outer(d, d))


def frac_box(m, a, b, c):
    z = Fraction(0)
    return [[m * (b * b + c * c) / 12, z, z], [z, m * (a * a + c * c) / 12, z],
            [z, z, m * (a * a + b * b) / 12]]


def frac_shift(m, d):
    n = sum(x * x for x in d)
    return [[m * ((n if i == j else 0) - d[i] * d[j]) for j in range(3)] for i in range(3)]


def close(a, b, rtol, scale=None):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    s = scale if scale is not None else max(float(np.max(np.abs(b))), 1e-300)
    return float(np.max(np.abs(a - b))) <= rtol * s


def links_of(path, **kw):
    return {r.name: r for r in analyze_model(path, **kw).links}


# --- the arm (URDF, meshes) ----------------------------------------------------------------------
def test_mesh_scaled_by_0001_and_turned_90_degrees():
    """base_link: a 100×200×400 mm box (corner at the origin) scaled by 0.001, turned +90° about
    z and moved by (0.1, 0.2, 0.3): Rz90 (x, y, z) = (-y, x, z), so the COM (0.05, 0.1, 0.2)
    lands at (0, 0.25, 0.5) and the box's x and y moments swap."""
    r = links_of(ARM)["base_link"]
    c = r.computed
    assert c.mass == 5.0
    assert close(c.center_of_mass, [0.0, 0.25, 0.5], 1e-15, scale=1.0)
    turned = box_j(5.0, 0.2, 0.1, 0.4)  # edges along link x, y, z after the turn
    assert close(c.inertia, turned, 1e-14)
    assert c.volume == pytest.approx(0.1 * 0.2 * 0.4, rel=1e-14)


def test_link_of_two_offset_rotated_meshes_against_exact_fractions():
    """upper_arm: cube A scaled to 0.1×0.1×0.3 at the origin; cube B scaled to 0.2×0.1×0.1,
    turned +90° about x ((x, y, z) -> (x, -z, y): it spans x 0..0.2, y -0.1..0, z 0.3..0.4)
    and moved up 0.3. Stated mass 2.5 over the volume 0.005: density 500."""
    f = Fraction
    ma, mb = f(3, 2), f(1)                          # 500 × 0.003, 500 × 0.002
    ca, cb = [f(1, 20), f(1, 20), f(3, 20)], [f(1, 10), f(-1, 20), f(7, 20)]
    com = [(ma * x + mb * y) / (ma + mb) for x, y in zip(ca, cb)]
    ja = frac_box(ma, f(1, 10), f(1, 10), f(3, 10))
    jb = frac_box(mb, f(1, 5), f(1, 10), f(1, 10))  # edges along link axes after the turn
    sa = frac_shift(ma, [x - y for x, y in zip(ca, com)])
    sb = frac_shift(mb, [x - y for x, y in zip(cb, com)])
    expected = [[float(ja[i][j] + jb[i][j] + sa[i][j] + sb[i][j]) for j in range(3)]
                for i in range(3)]
    c = links_of(ARM)["upper_arm"].computed
    assert c.mass == 2.5
    assert close(c.center_of_mass, [float(x) for x in com], 1e-15, scale=1.0)
    assert close(c.inertia, expected, 1e-14)
    assert expected[0][1] != 0 and expected[1][2] != 0  # a real test of the products


def test_primitives_and_an_ascii_stl_link():
    links = links_of(ARM)
    fore = links["forearm"].computed  # cylinder r .04 L .3 at z .15 + ball r .05 at z .3
    vc, vs = math.pi * 0.04**2 * 0.3, 4 / 3 * math.pi * 0.05**3
    mc, ms = 1.2 * vc / (vc + vs), 1.2 * vs / (vc + vs)
    z = (mc * 0.15 + ms * 0.3) / 1.2
    jc = np.diag([mc * (3 * 0.04**2 + 0.09) / 12] * 2 + [mc * 0.04**2 / 2])
    js = np.eye(3) * 0.4 * ms * 0.05**2
    expected = jc + shift(mc, [0, 0, 0.15 - z]) + js + shift(ms, [0, 0, 0.3 - z])
    assert close(fore.center_of_mass, [0, 0, z], 1e-15, scale=1.0)
    assert close(fore.inertia, expected, 1e-14)
    wrist = links["wrist"].computed  # 0.2×0.1×0.1 box centred at (0.1, 0, 0) turned 0.5 rad
    rz = np.array([[math.cos(0.5), -math.sin(0.5), 0], [math.sin(0.5), math.cos(0.5), 0],
                   [0, 0, 1]])
    assert close(wrist.center_of_mass, rz @ [0.1, 0, 0], 1e-15, scale=1.0)
    assert close(wrist.inertia, rz @ box_j(0.4, 0.2, 0.1, 0.1) @ rz.T, 1e-14)


def test_arm_json_per_link_and_dummy_link(run):
    res = run("model", "--json", ARM)
    assert res.exit_code == 0, res.stderr
    rows = json_lines(res.stdout)
    assert [r["link"] for r in rows] == ["base_link", "upper_arm", "forearm", "wrist", "tool0"]
    for r in rows:
        assert CONTRACT_KEYS <= r.keys() and r["model"] == str(ARM)
    tool = rows[-1]
    assert tool["status"] == "skipped" and "no geometry" in tool["reason"]
    assert tool["stated"] is None and tool["computed"] is None
    base = rows[0]
    assert base["status"] == "computed" and base["reason"] is None
    assert {"mass", "center_of_mass", "inertia"} <= base["stated"].keys()
    assert {"mass", "center_of_mass", "inertia", "principal_moments",
            "principal_axes"} <= base["computed"].keys()
    j = np.array(base["computed"]["inertia"])
    r_ = np.array(base["computed"]["principal_axes"])
    assert close(r_ @ np.diag(base["computed"]["principal_moments"]) @ r_.T, j, 1e-14)
    # the stated values are the hand values to 6 digits: the check passes at 1e-5
    assert run("model", "--check", "1e-5", ARM).exit_code == 0


# --- the mobile base (SDF, primitives) ---------------------------------------------------------
def test_mobile_base_against_hand_values():
    links = links_of(BASE)
    chassis = links["chassis"].computed  # box .6×.4×.2 at z .05 + ball r .04 via a frame
    vb, vs = 0.6 * 0.4 * 0.2, 4 / 3 * math.pi * 0.04**3
    mb, ms = 20 * vb / (vb + vs), 20 * vs / (vb + vs)
    cb, cs = np.array([0, 0, 0.05]), np.array([-0.25, 0, -0.05])
    com = (mb * cb + ms * cs) / 20
    expected = (box_j(mb, 0.6, 0.4, 0.2) + shift(mb, cb - com) + np.eye(3) * 0.4 * ms * 0.04**2
                + shift(ms, cs - com))
    assert close(chassis.center_of_mass, com, 1e-15, scale=1.0)
    assert close(chassis.inertia, expected, 1e-14)
    axial, radial = 1.5 * 0.01 / 2, 1.5 * (3 * 0.01 + 0.05**2) / 12  # wheel axis along y
    for wheel in ("wheel_left", "wheel_right"):
        r = links[wheel]
        assert close(r.computed.inertia, np.diag([radial, axial, radial]), 1e-14)
        # wheel_right states its tensor in an inertial frame turned 90° (degrees="true")
        assert close(r.link.stated.inertia, np.diag([radial, axial, radial]), 1e-14)
    lidar = links["lidar"].computed  # capsule r .03, cylinder part .1, along z
    r_, length = 0.03, 0.1
    vc, vh = math.pi * r_**2 * length, 4 / 3 * math.pi * r_**3
    mc, mh = 0.3 * vc / (vc + vh), 0.3 * vh / (vc + vh)
    # each cap: 2/5 mh/2 r² about its flat face's centre, moved to the capsule's centre
    cap_com = length / 2 + 3 * r_ / 8
    cap = (mh / 2) * (2 * r_**2 / 5 - (3 * r_ / 8) ** 2 + cap_com**2)
    jxx = mc * (3 * r_**2 + length**2) / 12 + 2 * cap
    assert close(lidar.inertia, np.diag([jxx, jxx, mc * r_**2 / 2 + 2 * mh * r_**2 / 5]), 1e-14)
    assert links["imu_link"].status == "skipped"
    assert links["imu_link"].error is False


def test_sdf_visual_with_unresolvable_model_uri(run):
    res = run("model", "--json", "--from", "visual", BASE)
    assert res.exit_code == 1
    (line,) = res.stderr.strip().splitlines()
    assert "chassis" in line and "model://mobile_base" in line and "--package-path" in line
    rows = {r["link"]: r for r in json_lines(res.stdout)}
    assert rows["chassis"]["status"] == "skipped" and "mobile_base" in rows["chassis"]["reason"]


# --- the gripper (MJCF, default classes) -----------------------------------------------------
def test_gripper_default_classes_and_childclass():
    links = links_of(GRIPPER)
    palm = links["palm"].computed  # no <inertial>: MuJoCo's rule, geoms at density 1000
    mbox = 1000 * 0.08 * 0.06 * 0.02  # box half-sizes .04 .03 .01
    r, length = 0.01, 0.08                # capsule fromto along x at z = .01
    vc, vh = math.pi * r * r * length, 4 / 3 * math.pi * r**3
    mcap = 1000 * (vc + vh)
    cap_com = length / 2 + 3 * r / 8
    j_axial = 1000 * (vc * r * r / 2 + 2 * vh * r * r / 5)
    j_across = 1000 * (vc * (3 * r * r + length**2) / 12
                       + vh * (2 * r * r / 5 - (3 * r / 8) ** 2 + cap_com**2))
    m = mbox + mcap
    com = np.array([0, 0, mcap * 0.01 / m])
    expected = (box_j(mbox, 0.08, 0.06, 0.02) + shift(mbox, -com)
                + np.diag([j_axial, j_across, j_across]) + shift(mcap, [0, 0, 0.01] - com))
    assert palm.mass == pytest.approx(m, rel=1e-15)
    assert close(palm.center_of_mass, com, 1e-15, scale=1.0)
    assert close(palm.inertia, expected, 1e-14)
    # fingers: class "finger" by childclass (mesh, density 2700, scale from the <mesh> default),
    # the pad by its own class="pad" (box, mass attribute 0.01)
    m1 = 2700 * 0.02 * 0.01 * 0.06
    c1 = np.array([-0.015, 0.005, 0.03])       # Rz(90°) (0.01, 0.005, 0.03) + (-0.01, -0.005, 0)
    c2 = np.array([0.0, 0.01, 0.05])
    m = m1 + 0.01
    com = (m1 * c1 + 0.01 * c2) / m
    expected = (box_j(m1, 0.01, 0.02, 0.06) + shift(m1, c1 - com) + box_j(0.01, 0.02, 0.01, 0.04)
                + shift(0.01, c2 - com))
    for name in ("left_finger", "right_finger"):  # right: the same through a <frame>
        f = links[name].computed
        assert f.mass == pytest.approx(m, rel=1e-15)
        assert close(f.center_of_mass, com, 1e-14, scale=1.0)
        assert close(f.inertia, expected, 1e-13)
    assert links["left_finger"].link.stated is not None
    assert links["right_finger"].link.stated is None


def test_mjcf_degrees_radians_and_eulerseq(tmp_path):
    """One box turned by the same rotation written five ways must give one tensor."""
    rotations = ['euler="0 0 30"', 'axisangle="0 0 1 30"',
                 'quat="0.9659258262890683 0 0 0.25881904510252074"',
                 'xyaxes="0.8660254037844387 0.5 0 -0.5 0.8660254037844387 0"']
    tensors = []
    for compiler, rot in [("", r) for r in rotations] + [
            ('<compiler angle="radian" eulerseq="ZYX"/>', 'euler="0.5235987755982988 0 0"')]:
        p = tmp_path / "m.xml"
        p.write_text(f'<mujoco>{compiler}<worldbody><body name="b"><geom type="box" '
                     f'size="0.3 0.1 0.05" {rot}/></body></worldbody></mujoco>')
        tensors.append(links_of(p)["b"].computed.inertia)
    rz = np.array([[math.sqrt(3) / 2, -0.5, 0], [0.5, math.sqrt(3) / 2, 0], [0, 0, 1]])
    truth = rz @ box_j(1000 * 0.6 * 0.2 * 0.1, 0.6, 0.2, 0.1) @ rz.T
    for t in tensors:
        assert close(t, truth, 1e-14)


# --- --write and --check -----------------------------------------------------------------------
def _strip_inertials(text: str) -> str:
    return re.sub(r"\s*(<inertial\b[^>]*/>|<inertial\b.*?</inertial>)", "", text, flags=re.S)


@pytest.mark.parametrize("density", [(), ("--density", "1234.5")], ids=["kept", "density"])
@pytest.mark.parametrize("path", [ARM, BASE, GRIPPER], ids=["urdf", "sdf", "mjcf"])
def test_write_then_check_1e12(run, path, density):
    # written beside the input so that its relative mesh paths still resolve; named per
    # process, as xdist's workers run the other parameters at the same time
    out = path.with_name(f"massprops-test-out-{os.getpid()}{path.suffix}")
    try:
        res = run("model", "--write", out, *density, path)
        assert res.exit_code == 0, res.stderr
        again = run("model", "--check", "1e-12", "--json", *density, out)
        assert again.exit_code == 0, again.stderr
        rows = [r for r in json_lines(again.stdout) if r["status"] == "computed"]
        assert rows and all(r["comparison"]["inertia_rel"] <= 1e-12 for r in rows)
        before, after = path.read_text(), out.read_text()
        # every comment and every non-inertial byte kept
        assert _strip_inertials(before) == _strip_inertials(after)
        assert after.count("<!--") == before.count("<!--")
    finally:
        out.unlink(missing_ok=True)


@pytest.mark.parametrize("check", [None, "1e-6"], ids=["default", "check-1e-6"])
@pytest.mark.parametrize("path", [ARM, BASE, GRIPPER], ids=["urdf", "sdf", "mjcf"])
def test_write_rewrites_only_the_inertials_that_are_off(run, path, check):
    """Issue 30: every other byte stays, correct inertials included (they were rewritten, 5 ->
    5.0); off means none stated, invalid, or off by more than --check RTOL (default 1e-12)."""
    from massprops.robot.analyze import load_model

    rtol = 1e-12 if check is None else float(check)
    rows = [r for r in json_lines(run("model", "--json", path).stdout)
            if r["status"] == "computed"]
    off = [r["link"] for r in rows if r["stated"] is None or not r["stated"]["valid"]
           or max(r["comparison"][k] for k in ("mass_rel", "com_rel", "inertia_rel")) > rtol]
    # the three files and two tolerances give every case: all off, some, none
    out = path.with_name(f"massprops-test-only-{os.getpid()}{path.suffix}")
    try:
        res = run("model", "--write", out, *(["--check", check] if check else []), path)
        assert res.exit_code in (0, 4), res.stderr
        said = (f"rewrote the inertial of {', '.join(off)} ({len(off)} of {len(rows)}"
                if off else "every computed inertial agrees within")
        assert said in res.stderr
        before, after = path.read_bytes(), out.read_bytes()
        old = {k.name: k for k in load_model(path).links}
        new = {k.name: k for k in load_model(out).links}
        # put the old bytes back where the rewritten links' inertials are: the input again
        undo = bytearray(after)
        for name in sorted(off, key=lambda n: new[n].inertial_node.start, reverse=True):
            o, n = old[name].inertial_node, new[name].inertial_node
            if o is None:  # inserted after the link's start tag, on a line of its own
                del undo[new[name].node.head_end:n.end]
            else:
                undo[n.start:n.end] = before[o.start:o.end]
        assert bytes(undo) == before
        for name in set(old) - set(off):  # kept: the very same bytes
            o, n = old[name].inertial_node, new[name].inertial_node
            if o is not None:
                assert after[n.start:n.end] == before[o.start:o.end]
    finally:
        out.unlink(missing_ok=True)


def test_write_keeps_every_inertial_that_agrees(run, tmp_path):
    """A file --write wrote is kept byte for byte by a second --write (idempotent)."""
    src = tmp_path / "r.urdf"
    src.write_text('<robot name="r">\n  <link name="a">\n    <inertial><mass value="5"/>'
                   '<inertia ixx="0.8333333333333334" ixy="0" ixz="0" iyy="0.8333333333333334" '
                   'iyz="0" izz="0.8333333333333334"/></inertial>\n    <collision><geometry>'
                   '<box size="1 1 1"/></geometry></collision>\n  </link>\n</robot>\n')
    out = tmp_path / "o.urdf"
    res = run("model", "--write", out, src)
    assert res.exit_code == 0, res.stderr
    assert out.read_bytes() == src.read_bytes()  # `5` stays `5`
    assert res.stderr == (f"massprops: wrote {out}: every computed inertial agrees within "
                          "1e-12 of the geometry; none rewritten\n")


def test_write_inserts_with_the_links_indentation(run, tmp_path):
    src = tmp_path / "r.urdf"
    src.write_text('<robot name="r">\n\t<link name="a">\n\t\t<collision><geometry><box size="1 '
                   '2 3"/></geometry></collision>\n\t</link>\n</robot>\n')
    out = tmp_path / "out.urdf"
    assert run("model", "--density", "2", "--write", out, src).exit_code == 0
    text = out.read_text()
    assert '\t<link name="a">\n\t\t<inertial>\n\t\t\t<origin xyz="' in text
    assert "\t\t</inertial>\n\t\t<collision>" in text
    rows = json_lines(run("model", "--json", out).stdout)
    assert rows[0]["stated"]["mass"] == 12.0
    assert close(rows[0]["stated"]["inertia"], box_j(12.0, 1, 2, 3), 1e-15)


def test_write_never_over_the_input_nor_an_existing_file(run, tmp_path):
    src = tmp_path / "r.urdf"
    shutil.copy(ARM, src)
    before = src.read_bytes()
    res = run("model", "--write", src, src)
    assert res.exit_code == 1 and src.read_bytes() == before
    other = tmp_path / "o.urdf"
    other.write_text("keep")
    res = run("model", "--write", other, "--package-path", ROBOTS, src)
    assert res.exit_code == 1 and other.read_text() == "keep" and "--force" in res.stderr
    res = run("model", "--write", other, "--force", "--package-path", ROBOTS, src)
    assert res.exit_code == 1  # ../meshes/unit_cube.obj does not resolve from tmp: reported
    assert "upper_arm" in res.stderr and other.read_text() != "keep"


@pytest.mark.parametrize("field,new", [("ixx", '"0.05"'), ("mass", None), ("xyz", None)])
def test_wrong_inertial_fails_check_with_exit_4(run, field, new):
    text = ARM.read_text()
    if field == "ixx":
        text = text.replace('ixx="0.0441667"', f"ixx={new}")
    elif field == "mass":
        text = text.replace('<mass value="1.2"/>', '<mass value="1.3"/>')
    else:
        text = text.replace('xyz="0.0877583 0.0479426 0"', 'xyz="0.0877583 0.0479426 0.02"')
    bad = ARM.with_name(f"massprops-test-bad-{os.getpid()}.urdf")  # per process: see above
    bad.write_text(text)
    try:
        res = run("model", "--check", "0.05", "--json", bad)
        assert res.exit_code == 4, res.stderr
        (line,) = res.stderr.strip().splitlines()
        assert line.startswith("massprops: error: ")
        assert re.search(r": 1 link\(s\) differ.*: (upper_arm|forearm|wrist) \(", line)
        assert len(json_lines(res.stdout)) == 5  # the full report came first
        assert run("model", "--check", "10", bad).exit_code == 0
    finally:
        bad.unlink()


def test_unphysical_stated_inertia_fails_any_tolerance(run, tmp_path):
    p = tmp_path / "r.urdf"
    p.write_text('<robot name="r"><link name="a"><inertial><mass value="3"/><inertia ixx="1" '
                 'ixy="0" ixz="0" iyy="1" iyz="0" izz="3"/></inertial><collision><geometry>'
                 '<sphere radius="1"/></geometry></collision></link></robot>')
    res = run("model", "--check", "100", "--json", p)
    assert res.exit_code == 4 and "triangle" in res.stderr
    (row,) = json_lines(res.stdout)
    assert row["stated"]["valid"] is False and row["comparison"]["valid"] is False


# --- bad inputs: one line, the right exit code ----------------------------------------------------
BAD = {
    "malformed.urdf": ('<robot name="r">\n<link name="a">\n</robot>\n', 1, ":3:"),
    "loop.urdf": ('<robot name="r"><link name="a"/><link name="b"/>\n'
                  '<joint name="j1" type="fixed"><parent link="a"/><child link="b"/></joint>\n'
                  '<joint name="j2" type="fixed"><parent link="b"/><child link="a"/></joint>'
                  "</robot>", 1, "loop"),
    "two-parents.urdf": ('<robot name="r"><link name="a"/><link name="b"/><link name="c"/>\n'
                         '<joint name="j1"><parent link="a"/><child link="c"/></joint>\n'
                         '<joint name="j2"><parent link="b"/><child link="c"/></joint></robot>',
                         1, ":3: <joint>"),
    "angle.xml": ('<mujoco>\n<compiler angle="grad"/><worldbody/></mujoco>', 1, "angle='grad'"),
    "degrees.sdf": ('<sdf version="1.9"><model name="m"><link name="a"><collision name="c">\n'
                    '<pose degrees="maybe">0 0 0 0 0 0</pose><geometry><sphere><radius>1'
                    "</radius></sphere></geometry></collision></link></model></sdf>", 1,
                    ":2: <pose>"),
    "xacro.urdf": ('<robot xmlns:xacro="http://www.ros.org/wiki/xacro" name="r">\n'
                   '<link name="${nope}"/></robot>', 1, "xacro failed"),
    "not-a-robot.xml": ("<html><body/></html>", 1, "<html>"),
    "include.xml": ('<mujoco>\n<include file="other.xml"/></mujoco>', 1,
                    ":2: <include file='other.xml'>: no such file"),
    "bad-number.urdf": ('<robot name="r"><link name="a"><collision><geometry>\n'
                        '<box size="1 2"/></geometry></collision></link></robot>', 1,
                        ":2: <box>: size="),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_description_one_line(run, tmp_path, name):
    text, code, needle = BAD[name]
    p = tmp_path / name
    p.write_text(text)
    res = run("model", "--json", p)
    assert res.exit_code == code, res.stderr
    assert res.stdout == ""
    (line,) = res.stderr.strip().splitlines()
    assert line.startswith("massprops: error: ") and str(p) in line and needle in line
    assert "Traceback" not in res.stderr


def test_missing_file(run, tmp_path):
    res = run("model", tmp_path / "nope.urdf")
    assert res.exit_code == 1 and "nope.urdf" in res.stderr and "Traceback" not in res.stderr


@pytest.mark.parametrize("mesh,needle", [("missing", "no such file"),
                                         ("garbage", "garbage.stl"),
                                         ("open", "open")])
def test_bad_mesh_skips_its_link_and_exits_1_after_the_report(run, tmp_path, mesh, needle):
    (tmp_path / "garbage.stl").write_bytes(b"\x00\x01 not a mesh" * 10)
    (tmp_path / "open.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\n")
    file = {"missing": "missing.obj", "garbage": "garbage.stl", "open": "open.obj"}[mesh]
    p = tmp_path / "r.urdf"
    p.write_text(f'<robot name="r"><link name="good"><inertial><mass value="1"/><inertia ixx="1" '
                 'ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial><collision><geometry><box '
                 'size="1 1 1"/></geometry></collision></link>\n<link name="bad"><collision>'
                 f'<geometry><mesh filename="{file}"/></geometry></collision></link></robot>')
    res = run("model", "--json", p)
    assert res.exit_code == 1
    (line,) = res.stderr.strip().splitlines()
    assert "'bad'" in line and needle in line and f"{p}:2" in line
    rows = {r["link"]: r for r in json_lines(res.stdout)}
    assert rows["good"]["status"] == "computed"
    assert rows["bad"]["status"] == "skipped" and needle in rows["bad"]["reason"]
    # the check still runs on what was computed; a disagreement wins (exit 4 > 1)
    assert run("model", "--check", "0.01", p).exit_code == 4


def test_package_path_option_and_environment(run, tmp_path, monkeypatch):
    p = tmp_path / "arm.urdf"
    p.write_text(ARM.read_text().replace("../meshes/", "package://arm_description/meshes/"))
    res = run("model", "--json", p)
    assert res.exit_code == 1 and "--package-path" in res.stderr
    assert run("model", "--json", "--package-path", ROBOTS, p).exit_code == 0
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(ROBOTS / "arm_description"))
    assert run("model", "--json", p).exit_code == 0


def test_no_stated_mass_needs_density(run, tmp_path):
    p = tmp_path / "r.urdf"
    p.write_text('<robot name="r"><link name="a"><collision><geometry><sphere radius="0.5"/>'
                 "</geometry></collision></link></robot>")
    (row,) = json_lines(run("model", "--json", p).stdout)
    assert row["status"] == "skipped" and "--density" in row["reason"]
    res = run("model", "--json", "--density", "1000", p)
    (row,) = json_lines(res.stdout)
    assert res.exit_code == 0 and row["computed"]["mass"] == pytest.approx(
        1000 * 4 / 3 * math.pi / 8, rel=1e-15)


def test_gripper_agrees_with_mujoco_when_installed():
    """MuJoCo's own compiler as a second opinion on the MJCF rules (skipped without mujoco)."""
    mujoco = pytest.importorskip("mujoco")
    from massprops.rotation import quat_to_matrix

    model = mujoco.MjModel.from_xml_path(str(GRIPPER))
    for name, r in links_of(GRIPPER).items():
        b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
        a = quat_to_matrix(model.body_iquat[b])
        j = a @ np.diag(model.body_inertia[b]) @ a.T
        if r.link.stated is None:  # MuJoCo computes these from the geoms, as massprops does
            assert r.computed.mass == pytest.approx(model.body_mass[b], rel=1e-14)
            assert close(r.computed.center_of_mass, model.body_ipos[b], 1e-14, scale=0.1)
            assert close(r.computed.inertia, j, 1e-12)
        else:  # MuJoCo takes the stated inertial: 6 digits of the computed one
            assert close(r.computed.inertia, j, 1e-5)


def test_mirrored_mesh_keeps_its_volume_and_mirrors_its_com(tmp_path):
    """scale "-1 1 1" turns the surface inside out; the faces are reversed, not refused."""
    shutil.copy(ROBOTS / "arm_description" / "meshes" / "box_mm.obj", tmp_path / "b.obj")
    p = tmp_path / "r.urdf"
    p.write_text('<robot name="r"><link name="a"><collision><geometry><mesh filename="b.obj" '
                 'scale="-0.001 0.001 0.001"/></geometry></collision></link></robot>')
    c = links_of(p, density=1.0)["a"].computed
    assert c.volume == pytest.approx(0.1 * 0.2 * 0.4, rel=1e-14)
    assert close(c.center_of_mass, [-0.05, 0.1, 0.2], 1e-15, scale=1.0)
    assert close(c.inertia, box_j(c.mass, 0.1, 0.2, 0.4), 1e-14)


def test_write_keeps_crlf_and_comments(run, tmp_path):
    src = tmp_path / "r.urdf"
    src.write_bytes(b'<robot name="r">\r\n  <!-- keep -->\r\n  <link name="a">\r\n    <inertial>'
                    b'<mass value="2"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/>'
                    b'</inertial>\r\n    <collision><geometry><sphere radius="0.5"/></geometry>'
                    b"</collision>\r\n  </link>\r\n</robot>\r\n")
    out = tmp_path / "o.urdf"
    assert run("model", "--write", out, src).exit_code == 0
    data = out.read_bytes()
    assert b"\n" not in data.replace(b"\r\n", b"")
    assert data.startswith(b'<robot name="r">\r\n  <!-- keep -->\r\n  <link name="a">\r\n    '
                           b"<inertial>\r\n      <origin")
    assert data.endswith(b"</inertial>\r\n    <collision><geometry><sphere radius=\"0.5\"/>"
                         b"</geometry></collision>\r\n  </link>\r\n</robot>\r\n")
    (row,) = json_lines(run("model", "--json", out).stdout)
    assert close(row["stated"]["inertia"], np.eye(3) * 0.4 * 2 * 0.25, 1e-15)
