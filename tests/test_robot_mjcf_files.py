"""MJCF as people write it: a model split over ``<include>`` files (defaults and assets from the
included files), ``<frame>``, ``<replicate>``, ``<attach>`` and the compiler's mass rules, against
closed forms and, where mujoco is installed, against MuJoCo's own compiled bodies."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from massprops.errors import RobotModelError
from massprops.robot.analyze import analyze_model

SPLIT = Path(__file__).resolve().parent / "robots" / "split" / "main.xml"


def links(path, **kw):
    return {r.name: r for r in analyze_model(path, **kw).links}


def test_split_model_masses_in_closed_form():
    """Every body of the split model from its shapes: densities from the included defaults
    (500, class heavy 7800, the attached model's own 2000), the wedge mesh from the included
    asset (legs 0.1 and 0.2, height 0.3 after scale 0.1: V = 0.003), replicate copies named
    finger_0.. and the attached bodies prefixed."""
    r = links(SPLIT)
    assert list(r) == ["base", "arm", "finger_0", "finger_1", "finger_2", "h-palm", "h-thumb"]
    box = 7800 * 0.2 * 0.4 * 0.1
    capsule = 500 * (math.pi * 0.02**2 * 0.1 + 4 / 3 * math.pi * 0.02**3)
    assert r["base"].computed.mass == pytest.approx(box + capsule, rel=1e-14)
    # the capsule sits at (0, 0.1, 0.1): the frame turns its (0.1, 0, 0) by 90° about z
    assert r["base"].computed.center_of_mass == pytest.approx(
        [0, capsule * 0.1 / (box + capsule), capsule * 0.1 / (box + capsule)], abs=1e-15)
    ellipsoids = 4 * 500 * 4 / 3 * math.pi * 0.01 * 0.02 * 0.03
    assert r["arm"].computed.mass == pytest.approx(500 * 0.003 + ellipsoids, rel=1e-14)
    finger = 500 * (math.pi * 0.01**2 * math.sqrt(0.02) + 4 / 3 * math.pi * 0.02**3)
    for k in range(3):
        assert r[f"finger_{k}"].computed.mass == pytest.approx(finger, rel=1e-14)
    assert r["h-palm"].computed.mass == pytest.approx(2000 * 0.06 * 0.08 * 0.02, rel=1e-14)
    assert r["h-thumb"].link.stated.mass == 0.2


def test_replicated_geoms_follow_their_cumulative_frames():
    """Four ellipsoids at (0.2, 0, 0) in frames T^i, T = 0.03 up after 0.3 rad about x: copy i
    sits at x = 0.2 and (y, z) = Σ_{k<i} R^k (0, 0.03); their mean is the ellipsoids' COM."""
    r = links(SPLIT)["arm"].computed
    pts, rot, off = [], np.eye(3), np.zeros(3)
    c, s = math.cos(0.3), math.sin(0.3)
    step = np.array([[1, 0, 0], [0, c, -s], [0, s, c]])
    for _ in range(4):
        pts.append(off + rot @ np.array([0.2, 0, 0]))
        rot, off = step @ rot, step @ off + np.array([0, 0, 0.03])
    m_e = 500 * 4 / 3 * math.pi * 0.01 * 0.02 * 0.03
    # the wedge (legs along the mesh's x and y, height z) turned by quat (.5 .5 .5 .5), which
    # maps x->y, y->z, z->x, then moved by (0.05, 0, 0): its centroid (1/3, 2/3, 1.5)·0.1
    wedge_c = np.array([0.15 + 0.05, 0.1 / 3, 0.2 / 3])
    m_w = 500 * 0.003
    expect = (m_w * wedge_c + m_e * np.sum(pts, axis=0)) / (m_w + 4 * m_e)
    assert np.allclose(r.center_of_mass, expect, atol=1e-15)


def test_compiler_bounds_then_total_mass(tmp_path):
    """boundmass 1 and boundinertia 0.5 lift a 1 g box to 1 kg and every moment to 0.5, then
    settotalmass 10 scales both bodies by 10 / (m_sphere + 1) (MuJoCo's order)."""
    f = tmp_path / "bounds.xml"
    f.write_text('<mujoco><compiler boundmass="1" boundinertia="0.5" settotalmass="10"/>'
                 '<worldbody><body name="a"><geom size="0.1"/><body name="b">'
                 '<geom type="box" size="0.01 0.01 0.01" mass="0.001"/></body></body>'
                 '</worldbody></mujoco>')
    r = links(f)
    sphere = 1000 * 4 / 3 * math.pi * 0.1**3
    k = 10 / (sphere + 1)
    assert r["a"].computed.mass == pytest.approx(sphere * k, rel=1e-14)
    assert r["b"].computed.mass == pytest.approx(k, rel=1e-14)
    for name in "ab":
        assert np.allclose(r[name].computed.inertia, 0.5 * k * np.eye(3), rtol=1e-14)


def test_include_errors_name_the_including_file_and_line(tmp_path):
    (tmp_path / "main.xml").write_text('<mujoco>\n<include file="nope.xml"/>\n</mujoco>')
    with pytest.raises(RobotModelError, match=r"main\.xml:2: <include file='nope.xml'>"):
        analyze_model(tmp_path / "main.xml")
    (tmp_path / "loop.xml").write_text('<mujoco>\n\n<include file="loop.xml"/></mujoco>')
    with pytest.raises(RobotModelError, match=r"loop\.xml:3: .*include loop"):
        analyze_model(tmp_path / "loop.xml")


def test_a_missing_include_names_the_folders_it_was_looked_for_in(run, tmp_path, monkeypatch):
    """Issue 30: a main model given as a bare name said "no such file in . (the main model's
    folder) nor in .": the folders are said absolute, once each."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "sub").mkdir()
    (tmp_path / "main.xml").write_text('<mujoco>\n<include file="nope.xml"/>\n</mujoco>')
    res = run("model", "main.xml")
    assert res.exit_code == 1
    assert res.stderr == (f"massprops: error: main.xml:2: <include file='nope.xml'>: no such "
                          f"file in {tmp_path} (the main model's folder); fix the path\n")
    (tmp_path / "top.xml").write_text('<mujoco><include file="sub/a.xml"/></mujoco>')
    (tmp_path / "sub" / "a.xml").write_text('<mujoco><include file="b.xml"/></mujoco>')
    res = run("model", "top.xml")
    assert res.stderr == (f"massprops: error: sub/a.xml:1: <include file='b.xml'>: no such file "
                          f"in {tmp_path} (the main model's folder) nor in {tmp_path / 'sub'} "
                          "(the including file's folder); fix the path\n")


def test_include_looks_in_the_main_folder_first(tmp_path):
    """MuJoCo's rule: a relative include is found from the main file's folder before the
    including file's own folder."""
    (tmp_path / "sub").mkdir()
    (tmp_path / "main.xml").write_text('<mujoco><include file="sub/a.xml"/></mujoco>')
    (tmp_path / "sub" / "a.xml").write_text('<mujoco><include file="b.xml"/></mujoco>')
    body = '<mujoco><worldbody><body name="{}"><geom size="0.1"/></body></worldbody></mujoco>'
    (tmp_path / "sub" / "b.xml").write_text(body.format("inner"))
    assert list(links(tmp_path / "main.xml")) == ["inner"]
    (tmp_path / "b.xml").write_text(body.format("outer"))
    assert list(links(tmp_path / "main.xml")) == ["outer"]


def _mujoco_tensor(model, i):
    w, x, y, z = model.body_iquat[i]
    a = np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                  [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                  [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    return a @ np.diag(model.body_inertia[i]) @ a.T


@pytest.mark.parametrize("name", ["split", "bounds"])
def test_against_mujoco_compiled_bodies(name, tmp_path, monkeypatch):
    """MuJoCo's body_mass, body_ipos and body_inertia (principal moments in the body_iquat
    frame, turned back into the body's axes here): what massprops states where the body has an
    <inertial>, else what it computes. MuJoCo stores meshes in float32: 1e-6 for those."""
    mujoco = pytest.importorskip("mujoco")
    monkeypatch.chdir(tmp_path)  # MuJoCo writes MUJOCO_LOG.TXT (settotalmass's deprecation) here
    if name == "split":
        path = SPLIT
    else:
        path = tmp_path / "bounds.xml"
        path.write_text('<mujoco><compiler boundmass="1" boundinertia="0.5" settotalmass="10"/>'
                        '<worldbody><body name="a"><geom size="0.1"/><body name="b">'
                        '<geom type="box" size="0.01 0.01 0.01" mass="0.001"/></body></body>'
                        '</worldbody></mujoco>')
    model = mujoco.MjModel.from_xml_path(str(path))
    reports = analyze_model(path).links
    assert [r.name for r in reports] == [model.body(i).name for i in range(1, model.nbody)]
    for i, r in enumerate(reports, start=1):
        s = r.link.stated
        mass, com, j = (s.mass, s.center_of_mass, s.inertia) if s is not None else (
            r.computed.mass, r.computed.center_of_mass, r.computed.inertia)
        rtol = 1e-6 if any(g.kind == "mesh" for g in r.link.geometries) else 1e-12
        assert mass == pytest.approx(model.body_mass[i], rel=rtol)
        assert np.allclose(com, model.body_ipos[i], rtol=0, atol=rtol * 0.5)
        assert np.allclose(j, _mujoco_tensor(model, i), rtol=0,
                           atol=rtol * float(np.max(model.body_inertia[i])))


def _box_mesh_files(folder, open_mesh):
    """A 0.1 × 0.2 × 0.3 box as an OBJ (without its bottom when ``open_mesh``) and as MuJoCo's
    binary .msh (float32 positions: 0.1, 0.2, 0.3 rounded)."""
    from conftest import CUBE_QUADS, CUBE_VERTS

    size = np.array([0.1, 0.2, 0.3])
    verts = np.array(CUBE_VERTS, float) * size
    quads = CUBE_QUADS[1:] if open_mesh else CUBE_QUADS
    (folder / "box.obj").write_text(
        "".join(f"v {x!r} {y!r} {z!r}\n" for x, y, z in verts.tolist())
        + "".join("f " + " ".join(str(i + 1) for i in q) + "\n" for q in quads))
    tris = np.array([[q[0], q[1], q[2]] for q in CUBE_QUADS] + [[q[0], q[2], q[3]]
                                                                  for q in CUBE_QUADS])
    header = np.array([8, 0, 0, 12], dtype="<i4").tobytes()
    (folder / "box.msh").write_bytes(header + verts.astype("<f4").tobytes()
                                     + tris.astype("<i4").tobytes())


@pytest.mark.parametrize("inertia, expect", [("legacy", "legacy"), ("convex", "hull"),
                                             ("exact", "refused")])
def test_open_mesh_in_mjcf_takes_the_body_mujoco_simulates(tmp_path, inertia, expect):
    """An open box (bottom missing) with inertia="convex" is the box MuJoCo simulates (its
    convex hull): V = 0.006, COM at the centre; under the default "legacy" MuJoCo integrates the
    five faces' pyramids from their centroid, volumes taken positive (issue 32.4: not the hull),
    checked against MuJoCo's own compiled body; with inertia="exact" MuJoCo needs a closed mesh
    too, so it is refused."""
    _box_mesh_files(tmp_path, open_mesh=True)
    f = tmp_path / "m.xml"
    f.write_text(f'<mujoco><asset><mesh name="b" file="box.obj" inertia="{inertia}"/></asset>'
                 '<worldbody><body name="a"><geom type="mesh" mesh="b"/></body></worldbody>'
                 '</mujoco>')
    r = links(f)["a"]
    if expect == "refused":
        assert r.status == "skipped" and r.error and "not closed" in r.reason
        return
    assert r.status == "computed"
    if expect == "legacy":
        mujoco = pytest.importorskip("mujoco")
        compiled = mujoco.MjModel.from_xml_path(str(f))
        assert r.computed.volume == pytest.approx(compiled.body_mass[1] / 1000, rel=1e-6)
        assert r.computed.center_of_mass == pytest.approx(compiled.body_ipos[1], rel=1e-6)
        assert any("MuJoCo's legacy rule" in w for w in r.warnings)
        return
    assert r.computed.volume == pytest.approx(0.006, rel=1e-14)
    assert r.computed.center_of_mass == pytest.approx([0.05, 0.1, 0.15], rel=1e-14)
    assert any("convex hull" in w for w in r.warnings)


def test_mujoco_msh_mesh_and_massless_geoms(tmp_path):
    """MuJoCo's binary .msh box (float32 corners) at density 1000, and a mass="0" decoration
    that adds nothing (MuJoCo's rule); a body with only massless geoms and an inertial is
    stated-only."""
    _box_mesh_files(tmp_path, open_mesh=False)
    f = tmp_path / "m.xml"
    f.write_text('<mujoco><asset><mesh name="b" file="box.msh" inertia="exact"/></asset>'
                 '<worldbody><body name="a"><geom type="mesh" mesh="b"/>'
                 '<geom type="sphere" size="1" mass="0"/></body>'
                 '<body name="c"><inertial pos="0 0 0" mass="2" diaginertia="1 1 1"/>'
                 '<geom type="box" size="1 1 1" mass="0"/></body></worldbody></mujoco>')
    r = links(f)
    edges = np.array([0.1, 0.2, 0.3], dtype=np.float32).astype(float)
    assert r["a"].computed.mass == pytest.approx(1000 * np.prod(edges), rel=1e-14)
    assert r["a"].computed.center_of_mass == pytest.approx(edges / 2, rel=1e-14)
    assert r["c"].status == "stated-only"


def test_lenient_xml_blank_lines_before_declaration_and_trailing_junk(tmp_path):
    f = tmp_path / "r.urdf"
    f.write_text('\n\n<?xml version="1.0"?>\n<robot name="r"><link name="a"><inertial>'
                 '<mass value="2"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/>'
                 '</inertial><collision><geometry><sphere radius="0.5"/></geometry>'
                 '</collision></link></robot>\n\x01junk')
    r = links(f)["a"]
    assert r.status == "computed" and r.computed.inertia[0, 0] == pytest.approx(0.2, rel=1e-14)
    assert r.link.node.line == 4   # the blanked declaration keeps the lines
