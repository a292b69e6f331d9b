"""The command line: exit codes, one-line errors, parsed --json against closed forms."""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np
import pytest
from conftest import CUBE_QUADS, SAMPLES, box_vf, json_lines, rot_z, vf_text

from massprops.errors import DivergenceError, MeshFormatError, UsageError, exit_code

# The notes' cuboid (slide 14), from its definition: 3×2×2, turned 30° about z.
R30 = rot_z(30.0)
CUBOID_J = R30 @ np.diag([8.0, 13.0, 13.0]) @ R30.T
CONTRACT_KEYS = {"file", "volume", "mass", "density", "center_of_mass", "inertia",
                 "principal_moments", "principal_axes", "mesh", "warnings"}


def rel(a, b, scale) -> float:
    return float(np.max(np.abs(np.asarray(a) - np.asarray(b)))) / scale


@pytest.mark.parametrize("name", ["cuboid.vf", "cuboid.vtx", "cuboid.fac", "cuboid.obj"])
def test_notes_cuboid_every_exact_format(run, name):
    res = run("inspect", "--json", SAMPLES / name)
    assert res.exit_code == 0, res.stderr
    (out,) = json_lines(res.stdout)
    assert CONTRACT_KEYS <= out.keys()
    assert abs(out["mass"] - 12.0) <= 8 * np.spacing(12.0)
    assert out["density"] == 1.0
    assert rel(out["center_of_mass"], [0, 0, 0], 1.0) < 1e-14
    assert rel(out["inertia"], CUBOID_J, 13.0) < 1e-14
    assert rel(out["principal_moments"], [8, 13, 13], 13.0) < 1e-14
    assert rel(out["principal_axes"], R30, 1.0) < 1e-14
    assert out["mesh"]["closed"] is True and out["warnings"] == []


def test_binary_stl_within_its_float32_error_bar(run):
    res = run("inspect", "--json", SAMPLES / "cuboid.stl")
    assert res.exit_code == 0, res.stderr
    (out,) = json_lines(res.stdout)
    bars = out["uncertainty"]["input"]
    assert bars is not None
    assert abs(out["mass"] - 12.0) <= bars["mass"] + out["uncertainty"]["rounding"]["mass"]
    assert np.all(np.abs(np.array(out["inertia"]) - CUBOID_J) <= np.array(bars["inertia"]) + 1e-14)


def test_human_table_prints_exact_mass_without_colour(run):
    res = run("inspect", SAMPLES / "cuboid.vf")
    assert res.exit_code == 0
    assert "\x1b[" not in res.stdout  # not a terminal: no colour codes
    assert "12" in res.stdout and "11.99" not in res.stdout and "12.00000" not in res.stdout
    assert "9.25" in res.stdout and "-2.16506350946" in res.stdout


def test_density_mass_and_unit(run, tmp_path):
    cube = box_vf(tmp_path / "cube.vf", size=(2.0, 2.0, 2.0))
    (d,) = json_lines(run("inspect", "--json", "--density", "7850", cube).stdout)
    assert math.isclose(d["mass"], 8 * 7850, rel_tol=1e-15)
    assert rel(d["inertia"], np.eye(3) * 8 * 7850 * 8 / 12, 8 * 7850 * 8 / 12) < 1e-15
    (m,) = json_lines(run("inspect", "--json", "--mass", "2", cube).stdout)
    assert math.isclose(m["mass"], 2.0, rel_tol=1e-15) and math.isclose(m["density"], 0.25)
    (mm,) = json_lines(run("inspect", "--json", "--unit", "mm", cube).stdout)
    # 2 mm cube at density 1: volume 8e-9 m³, inertia m(a²+a²)/12 scales as length⁵
    assert math.isclose(mm["volume"], 8e-9, rel_tol=1e-14)
    assert math.isclose(mm["inertia"][0][0], 8e-9 * 8e-6 / 12, rel_tol=1e-14)
    assert rel(mm["center_of_mass"], [1e-3] * 3, 1e-3) < 1e-14


@pytest.mark.parametrize("args", [["--density", "1", "--mass", "2"], ["--density", "-1"],
                                  ["--mass", "0"], ["--density", "nan"], ["--unit", "furlong"]],
                         ids=["both", "negative", "zero-mass", "nan", "bad-unit"])
def test_usage_errors_exit_2(run, args):
    res = run("inspect", *args, SAMPLES / "cube.obj")
    assert res.exit_code == 2 and res.stdout == ""


def test_stdin_needs_format_and_reads(run):
    text = (SAMPLES / "cuboid.obj").read_text()
    assert run("inspect", "-", input=text).exit_code == 2
    res = run("inspect", "--json", "--input-format", "obj", "-", input=text)
    assert res.exit_code == 0, res.stderr
    (out,) = json_lines(res.stdout)
    assert abs(out["mass"] - 12) < 1e-13


def test_several_inputs_good_ones_still_reported(run, tmp_path):
    res = run("inspect", "--json", SAMPLES / "cube.obj", tmp_path / "missing.obj",
              SAMPLES / "tetrahedron.obj")
    assert res.exit_code == 1
    assert [o["file"] for o in json_lines(res.stdout)] == [str(SAMPLES / "cube.obj"),
                                                           str(SAMPLES / "tetrahedron.obj")]
    (line,) = res.stderr.strip().splitlines()
    assert "missing.obj" in line and "Traceback" not in res.stderr


def _bad_inputs(tmp):
    """name -> path of an input that must fail with exit 1 and one line naming the file."""
    cases = {}

    def put(name, data):
        p = tmp / name
        p.write_bytes(data if isinstance(data, bytes) else data.encode())
        cases[name] = p

    put("empty.obj", b"")
    put("garbage.stl", os.urandom(1000))
    put("garbage.obj", b"\x00\xff\xfe garbage \x00" * 20)
    head = b"binary".ljust(80, b" ")
    put("truncated.stl", head + (10).to_bytes(4, "little") + b"\x00" * 50 * 3)
    put("huge-count.stl", head + (2**32 - 1).to_bytes(4, "little") + b"\x00" * 100)
    put("nan.vf", vf_text([[float("nan"), 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]],
                          [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]))
    put("inf.obj", "v inf 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    put("out-of-range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 9\n")
    put("zero-index.vf", "4\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n1\n0 1 2\n")
    put("count-mismatch.vf", "5\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n4\n1 3 2\n")
    put("unknown.xyz", "1 2 3\n")
    open_cube = [q for q in CUBE_QUADS[1:]]
    put("open.vf", vf_text(CUBE_VERTS_F, open_cube))
    put("flat.vf", vf_text([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 1]]))
    (tmp / "a-directory.obj").mkdir()
    cases["a-directory.obj"] = tmp / "a-directory.obj"
    cases["missing.stl"] = tmp / "missing.stl"
    return cases


CUBE_VERTS_F = [[float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1)] for i in range(8)]
BAD_NAMES = ["empty.obj", "garbage.stl", "garbage.obj", "truncated.stl", "huge-count.stl",
             "nan.vf", "inf.obj", "out-of-range.obj", "zero-index.vf", "count-mismatch.vf",
             "unknown.xyz", "open.vf", "flat.vf", "a-directory.obj", "missing.stl"]


@pytest.mark.parametrize("name", BAD_NAMES)
def test_bad_input_one_line_exit_1(run, tmp_path, name):
    path = _bad_inputs(tmp_path)[name]
    res = run("inspect", "--json", path)
    assert res.exit_code == 1, (res.stdout, res.stderr)
    assert res.stdout == ""
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and name in lines[0] and lines[0].startswith("massprops: error: ")


def test_open_mesh_allowed_says_so(run, tmp_path):
    path = _bad_inputs(tmp_path)["open.vf"]
    res = run("inspect", "--json", "--allow-open", path)
    assert res.exit_code == 0
    (out,) = json_lines(res.stdout)
    assert out["mesh"]["closed"] is False and out["warnings"]
    assert math.isfinite(out["mass"])


def test_inside_out_mesh_is_flipped_with_warning(run, tmp_path):
    path = box_vf(tmp_path / "inv.vf", faces=[q[::-1] for q in CUBE_QUADS])
    res = run("inspect", "--json", path)
    assert res.exit_code == 0
    (out,) = json_lines(res.stdout)
    assert math.isclose(out["volume"], 1.0, rel_tol=1e-15)
    assert any("flip" in w for w in out["warnings"])
    assert "warning" in res.stderr


@pytest.mark.parametrize("ext", ["obj", "vf", "ply", "off", "stl"])
def test_align_output_is_in_principal_frame(run, tmp_path, ext):
    out_path = tmp_path / f"aligned.{ext}"
    res = run("align", "--json", SAMPLES / "cuboid.obj", out_path)
    assert res.exit_code == 0, res.stderr
    (info,) = json_lines(res.stdout)
    assert rel(np.array(info["rotation"]), R30.T, 1.0) < 1e-14
    (again,) = json_lines(run("inspect", "--json", out_path).stdout)
    tol = 1e-6 if ext == "stl" else 1e-13  # binary STL stores float32 (documented)
    j = np.array(again["inertia"])
    assert np.max(np.abs(j - np.diag(np.diag(j)))) <= tol * 13
    assert rel(np.diag(j), [8, 13, 13], 13) < tol
    assert rel(again["center_of_mass"], [0, 0, 0], 1.0) < tol


def test_align_map_matches_json(run, tmp_path):
    src = box_vf(tmp_path / "box.vf", size=(1.0, 2.0, 3.0), offset=(1e6, -2e6, 5.0))
    out_path = tmp_path / "out.vf"
    (info,) = json_lines(run("align", "--json", src, out_path).stdout)
    (again,) = json_lines(run("inspect", "--json", out_path).stdout)
    # box 1×2×3: moments m(b²+c²)/12 ascending = (3²+2²... ) -> x-axis largest, z smallest
    m = 6.0
    expected = sorted([m * (4 + 9) / 12, m * (1 + 9) / 12, m * (1 + 4) / 12])
    assert rel(np.diag(again["inertia"]), expected, expected[-1]) < 1e-13
    assert rel(info["principal_moments"], expected, expected[-1]) < 1e-13
    c = np.array([1e6, -2e6, 5.0]) + [0.5, 1.0, 1.5]
    rot, tr = np.array(info["rotation"]), np.array(info["translation"])
    assert np.allclose(rot @ c + tr, 0, atol=1e-9)  # |c| ~ 2e6: translation carries its ulps


def test_align_never_overwrites(run, tmp_path):
    src = box_vf(tmp_path / "box.vf")
    before = src.read_bytes()
    res = run("align", src, src)
    assert res.exit_code == 1 and src.read_bytes() == before
    out_path = tmp_path / "out.obj"
    out_path.write_text("keep me")
    res = run("align", src, out_path)
    assert res.exit_code == 1 and out_path.read_text() == "keep me"
    assert "--force" in res.stderr
    assert run("align", "--force", src, out_path).exit_code == 0
    assert out_path.read_text() != "keep me"
    assert run("align", "--force", src, src).exit_code == 1 and src.read_bytes() == before


def test_real_process_entry_points(tmp_path):
    """python -m massprops: exit codes and no traceback, through the real main()."""
    cmd = [sys.executable, "-m", "massprops"]
    ok = subprocess.run(cmd + ["inspect", "--json", str(SAMPLES / "cube.obj")],
                        capture_output=True, text=True)
    assert ok.returncode == 0 and json_lines(ok.stdout)[0]["volume"] == pytest.approx(1.0)
    bad = subprocess.run(cmd + ["inspect", str(tmp_path / "nope.obj")], capture_output=True,
                         text=True)
    assert bad.returncode == 1 and "Traceback" not in bad.stderr and "nope.obj" in bad.stderr
    usage = subprocess.run(cmd + ["inspect", "--density", "x", "a.obj"], capture_output=True,
                           text=True)
    assert usage.returncode == 2
    assert subprocess.run(cmd + ["--help"], capture_output=True).returncode == 0


def test_unit_choices_are_the_readers_units():
    from massprops.cli import UNIT_CHOICES
    from massprops.io import UNITS

    assert set(UNIT_CHOICES) == set(UNITS)


@pytest.mark.parametrize("exc,code", [
    (MeshFormatError("x"), 1),
    (UsageError("x"), 2),
    (DivergenceError("x"), 3),
    (PermissionError(13, "denied", "out.obj"), 1),
    (ZeroDivisionError("bug"), 3),
    (KeyboardInterrupt(), 130),
], ids=["input", "usage", "computation", "os-error", "bug", "interrupt"])
def test_exit_code_table(exc, code):
    assert exit_code(exc) == code


# --- no numpy warning on stderr (issue 30) --------------------------------------------------------
def _scaled_cube(path, scale: float):
    lines = [f"v {x * scale!r} {y * scale!r} {z * scale!r}"
             for x, y, z in ((i & 1, (i >> 1) & 1, (i >> 2) & 1) for i in range(8))]
    lines += ["f " + " ".join(str(i + 1) for i in q) for q in CUBE_QUADS]
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("scale", [1e300, 1e200])
def test_coordinates_too_large_exit_1_in_one_line(tmp_path, scale):
    """A real process: numpy's RuntimeWarnings went to stderr (12 lines) before exit 3."""
    cube = _scaled_cube(tmp_path / "big.obj", scale)
    cmd = [sys.executable, "-m", "massprops", "inspect", "--json", str(cube)]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert out.returncode == 1 and out.stdout == ""
    assert out.stderr == (
        f"massprops: error: {cube}: coordinates too large for float64 mass properties: vertex 2 "
        f"has |x| = {scale:.3g} m, but the inertia integrates coordinates to the fifth power, "
        "finite only for |x| below 6e+60 m (12 triangles); rescale the mesh or give the unit its "
        "coordinates are in (--unit)\n")


def test_density_beyond_float64_exit_1_in_one_line(tmp_path):
    cube = _scaled_cube(tmp_path / "big.obj", 1e60)
    cmd = [sys.executable, "-m", "massprops", "inspect", "--density", "1e300", str(cube)]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert out.returncode == 1 and out.stdout == ""
    lines = out.stderr.splitlines()
    assert len(lines) == 1 and "mass properties beyond float64's range" in lines[0], out.stderr


STRAY_WARNING = """
import sys, warnings
import massprops.inspection.file as inspection
from massprops.cli import main

real = inspection.read_mesh

def warning_read(*args, **kwargs):
    warnings.warn("overflow encountered in multiply", RuntimeWarning, stacklevel=1)
    return real(*args, **kwargs)

inspection.read_mesh = warning_read
main(sys.argv[1:])
"""


@pytest.mark.parametrize("debug", [False, True])
def test_a_stray_warning_never_reaches_stderr_without_debug(debug):
    """The process's entry ignores Python's warnings (a bug's noise, to be fixed at its cause);
    --debug shows them. A real process: the tests' own in-process runs keep every warning an
    error (pyproject's filterwarnings), so that a cause is never hidden from them."""
    args = [*(["--debug"] if debug else []), "inspect", "--json", "--jobs", "1",
            str(SAMPLES / "cube.obj")]
    out = subprocess.run([sys.executable, "-c", STRAY_WARNING, *args], capture_output=True,
                         text=True, timeout=60)
    assert out.returncode == 0 and json_lines(out.stdout)[0]["volume"] == pytest.approx(1.0)
    assert ("RuntimeWarning: overflow encountered in multiply" in out.stderr) is debug


# --- a bad --input-format is a usage error (issue 30) ---------------------------------------------
@pytest.mark.parametrize("command", ["inspect", "align"])
def test_unknown_input_format_is_a_usage_error_listing_the_formats(run, tmp_path, command):
    from massprops.io import input_formats

    args = [SAMPLES / "cube.obj"] + ([tmp_path / "out.obj"] if command == "align" else [])
    res = run(command, *args, "--input-format", "bogus")
    assert res.exit_code == 2 and res.stdout == ""
    assert res.stderr.splitlines()[-1] == (
        f"Error: Invalid value for '--input-format': 'bogus' is not one of "
        f"{', '.join(input_formats())}")
    assert not (tmp_path / "out.obj").exists()


def test_input_format_is_case_insensitive_with_a_dot(run):
    res = run("inspect", "--json", "--input-format", ".OBJ", SAMPLES / "cube.obj")
    assert res.exit_code == 0 and json_lines(res.stdout)[0]["volume"] == pytest.approx(1.0)


# --- --debug says settings as the command's options (issue 30) -------------------------------
def test_debug_traceback_says_settings_as_options(run, tmp_path):
    res = run("--debug", "align", SAMPLES / "open_box.obj", tmp_path / "out.obj")
    assert res.exit_code == 1
    assert "Traceback (most recent call last)" in res.stderr
    last = res.stderr.strip().splitlines()[-1]
    assert last.startswith("massprops.errors.MeshTopologyError: ")
    assert "use --fill-holes with --max-hole 0.21 to cap them" in last
    assert "--allow-open to compute anyway" in last and " allow_open " not in last


def test_debug_traceback_of_a_batch_says_settings_as_options(tmp_path):
    """A batch's failure goes through with --debug (the process's own handler printed it, with
    the library's keyword: "(unit)")."""
    cube = _scaled_cube(tmp_path / "big.obj", 1e300)
    cmd = [sys.executable, "-m", "massprops", "--debug", "inspect", str(cube)]
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=60)
    assert out.returncode == 1
    assert "Traceback (most recent call last)" in out.stderr
    assert out.stderr.rstrip().endswith("give the unit its coordinates are in (--unit)")
