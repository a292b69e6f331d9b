"""``model --write`` repairs that say what they change (issue 32.3): ``--only-invalid`` replaces
only the inertials that fail a validity test, ``--keep-mass`` keeps each stated mass with the
geometry's distribution; one note per link rewritten."""

from __future__ import annotations

import shutil

from conftest import ROOT, json_lines

ARM = ROOT / "tests" / "robots" / "arm_description"
PLACEHOLDER = '<inertia ixx="0.01" ixy="0" ixz="0" iyy="0.01" iyz="0" izz="0.01"/>'
BROKEN = '<inertia ixx="0.0125112" ixy="0" ixz="0" iyy="0.0125112" iyz="0" izz="0.03"/>'


def _arm(tmp_path):
    """The arm with upper_arm's tensor a (valid) placeholder and forearm's izz 0.03 > 0.0125112
    × 2: invalid."""
    shutil.copytree(ARM, tmp_path / "arm_description")
    path = tmp_path / "arm_description" / "urdf" / "arm.urdf"
    text = path.read_text()
    text = text.replace('<inertia ixx="0.0441667" ixy="0.003" ixz="-0.006" iyy="0.0421667" '
                        'iyz="0.012" izz="0.0141667"/>', PLACEHOLDER)
    text = text.replace('<inertia ixx="0.0125112" ixy="0" ixz="0" iyy="0.0125112" iyz="0" '
                        'izz="0.00102186"/>', BROKEN)
    assert PLACEHOLDER in text and BROKEN in text
    path.write_text(text)
    return path


def test_only_invalid_replaces_only_what_fails_validity(tmp_path, run):
    path = _arm(tmp_path)
    out = path.with_name("out.urdf")  # beside it: the meshes are found as from the input
    result = run("model", path, "--write", out, "--only-invalid")
    assert result.exit_code == 0, result.stderr
    assert "rewrote the inertial of forearm (1 of 4" in result.stderr
    assert "the other 3 are valid (--only-invalid) and are kept" in result.stderr
    notes = [line for line in result.stderr.splitlines() if line.startswith("massprops:   ")]
    assert len(notes) == 1 and "forearm: invalid (principal moments" in notes[0]
    assert "mass 1.2 kg kept" in notes[0]
    text = out.read_text()
    assert PLACEHOLDER in text and BROKEN not in text  # the valid placeholder stays
    rows = {r["link"]: r for r in json_lines(run("model", out, "--json").stdout)}
    assert rows["forearm"]["comparison"]["inertia_rel"] < 1e-12
    assert all(v for v in rows["forearm"]["valid"].values())


def test_keep_mass_keeps_each_stated_mass(tmp_path, run):
    """With --density 1000 the computed masses are the geometry's; --keep-mass writes the
    stated ones with the geometry's distribution, which is what the default (stated mass kept)
    computes: the written file then agrees with its geometry to round-off."""
    path = _arm(tmp_path)
    out = path.with_name("out.urdf")  # beside it: the meshes are found as from the input
    result = run("model", path, "--write", out, "--density", "1000", "--keep-mass")
    assert result.exit_code == 0, result.stderr
    notes = [line for line in result.stderr.splitlines() if line.startswith("massprops:   ")]
    assert len(notes) == 4 and all(" kg kept" in n for n in notes), notes
    rows = {r["link"]: r for r in json_lines(run("model", out, "--json").stdout)}
    stated = {r["link"]: r["stated"]["mass"]
              for r in json_lines(run("model", path, "--json").stdout) if r["stated"]}
    for name in ("base_link", "upper_arm", "forearm", "wrist"):
        assert rows[name]["stated"]["mass"] == stated[name]
        assert rows[name]["comparison"]["inertia_rel"] < 1e-12
    # without --keep-mass the geometry's mass at 1000 kg/m³ is written, said per link
    result = run("model", path, "--write", tmp_path / "dense.urdf", "--density", "1000")
    assert "upper_arm: off by" in result.stderr and "mass 2.5 -> " in result.stderr


def test_the_write_options_need_write(run):
    for flag in ("--keep-mass", "--only-invalid"):
        result = run("model", ARM / "urdf" / "arm.urdf", flag)
        assert result.exit_code == 2
        assert f"{flag} changes what --write writes; give --write OUT" in result.stderr
