"""The repairs on the command line and in a scene: exit codes, the stderr line, parsed --json
(the ``repairs`` object) against closed forms; align writes the repaired mesh."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import CUBE_QUADS, CUBE_VERTS, SAMPLES, json_lines, vf_text

from massprops.dynamics.scene import load_scene
from massprops.errors import InputError

TIME = "time: {duration: 1.0}\n"


def boxes_vf(path, boxes):
    """Several unit-cube quad meshes scaled into boxes, one file."""
    verts, faces = [], []
    for lo, hi in boxes:
        base = len(verts)
        lo, hi = np.array(lo, float), np.array(hi, float)
        verts += (lo + np.array(CUBE_VERTS, float) * (hi - lo)).tolist()
        faces += [[base + i for i in q] for q in CUBE_QUADS]
    path.write_text(vf_text(verts, faces))
    return path


OVERLAP = [((0, 0, 0), (2, 2, 2)), ((1, 1, 1), (3, 3, 3))]  # 8 + 8 - 1


def test_union_json_repairs_object(run, tmp_path):
    path = boxes_vf(tmp_path / "two.vf", OVERLAP)
    res = run("inspect", "--json", "--union", "--density", "2", path)
    assert res.exit_code == 0, res.stderr
    (out,) = json_lines(res.stdout)
    union = out["repairs"]["union"]
    assert union["pieces"] == 2 and union["unioned"] == 2
    assert union["volume_before"] == pytest.approx(16.0, rel=1e-15)
    assert union["volume_after"] == pytest.approx(15.0, rel=1e-15)
    assert union["counted_twice"] == pytest.approx(1.0, rel=1e-14)
    assert out["volume"] == pytest.approx(15.0, rel=1e-15) and out["mass"] == pytest.approx(30.0)
    assert np.allclose(out["center_of_mass"], [1.5, 1.5, 1.5], rtol=0, atol=1e-14)
    assert set(out["uncertainty"]) == {"rounding", "input", "repair"}
    assert res.stderr == ""


def test_overlap_warning_names_union(run, tmp_path):
    path = boxes_vf(tmp_path / "two.vf", OVERLAP)
    res = run("inspect", "--json", path)
    assert res.exit_code == 0
    assert (f"massprops: warning: {path}: the pieces share 1 m³ (6.25% of the 16 m³ reported), "
            f"measured from their union: that volume is counted more than once; --union counts "
            f"it once") in res.stderr.splitlines()
    (out,) = json_lines(res.stdout)
    assert "repairs" not in out and "repair" not in out["uncertainty"]


def open_cube(tmp_path, name="open.vf"):
    path = tmp_path / name
    path.write_text(vf_text(CUBE_VERTS, CUBE_QUADS[1:]))
    return path


def test_open_mesh_error_names_fill_holes_and_the_hole(run, tmp_path):
    path = open_cube(tmp_path)
    res = run("inspect", path)
    assert res.exit_code == 1
    assert res.stderr == (f"massprops: error: {path}: mesh is not closed: 4 boundary edges (total "
                          f"length 4 m in 1 boundary loop, the largest of 4 edges spanning 1 m² "
                          f"(20% of the surface area)); use --fill-holes with --max-hole 0.21 "
                          f"to cap them (the largest is above the default limit 0.1), --shell "
                          f"THICKNESS for a thin-walled or open part, or --allow-open to "
                          f"compute anyway\n")
    res = run("inspect", "--json", "--fill-holes", "--max-hole", "0.21", path)
    assert res.exit_code == 0, res.stderr  # what the message says works


def test_a_small_hole_suggests_fill_holes_alone_which_works(run, tmp_path):
    lines = (SAMPLES / "torus.obj").read_text().splitlines()
    first_face = next(i for i, line in enumerate(lines) if line.startswith("f "))
    path = tmp_path / "holed.obj"
    path.write_text("\n".join(lines[:first_face] + lines[first_face + 1:]) + "\n")
    res = run("inspect", path)
    assert res.exit_code == 1
    assert res.stderr.endswith("; use --fill-holes to cap them, or --allow-open to compute "
                               "anyway\n")
    assert run("inspect", "--fill-holes", path).exit_code == 0


def test_fill_holes_refuses_an_opening_then_caps_it_when_allowed(run, tmp_path):
    path = open_cube(tmp_path)
    res = run("inspect", "--fill-holes", path)
    assert res.exit_code == 1
    assert res.stderr == (f"massprops: error: {path}: boundary loop 1 of 1 (4 edges, length 4 m) "
                          f"would need a cap of 1 m², 20% of the surface area: too large to be a "
                          f"hole (limit 0.1 of the surface; raise it with --max-hole 0.21, or "
                          f"use --shell for a thin-walled or open part)\n")
    res = run("inspect", "--json", "--fill-holes", "--max-hole", "0.25", path)
    assert res.exit_code == 0, res.stderr
    (out,) = json_lines(res.stdout)
    assert out["volume"] == 1.0 and out["center_of_mass"] == [0.5, 0.5, 0.5]
    holes = out["repairs"]["fill_holes"]
    assert holes["holes"] == 1 and holes["area"] == 1.0 and holes["area_fraction"] == 0.2
    assert holes["cap_volume_spread"] == 0.0


def test_shell_thickness_is_in_metres_whatever_the_unit(run, tmp_path):
    """A 2000 × 1000 mm sheet, 2 mm steel: 2 m² × 0.002 m × 7850 kg/m³ = 31.4 kg."""
    path = tmp_path / "sheet.vf"
    path.write_text(vf_text([[0, 0, 0], [2000, 0, 0], [2000, 1000, 0], [0, 1000, 0]],
                            [[0, 1, 2, 3]]))
    res = run("inspect", "--json", "--shell", "0.002", "--unit", "mm", "--density", "7850", path)
    assert res.exit_code == 0, res.stderr
    (out,) = json_lines(res.stdout)
    assert out["mass"] == pytest.approx(31.4, rel=1e-14)
    assert out["repairs"]["shell"]["thickness"] == 0.002
    assert out["repairs"]["shell"]["area"] == pytest.approx(2.0, rel=1e-15)
    m = 31.4
    assert out["inertia"][2][2] == pytest.approx(m * (4 + 1) / 12, rel=1e-14)
    assert out["inertia"][0][0] == pytest.approx(m * (1 + 0.002**2) / 12, rel=1e-14)
    assert out["warnings"] == []


@pytest.mark.parametrize("args", [
    ["--max-hole", "0.2"], ["--fill-holes", "--max-hole", "2"], ["--shell", "-1"],
    ["--shell", "0"], ["--union", "--density", "1", "--mass", "2"],
], ids=["max-hole-alone", "max-hole-range", "shell-negative", "shell-zero", "density-and-mass"])
def test_repair_usage_errors_exit_2(run, tmp_path, args):
    res = run("inspect", *args, open_cube(tmp_path))
    assert res.exit_code == 2


def test_help_lists_the_repairs(run):
    text = run("inspect", "--help").stdout
    for option in ("--union", "--shell THICKNESS", "--fill-holes", "--max-hole FRACTION"):
        assert option in text
    assert "METRES" in text


def test_align_union_writes_the_united_mesh(run, tmp_path):
    path = boxes_vf(tmp_path / "two.vf", OVERLAP)
    out_path = tmp_path / "aligned.obj"
    res = run("align", "--json", "--union", path, out_path)
    assert res.exit_code == 0, res.stderr
    (out,) = json_lines(res.stdout)
    assert out["repairs"]["union"]["volume_after"] == pytest.approx(15.0)
    again = run("inspect", "--json", out_path)
    assert again.exit_code == 0 and again.stderr == ""  # one clean solid: no overlap warning
    (check,) = json_lines(again.stdout)
    assert check["volume"] == pytest.approx(15.0, rel=1e-14)
    assert check["mesh"]["components"] == 1
    assert np.allclose(check["center_of_mass"], 0, atol=1e-14)
    j = np.array(check["inertia"])
    assert np.allclose(j, np.diag(np.diag(j)), atol=1e-13)


def test_align_fill_holes_writes_the_closed_mesh(run, tmp_path):
    out_path = tmp_path / "closed.obj"
    res = run("align", "--fill-holes", "--max-hole", "0.3", open_cube(tmp_path), out_path)
    assert res.exit_code == 0, res.stderr
    again = run("inspect", "--json", out_path)
    assert again.exit_code == 0, again.stderr
    (check,) = json_lines(again.stdout)
    assert check["mesh"]["closed"] is True and check["volume"] == pytest.approx(1.0, rel=1e-15)


# --- scene ---------------------------------------------------------------------------------------
def test_scene_body_repairs_match_inspect(run, tmp_path):
    boxes_vf(tmp_path / "two.vf", OVERLAP)
    open_cube(tmp_path, "open.vf")
    cases = [("{mesh: two.vf, union: true}", ["--union"], "two.vf"),
             ("{mesh: open.vf, fill_holes: true, shell: 0.01, density: 1000}",
              ["--fill-holes", "--max-hole", "0.25", "--shell", "0.01", "--density", "1000"],
              "open.vf"),
             ("{mesh: open.vf, shell: 0.002, mass: 3}", ["--shell", "0.002", "--mass", "3"],
              "open.vf")]
    for body, options, mesh in cases[:1] + cases[2:]:
        (tmp_path / "scene.yaml").write_text(f"body: {body}\n" + TIME)
        scene = load_scene(tmp_path / "scene.yaml")
        res = run("inspect", "--json", *options, tmp_path / mesh)
        (out,) = json_lines(res.stdout)
        assert scene.body.mass == pytest.approx(out["mass"], rel=1e-14)
        np.testing.assert_allclose(scene.body.center_of_mass, out["center_of_mass"], atol=1e-14)
        np.testing.assert_allclose(scene.body.inertia_body, out["inertia"], rtol=1e-12,
                                   atol=1e-14)
    # fill_holes in a scene uses the default limit: the open cube's face is an opening
    (tmp_path / "scene.yaml").write_text(f"body: {cases[1][0]}\n" + TIME)
    with pytest.raises(InputError) as info:
        load_scene(tmp_path / "scene.yaml")
    assert "too large to be a hole" in str(info.value) and "body.mesh" in str(info.value)


def test_scene_open_mesh_error_words_the_fix_as_keys(tmp_path):
    open_cube(tmp_path, "open.vf")
    (tmp_path / "scene.yaml").write_text("body: {mesh: open.vf}\n" + TIME)
    with pytest.raises(InputError) as info:
        load_scene(tmp_path / "scene.yaml")
    message = str(info.value)
    assert ("use fill_holes: true with max_hole 0.21 to cap them (the largest is above the "
            "default limit 0.1), shell THICKNESS for a thin-walled or open part, or "
            "allow_open: true to compute anyway") in message
    assert "--" not in message


def test_scene_repair_keys_are_checked(tmp_path):
    open_cube(tmp_path, "open.vf")
    for body, key in (("{mesh: open.vf, union: 1}", "body.union"),
                      ("{mesh: open.vf, shell: -2}", "body.shell")):
        (tmp_path / "scene.yaml").write_text(f"body: {body}\n" + TIME)
        with pytest.raises(InputError, match=key):
            load_scene(tmp_path / "scene.yaml")
