"""An MJCF ``<mesh vertex=...>`` without ``face=``: MuJoCo's mesh is the convex hull of the
points (the car in MuJoCo's model gallery, the Rubik's cube's cubelets). Against MuJoCo's own
compiled body, and the closed form of the hull of a box's corners."""

from __future__ import annotations

import json

import numpy as np
import pytest

# a 0.4 x 0.2 x 0.1 box's eight corners and an interior point (not a hull vertex)
CORNERS = " ".join(f"{x} {y} {z}" for x in (-0.2, 0.2) for y in (-0.1, 0.1) for z in (-0.05, 0.05))
MJCF = f"""<mujoco>
  <asset><mesh name="hull" vertex="{CORNERS} 0.01 0.02 0"/></asset>
  <worldbody><body name="b"><joint name="h" axis="0 1 0"/>
    <geom type="mesh" mesh="hull" pos="0.3 0 0" density="500"/></body></worldbody>
</mujoco>"""


def test_vertex_only_mesh_is_its_convex_hull(tmp_path, run):
    (tmp_path / "m.xml").write_text(MJCF)
    result = run("model", tmp_path / "m.xml", "--json")
    assert result.exit_code == 0, result.stderr
    row = json.loads(result.stdout.splitlines()[0])
    computed = row["computed"]
    mass = 500 * 0.4 * 0.2 * 0.1
    assert computed["mass"] == pytest.approx(mass, rel=1e-12)
    assert computed["center_of_mass"] == pytest.approx([0.3, 0, 0], abs=1e-15)
    box = mass / 12 * np.array([0.2**2 + 0.1**2, 0.4**2 + 0.1**2, 0.4**2 + 0.2**2])
    assert computed["principal_moments"] == pytest.approx(sorted(box), rel=1e-12)
    assert not any("convex hull" in w for w in row["warnings"])  # it is its hull: nothing to say
    mujoco = pytest.importorskip("mujoco")
    model = mujoco.MjModel.from_xml_string(MJCF)
    # MuJoCo keeps mesh vertices in float32: its 0.05 is 0.05 + 7e-10 (measured: 4.5e-8 rel)
    assert computed["mass"] == pytest.approx(model.body_mass[1], rel=1e-6)
    assert computed["principal_moments"] == pytest.approx(sorted(model.body_inertia[1]),
                                                          rel=1e-6)
    result = run("simulate", tmp_path / "m.xml", "--duration", "0", "--json")
    assert result.exit_code == 0, result.stderr
    held = json.loads(result.stdout)["final"]["joints"]["h"]["holding"][0]
    assert held == pytest.approx(-9.81 * mass * 0.3, rel=1e-12)


def test_points_that_span_no_volume_are_one_line(tmp_path, run):
    (tmp_path / "flat.xml").write_text(
        '<mujoco><asset><mesh name="f" vertex="0 0 0 1 0 0 0 1 0 1 1 0"/></asset>\n'
        '<worldbody><body name="b"><geom type="mesh" mesh="f"/></body></worldbody></mujoco>')
    result = run("model", tmp_path / "flat.xml")
    assert result.exit_code == 1
    lines = [line for line in result.stderr.splitlines() if "error" in line]
    assert len(lines) == 1 and "flat.xml:2" in lines[0] and "no volume" in lines[0], \
        result.stderr
