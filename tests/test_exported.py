"""Meshes as CAD and asset tools export them: round-off cracks, zero-area slivers, OBJ line
elements. Each file here is generated from an intended solid whose exact values are known (the
rational oracle in conftest, or a box's closed form); the result must equal them within its own
error bars, and a real gap must still be refused.
"""

from __future__ import annotations

import struct
from fractions import Fraction

import numpy as np
import pytest
from conftest import CUBE_QUADS, CUBE_VERTS, exact_mass_properties, json_lines
from hypothesis import given, settings
from hypothesis import strategies as st

from massprops.errors import MeshTopologyError
from massprops.inspection.file import inspect_file
from massprops.mesh.geometry import exactly_flat
from massprops.mesh.weld import near_groups
from massprops.tolerances import EPS, NEAR_WELD_ULPS

SIZE = np.array([0.05, 0.03, 0.02])  # a small part, in metres


def box_corners(offset) -> np.ndarray:
    return np.array(CUBE_VERTS, float) * SIZE + np.asarray(offset, float)


def per_face_obj(corners: np.ndarray, noise_ulps: int, seed: int = 1, extra: str = "") -> str:
    """The box as an exporter writes it: every quad with its own copies of its corners, each
    coordinate moved by up to ``noise_ulps`` ulps (the copies no longer agree bit for bit)."""
    rng = np.random.default_rng(seed)
    lines, n = [], 0
    for quad in CUBE_QUADS:
        for k in quad:
            v = corners[k] + rng.integers(-noise_ulps, noise_ulps + 1, 3) * np.spacing(
                np.abs(corners[k]))
            lines.append("v " + " ".join(repr(float(x)) for x in v))
        lines.append(f"f {n + 1} {n + 2} {n + 3} {n + 4}")
        n += 4
    return "\n".join(lines) + "\n" + extra


def tri_faces() -> np.ndarray:
    return np.array([[q[0], q[i], q[i + 1]] for q in CUBE_QUADS for i in (1, 2)])


def assert_equals_within_bars(result: dict, corners: np.ndarray) -> None:
    """volume, COM and inertia of ``result`` (inspect --json at density 1) against the exact
    values of the box on the unperturbed corners, within rounding + input error bars."""
    volume, com, inertia = exact_mass_properties(corners, tri_faces())
    bars = result["uncertainty"]

    def bar(key, *index):
        total = 0.0
        for kind in ("rounding", "input"):
            if bars[kind] is not None:
                value = bars[kind][key]
                for i in index:
                    value = value[i]
                total += value
        return total

    assert abs(Fraction(result["volume"]) - volume) <= Fraction(bar("volume"))
    for i in range(3):
        assert abs(Fraction(result["center_of_mass"][i]) - com[i]) <= Fraction(
            bar("center_of_mass", i))
        for j in range(3):
            assert abs(Fraction(result["inertia"][i][j]) - inertia[i][j]) <= Fraction(
                bar("inertia", i, j))


# --- round-off cracks -------------------------------------------------------------------------
@pytest.mark.parametrize("offset", [(0.1, -0.2, 0.3), (0.0, 0.0, 0.0), (1e3, -2e3, 5e2)],
                         ids=["near", "at-origin", "far"])
@pytest.mark.parametrize("noise", [1, 3])
def test_a_cracked_box_is_welded_and_equals_the_intended_box(tmp_path, run, offset, noise):
    corners = box_corners(offset)
    path = tmp_path / "cracked.obj"
    path.write_text(per_face_obj(corners, noise))
    result = run("inspect", path, "--json")
    assert result.exit_code == 0, result.stderr
    (out,) = json_lines(result.stdout)
    weld = out["repairs"]["weld"]
    assert 0 < weld["vertices"] <= 24 - 8
    assert weld["max_distance"] <= np.sqrt(3) * weld["tolerance"]
    assert weld["tolerance"] == NEAR_WELD_ULPS * EPS * float(np.abs(
        np.loadtxt(path, usecols=(1, 2, 3), comments=("f", "#"))).max())
    assert "closed round-off cracks: welded" in result.stderr
    assert out["mesh"]["closed"] and out["mesh"]["components"] == 1
    assert out["uncertainty"]["input"] is not None
    assert_equals_within_bars(out, corners)


def test_a_real_gap_is_still_refused(tmp_path, run):
    """A crack a thousand times wider than round-off is a modelling error, not noise."""
    corners = box_corners((0.1, -0.2, 0.3))
    text = per_face_obj(corners, 0).splitlines()
    x = float(text[0].split()[1])
    text[0] = f"v {x + 1e-12!r} " + " ".join(text[0].split()[2:])
    path = tmp_path / "gap.obj"
    path.write_text("\n".join(text) + "\n")
    result = run("inspect", path)
    assert result.exit_code == 1
    assert "mesh is not closed" in result.stderr and "Traceback" not in result.stderr


def test_a_missing_face_is_still_refused(tmp_path, run):
    corners = box_corners((0.1, -0.2, 0.3))
    text = per_face_obj(corners, 1).splitlines()
    path = tmp_path / "open.obj"
    path.write_text("\n".join(text[:-1]) + "\n")  # the last quad's face line is gone
    result = run("inspect", path)
    assert result.exit_code == 1 and "mesh is not closed" in result.stderr


def test_binary_stl_cracks_are_welded_at_float32_round_off(tmp_path, run):
    """A float32 file's copies differ by float32 ulps (a float64 corner rounded twice)."""
    corners = box_corners((0.1, -0.2, 0.3)).astype(np.float32).astype(np.float64)
    rng = np.random.default_rng(2)
    records = b""
    for a, b, c in tri_faces():
        tri = [np.float32(corners[k]) + rng.integers(-1, 2, 3).astype(np.float32)
               * np.spacing(np.abs(np.float32(corners[k]))) for k in (a, b, c)]
        records += struct.pack("<12fH", 0, 0, 0, *np.concatenate(tri).tolist(), 0)
    path = tmp_path / "cracked.stl"
    path.write_bytes(b"\0" * 80 + struct.pack("<I", 12) + records)
    result = run("inspect", path, "--json")
    assert result.exit_code == 0, result.stderr
    (out,) = json_lines(result.stdout)
    assert out["repairs"]["weld"]["vertices"] > 0
    assert_equals_within_bars(out, corners)


def test_near_groups_weld_copies_but_not_a_run_of_distinct_points():
    tol = 1e-15
    copies = np.array([[1.0, 2.0, 3.0], [1.0 + 4e-16, 2.0, 3.0], [1.0, 2.0 - 4e-16, 3.0]])
    assert near_groups(copies, tol).tolist() == [0, 0, 0]
    chain = np.array([[k * 0.9e-15, 0.0, 0.0] for k in range(4)])  # each step within tol
    assert near_groups(chain, tol).tolist() == [0, 1, 2, 3]
    apart = np.array([[0.0, 0.0, 0.0], [2e-15, 0.0, 0.0]])
    assert near_groups(apart, tol).tolist() == [0, 1]


# --- zero-area faces --------------------------------------------------------------------------
def sliver_obj(collinear: bool) -> str:
    """The closed box, plus two collinear slivers along edges (each adds edges nothing balances)
    and two faces with a repeated corner. ``collinear`` False moves one sliver's middle corner an
    ulp off its edge: a real, if tiny, triangle that leaves the surface open."""
    corners = box_corners((0.1, -0.2, 0.3))
    mid = (corners[0] + corners[1]) / 2  # on the edge, exactly (only x differs)
    quarter = corners[2] * 0.25 + corners[6] * 0.75  # only z differs: exactly on the edge too
    if not collinear:
        mid[1] = np.nextafter(mid[1], np.inf)
    lines = ["v " + " ".join(repr(float(x)) for x in v) for v in (*corners, mid, quarter)]
    lines += ["f " + " ".join(str(i + 1) for i in q) for q in CUBE_QUADS]
    lines += ["f 1 9 2", "f 3 10 7", "f 3 3 4", "f 5 6 5"]
    return "\n".join(lines) + "\n"


def test_exactly_flat_slivers_are_left_out_of_the_topology(tmp_path, run):
    path = tmp_path / "sliver.obj"
    path.write_text(sliver_obj(collinear=True))
    result = run("inspect", path, "--json")
    assert result.exit_code == 0, result.stderr
    (out,) = json_lines(result.stdout)
    assert out["mesh"]["degenerate_faces"] == 4 and out["mesh"]["closed"]
    assert "left 2 zero-area faces" in result.stderr
    assert "repairs" not in out  # nothing moved
    assert_equals_within_bars(out, box_corners((0.1, -0.2, 0.3)))


def test_a_sliver_an_ulp_off_its_line_is_a_real_triangle(tmp_path, run):
    path = tmp_path / "thin.obj"
    path.write_text(sliver_obj(collinear=False))
    result = run("inspect", path)
    assert result.exit_code == 1 and "mesh is not closed" in result.stderr


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(-1e3, 1e3, allow_nan=False, allow_subnormal=False), min_size=9,
                max_size=9),
       st.floats(-2.0, 3.0, allow_nan=False), st.integers(-2, 2), st.integers(0, 2))
def test_exactly_flat_agrees_with_rational_arithmetic(coords, t, nudge, axis):
    """Corners a, b and c = a + t (b - a) rounded, then nudged by a few ulps: every case near
    the line, where float cross products cannot decide, against the exact rational test."""
    a, b = np.array(coords[:3]), np.array(coords[3:6])
    c = a + t * (b - a)
    c[axis] += nudge * np.spacing(abs(c[axis]))
    points = np.array([a, b, c])
    got = exactly_flat(points, np.array([[0, 1, 2]]))[0]
    fa, fb, fc = ([Fraction(float(x)) for x in p] for p in points)
    u = [q - p for p, q in zip(fa, fb)]
    w = [q - p for p, q in zip(fa, fc)]
    cross = (u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0])
    assert got == all(x == 0 for x in cross)


# --- OBJ line elements --------------------------------------------------------------------------
def test_obj_line_elements_are_skipped_with_one_warning(tmp_path):
    corners = box_corners((0.1, -0.2, 0.3))
    body = ["v " + " ".join(repr(float(x)) for x in v) for v in corners]
    faces = ["f " + " ".join(str(i + 1) for i in q) for q in CUBE_QUADS]
    clean = tmp_path / "clean.obj"
    clean.write_text("\n".join(body + faces) + "\n")
    noisy = tmp_path / "noisy.obj"
    noisy.write_text("\n".join(body + faces[:3] + ["f 1 2", "l 1 2 3 4", "f 5"] + faces[3:]
                               + ["l 7 8"]) + "\n")
    a, b = inspect_file(clean), inspect_file(noisy)
    assert b.warnings[0] == ("skipped 2 faces with fewer than 3 vertices (first on line 12) and "
                             "2 polyline ('l') lines (first on line 13): edges, not surface")
    assert b.properties.volume == a.properties.volume
    assert np.array_equal(b.properties.inertia, a.properties.inertia)
    assert b.mesh.n_faces == 6


def test_an_obj_of_line_elements_only_is_refused(tmp_path, run):
    path = tmp_path / "lines.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2\nl 1 2 3\n")
    result = run("inspect", path)
    assert result.exit_code == 1
    assert "found 3 vertices and 0 faces" in result.stderr


def test_open_after_every_repair_names_the_gap(tmp_path):
    """Slivers and cracks together with a real hole: refused, nothing silently welded."""
    corners = box_corners((0.1, -0.2, 0.3))
    text = per_face_obj(corners, 2).splitlines()
    path = tmp_path / "hole.obj"
    path.write_text("\n".join(text[:-1] + ["f 1 1 2"]) + "\n")
    with pytest.raises(MeshTopologyError, match="not closed"):
        inspect_file(path)


def test_fill_holes_welds_the_cracks_and_caps_only_the_real_hole(tmp_path, run):
    """A cracked box missing one face: the cracks are welded (not capped as slivers of holes),
    the missing face is the one hole, and the result is the intended box within its bars."""
    corners = box_corners((0.1, -0.2, 0.3))
    text = per_face_obj(corners, 2).splitlines()
    path = tmp_path / "cracked_open.obj"
    path.write_text("\n".join(text[:-1]) + "\n")
    result = run("inspect", path, "--json", "--fill-holes", "--max-hole", "0.5")
    assert result.exit_code == 0, result.stderr
    (out,) = json_lines(result.stdout)
    assert out["repairs"]["weld"]["vertices"] > 0
    assert out["repairs"]["fill_holes"]["holes"] == 1
    assert "closed round-off cracks" in result.stderr
    assert_equals_within_bars(out, corners)
