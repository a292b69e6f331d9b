"""Defects of issue 32.4: MJCF's shell meshes are computed, a geom naming a mesh without a
type is a mesh geom, the legacy-inertia warning says what MuJoCo does, an open mesh's refusal in
`model` names what works."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import json_lines

BOX = [(x, y, z) for x in (0.0, 0.25) for y in (0.0, 0.5) for z in (0.0, 0.125)]
QUADS = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]


def _box_obj(path, drop=()):
    faces = [q for i, q in enumerate(QUADS) if i not in drop]
    path.write_text("".join(f"v {x} {y} {z}\n" for x, y, z in BOX)
                    + "".join(f"f {a + 1} {b + 1} {c + 1} {d + 1}\n" for a, b, c, d in faces))


def _mjcf(tmp_path, mesh_attrs, geom_attrs='type="mesh" mesh="b"'):
    _box_obj(tmp_path / "box.obj")
    f = tmp_path / "m.xml"
    f.write_text(f'<mujoco><asset><mesh name="b" file="box.obj" {mesh_attrs}/></asset>'
                 f'<worldbody><body name="a"><freejoint/><geom {geom_attrs}/></body>'
                 '</worldbody></mujoco>')
    return f


def test_a_shell_mesh_is_computed_as_mujoco_compiles_it(tmp_path, run):
    """inertia="shell": the surface carries the mass (density per m²); against MuJoCo's own
    compiled body."""
    mujoco = pytest.importorskip("mujoco")
    f = _mjcf(tmp_path, 'inertia="shell"', 'type="mesh" mesh="b" density="3"')
    (row,) = json_lines(run("model", f, "--json").stdout)
    assert row["status"] == "computed", row["reason"]
    compiled = mujoco.MjModel.from_xml_path(str(f))
    c = row["computed"]
    assert c["mass"] == pytest.approx(compiled.body_mass[1], rel=1e-6)  # 3 kg/m² × 0.4375 m²
    assert c["mass"] == pytest.approx(3 * 2 * (0.25 * 0.5 + 0.25 * 0.125 + 0.5 * 0.125))
    assert np.allclose(c["center_of_mass"], compiled.body_ipos[1], rtol=1e-6)
    assert np.allclose(sorted(c["principal_moments"]), sorted(compiled.body_inertia[1]),
                       rtol=1e-6)


def test_a_geom_naming_a_mesh_without_a_type_is_a_mesh_geom(tmp_path, run):
    typed = json_lines(run("model", _mjcf(tmp_path, 'inertia="exact"'), "--json").stdout)[0]
    f = _mjcf(tmp_path, 'inertia="exact"', 'mesh="b"')
    (row,) = json_lines(run("model", f, "--json").stdout)
    assert row["status"] == "computed" and row["computed"] == typed["computed"]
    assert row["computed"]["mass"] == pytest.approx(1000 * 0.25 * 0.5 * 0.125)


def test_the_legacy_warning_says_what_mujoco_does(tmp_path, run):
    (row,) = json_lines(run("model", _mjcf(tmp_path, ""), "--json").stdout)
    (w,) = [w for w in row["warnings"] if "'legacy'" in w]
    assert "each face's pyramid volume taken positive" in w and "convex hull" not in w


def test_an_open_mesh_in_model_names_what_works(tmp_path, run):
    _box_obj(tmp_path / "open.obj", drop=(0,))
    f = tmp_path / "r.urdf"
    f.write_text('<robot name="r"><link name="a"><inertial><mass value="1"/><inertia ixx="1" '
                 'ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial><collision><geometry>'
                 '<mesh filename="open.obj"/></geometry></collision></link></robot>')
    result = run("model", f)
    assert result.exit_code == 1
    line = next(x for x in result.stderr.splitlines() if "link 'a'" in x)
    for option in ("--fill-holes", "--max-hole", "--shell THICKNESS", "--allow-open",
                   "--from visual"):
        assert option in line, line
