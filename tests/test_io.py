"""Mesh files: round trips through every writer, each reader's features, every kind of bad input,
and the output guards (atomic, never over an input, never over a file without force).

Test meshes are built here from their definitions; file texts are written by hand here. The truth
is the mesh we started from (round trips), the hand-written file (readers), or a closed form.
"""

from __future__ import annotations

import io
import os
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from massprops.errors import (
    MeshFileError,
    MeshFormatError,
    OutputExistsError,
    UnknownFormatError,
    UsageError,
)
from massprops.io import (
    FORMATS,
    UNITS,
    input_formats,
    numtext,
    output_formats,
    read_mesh,
    write_mesh,
)
from massprops.io.atomic import atomic_write_bytes
from massprops.io.source import Source
from massprops.mesh.value import Mesh, fan_triangulate

# --- test meshes, from their definitions -------------------------------------------------------
# Unit cube: corner i at (i & 1, i >> 1 & 1, i >> 2 & 1); quads counter-clockwise from outside.
CUBE_QUADS = [[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4], [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]]
TETRA_FACES = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]


def make_mesh(vertices, polygons, name: str) -> Mesh:
    faces, sizes = fan_triangulate(np.concatenate([np.asarray(p) for p in polygons]),
                                   np.array([len(p) for p in polygons]))
    return Mesh(np.asarray(vertices, dtype=np.float64), faces, sizes, name=name)


def cube() -> Mesh:
    corners = [[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)]
    return make_mesh(corners, CUBE_QUADS, "cube")


def tetrahedron() -> Mesh:
    """Corner tetrahedron scaled and shifted by values without short binary forms (1/3, 0.1)."""
    corners = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
    return make_mesh(corners / 3 + [0.1, -2.5e-7, 12345.678], TETRA_FACES, "tetra")


def pentagonal_prism() -> Mesh:
    """Two pentagon caps and five quads: mixed polygon sizes."""
    angle = 2 * np.pi * np.arange(5) / 5
    ring = np.column_stack([np.cos(angle), np.sin(angle)])
    vertices = np.vstack([np.column_stack([ring, np.zeros(5)]),
                          np.column_stack([ring, np.ones(5)])])
    sides = [[i, (i + 1) % 5, 5 + (i + 1) % 5, 5 + i] for i in range(5)]
    return make_mesh(vertices, [[4, 3, 2, 1, 0], [5, 6, 7, 8, 9], *sides], "prism")


MESHES = {"cube": cube, "tetra": tetrahedron, "prism": pentagonal_prism}


def canonical(polygons) -> list[tuple[int, ...]]:
    """Polygons as a sorted list, each rotated to start at its smallest index: the cyclic order
    (the winding) is kept, the starting vertex and the order of faces are not."""
    out = []
    for p in polygons:
        p = [int(i) for i in p]
        k = p.index(min(p))
        out.append(tuple(p[k:] + p[:k]))
    return sorted(out)


def newell_normal(points: np.ndarray) -> np.ndarray:
    """Area vector of a planar polygon (Newell): |n| = 2 * area, direction by the winding."""
    nxt = np.roll(points, -1, axis=0)
    return np.cross(points, nxt).sum(axis=0)


def assert_same_surface(original: Mesh, back: Mesh) -> None:
    """``back`` triangulates ``original``'s polygons with the same winding (a reader that does its
    own triangulation): each triangle lies in one polygon, faces its way, and the areas add up."""
    polygons = original.polygons()
    total = 0.0
    for tri in back.faces:
        owners = [p for p in polygons if set(tri.tolist()) <= set(p.tolist())]
        assert len(owners) == 1
        n_tri = newell_normal(back.vertices[tri])
        assert n_tri @ newell_normal(original.vertices[owners[0]]) > 0
        total += np.linalg.norm(n_tri)
    expected = sum(np.linalg.norm(newell_normal(original.vertices[p])) for p in polygons)
    assert total == pytest.approx(expected, rel=1e-12)


def write_read(mesh: Mesh, fmt: str, directory: Path) -> Mesh:
    """Write ``mesh`` as ``fmt`` and read it back; asserts the input mesh was not mutated."""
    before = (mesh.vertices.copy(), mesh.faces.copy(),
              None if mesh.polygon_sizes is None else mesh.polygon_sizes.copy())
    path = directory / f"mesh{FORMATS[fmt].extensions[0]}"
    write_mesh(mesh, path)
    back = read_mesh(path)
    np.testing.assert_array_equal(mesh.vertices, before[0])
    np.testing.assert_array_equal(mesh.faces, before[1])
    if before[2] is not None:
        np.testing.assert_array_equal(mesh.polygon_sizes, before[2])
    assert back.name == str(path)
    return back


def assert_bits_equal(a: np.ndarray, b: np.ndarray) -> None:
    """Equal as bit patterns (so -0.0 != 0.0 and no tolerance)."""
    assert a.shape == b.shape and a.dtype == b.dtype == np.float64
    np.testing.assert_array_equal(a.view(np.int64), b.view(np.int64))


# How much of the file's structure each format gives back (by its definition / its reader).
KEEPS = {"obj": "polygons in order", "vf": "polygons in order", "vtx": "polygons in order",
         "off": "polygons in order", "ply": "polygons", "stl": "float32 soup"}


def test_every_writer_has_a_round_trip_expectation():
    assert set(output_formats()) == set(KEEPS)


ROUND_TRIPS = [(f, s) for f in sorted(KEEPS) for s in sorted(MESHES)]


@pytest.mark.parametrize(("fmt", "shape"), ROUND_TRIPS, ids=[f"{f}-{s}" for f, s in ROUND_TRIPS])
def test_round_trip(fmt, shape, tmp_path):
    mesh = MESHES[shape]()
    back = write_read(mesh, fmt, tmp_path)
    keeps = KEEPS[fmt]
    if keeps == "float32 soup":
        soup = mesh.vertices[mesh.faces].reshape(-1, 3).astype(np.float32).astype(np.float64)
        assert_bits_equal(back.vertices, soup)
        np.testing.assert_array_equal(back.faces, np.arange(soup.shape[0]).reshape(-1, 3))
        assert back.coordinate_dtype == np.float32
        return
    assert_bits_equal(back.vertices, mesh.vertices)
    assert back.coordinate_dtype == np.float64
    if keeps == "polygons in order":
        assert [p.tolist() for p in back.polygons()] == [p.tolist() for p in mesh.polygons()]
        np.testing.assert_array_equal(back.faces, mesh.faces)
    elif keeps == "polygons":
        assert canonical(back.polygons()) == canonical(mesh.polygons())
    else:
        assert_same_surface(mesh, back)


finite = st.floats(allow_nan=False, allow_infinity=False, width=64)


@pytest.mark.parametrize("fmt", ["obj", "vf", "off"])
@settings(max_examples=60, deadline=None)
@given(vertices=hnp.arrays(np.float64, st.tuples(st.integers(4, 12), st.just(3)), elements=finite))
def test_text_coordinates_read_back_bit_identical(fmt, vertices):
    """Any finite float64 (subnormals, -0.0, 1e308) survives the text writers and readers."""
    mesh = make_mesh(vertices, TETRA_FACES, "random")
    buffer = io.BytesIO()
    FORMATS[fmt].writer(mesh, buffer)
    back = read_mesh(io.BytesIO(buffer.getvalue()), format=fmt)
    assert_bits_equal(back.vertices, mesh.vertices)
    np.testing.assert_array_equal(back.faces, mesh.faces)


@pytest.mark.parametrize("fmt", ["obj", "vf", "off"])
@settings(max_examples=50, deadline=None)
@given(sizes=st.lists(st.integers(3, 40), min_size=1, max_size=12), data=st.data())
def test_text_formats_keep_any_polygon_layout(fmt, sizes, data):
    """Polygons of any size come back as written: same sizes, same indices, same order."""
    flat = np.array(data.draw(st.lists(st.integers(0, 19), min_size=sum(sizes),
                                       max_size=sum(sizes))), dtype=np.int64)
    faces, polygon_sizes = fan_triangulate(flat, np.array(sizes))
    mesh = Mesh(np.arange(60, dtype=np.float64).reshape(20, 3) / 7, faces, polygon_sizes)
    buffer = io.BytesIO()
    FORMATS[fmt].writer(mesh, buffer)
    back = read_mesh(io.BytesIO(buffer.getvalue()), format=fmt)
    back_flat, back_sizes = back.polygons_flat()
    np.testing.assert_array_equal(back_flat, flat)
    np.testing.assert_array_equal(back_sizes, sizes)
    assert_bits_equal(back.vertices, mesh.vertices)


@settings(max_examples=80, deadline=None)
@given(sizes=st.lists(st.integers(3, 9), min_size=1, max_size=12), data=st.data())
def test_vectorised_fan_matches_the_documented_layout(sizes, data):
    flat = np.array(data.draw(st.lists(st.integers(0, 99), min_size=sum(sizes),
                                       max_size=sum(sizes))), dtype=np.int64)
    polygons = np.split(flat, np.cumsum(sizes)[:-1])
    # the layout Mesh documents, written out by hand: (v0, v1, v2), (v0, v2, v3), ...
    expected_faces = [[p[0], p[k], p[k + 1]] for p in polygons for k in range(1, len(p) - 1)]
    faces, got_sizes = fan_triangulate(flat, np.array(sizes))
    np.testing.assert_array_equal(faces, expected_faces)
    assert (got_sizes is None) == all(k == 3 for k in sizes)
    mesh = Mesh(np.zeros((100, 3)), faces, got_sizes)
    back_flat, back_sizes = mesh.polygons_flat()
    np.testing.assert_array_equal(back_flat, flat)
    np.testing.assert_array_equal(back_sizes, sizes)
    assert [p.tolist() for p in mesh.polygons()] == [p.tolist() for p in polygons]


# --- registry and units ------------------------------------------------------------------------
def test_units_are_the_exact_definitions():
    assert UNITS == {"m": 1.0, "cm": 0.01, "mm": 0.001, "um": 1e-6, "in": 0.0254, "ft": 0.3048}


def test_registry_lists_are_derived_from_formats():
    assert input_formats() == sorted(n for n, f in FORMATS.items() if f.reader is not None)
    assert output_formats() == sorted(n for n, f in FORMATS.items() if f.can_write)
    extensions = [e for f in FORMATS.values() for e in f.extensions]
    assert len(extensions) == len(set(extensions))
    assert all(e.startswith(".") and e == e.lower() for e in extensions)
    assert {"obj", "stl", "vf", "vtx", "ply", "off"} <= set(input_formats())


@pytest.mark.parametrize("unit", sorted(UNITS))
def test_unit_scales_coordinates_to_metres(unit, tmp_path):
    mesh = tetrahedron()
    path = tmp_path / "t.obj"
    write_mesh(mesh, path)
    back = read_mesh(path, unit=unit)
    np.testing.assert_array_equal(back.vertices, mesh.vertices * UNITS[unit])
    assert back.coordinate_scale == UNITS[unit]


def test_unknown_unit_is_a_usage_error(tmp_path):
    with pytest.raises(UsageError, match="furlong"):
        read_mesh(tmp_path / "t.obj", unit="furlong")


def test_importing_io_does_not_import_trimesh_or_meshio():
    code = "import sys, massprops.io; print('trimesh' in sys.modules or 'meshio' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


# --- OBJ ---------------------------------------------------------------------------------------
def test_obj_reader_features(tmp_path):
    """Comments, objects and groups, v/vt/vn tokens of every kind, negative indices, w and colour
    columns, ignored statements, indentation, a continued line, CRLF: all one prism."""
    prism = pentagonal_prism()
    v = [" ".join(repr(float(c)) for c in row) for row in prism.vertices]
    lines = ["# a pentagonal prism", "mtllib prism.mtl", "o prism", "g bottom"]
    lines += [f"v {v[i]}" for i in range(5)]
    lines += ["vt 0 0", "vt 1 0", "vn 0 0 -1", "", "f 5/1/1 4/2/1 3/1/1 2/2/1 1/1/1"]
    lines += ["g top", "usemtl steel", "s off"]
    lines += [f"v {v[5]} 1.0", f"  v {v[6]} 0.5 0.5 0.5", f"v {v[7]}", f"v {v[8]}", f"v {v[9]}"]
    lines += ["f -5 -4 -3 -2 -1", "g sides", "vn 1 0 0", "l 1 2"]
    lines += ["f 1//1 2//1 7//1 6//1", "f 2/1 3/1 8/1 7/1", "f 3 4 \\", "  9 8"]
    lines += ["\tf 4/1/1 5/1/1 10/1/1 9/1/1", "f 5 1 6 10 # the last side"]
    path = tmp_path / "prism.obj"
    path.write_bytes("\r\n".join(lines).encode())
    back = read_mesh(path)
    assert_bits_equal(back.vertices, prism.vertices)
    assert [p.tolist() for p in back.polygons()] == [p.tolist() for p in prism.polygons()]
    np.testing.assert_array_equal(back.polygon_sizes, [5, 5, 4, 4, 4, 4, 4])


def test_obj_triangles_only_have_no_polygon_sizes(tmp_path):
    path = tmp_path / "t.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n")
    back = read_mesh(path)
    assert back.polygon_sizes is None
    np.testing.assert_array_equal(back.faces, TETRA_FACES)


@pytest.mark.parametrize("token", ["{v}", "{v}/{t}", "{v}//{n}", "{v}/{t}/{n}"])
def test_obj_face_token_styles(token, tmp_path):
    """Only the vertex index counts; texture (t) and normal (n) indices differ from it here."""
    faces = [token.format(v=v + 1, t=9 - v, n=7 + v % 2) for f in TETRA_FACES for v in f]
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvn 0 0 1\n" + "".join(
        "f {} {} {}\n".format(*faces[3 * i : 3 * i + 3]) for i in range(4)
    )
    path = tmp_path / "t.obj"
    path.write_text(text)
    np.testing.assert_array_equal(read_mesh(path).faces, TETRA_FACES)


@pytest.mark.parametrize("fmt", ["obj", "vf", "off"])
def test_text_with_a_byte_order_mark(fmt, tmp_path):
    mesh = tetrahedron()
    buffer = io.BytesIO()
    FORMATS[fmt].writer(mesh, buffer)
    path = tmp_path / f"bom.{fmt}"
    # The OBJ writer starts with a comment; make the first line a vertex so a BOM would hide it.
    path.write_bytes(b"\xef\xbb\xbf" + buffer.getvalue().split(b"\n", 1)[1])
    assert_bits_equal(read_mesh(path, format=fmt).vertices, mesh.vertices)


# --- STL ---------------------------------------------------------------------------------------
def binary_stl(triangles: np.ndarray, header: bytes = b"test", count: int | None = None) -> bytes:
    """Binary STL written by hand: header, count, then per triangle a zero normal, 9 float32 and
    a zero attribute."""
    body = b"".join(struct.pack("<3f9fH", 0, 0, 0, *t.reshape(-1), 0) for t in triangles)
    n = len(triangles) if count is None else count
    return header.ljust(80, b" ") + struct.pack("<I", n) + body


TETRA_TRIANGLES = np.array([[[0, 0, 0], [0, 1, 0], [1, 0, 0]], [[0, 0, 0], [1, 0, 0], [0, 0, 1]],
                            [[0, 0, 0], [0, 0, 1], [0, 1, 0]], [[1, 0, 0], [0, 1, 0], [0, 0, 1]]],
                           dtype=np.float64) * 0.1


def test_binary_stl_whose_header_starts_with_solid_is_binary(tmp_path):
    path = tmp_path / "solid.stl"
    path.write_bytes(binary_stl(TETRA_TRIANGLES, header=b"solid exported by some CAD tool"))
    back = read_mesh(path)
    expected = TETRA_TRIANGLES.astype(np.float32).astype(np.float64).reshape(-1, 3)
    assert_bits_equal(back.vertices, expected)
    np.testing.assert_array_equal(back.faces, np.arange(12).reshape(4, 3))
    assert back.coordinate_dtype == np.float32


def test_ascii_stl_with_two_solids(tmp_path):
    def facet(tri):
        rows = "".join(f"      vertex {x!r} {y!r} {z!r}\n" for x, y, z in tri.tolist())
        return f"  facet normal 0 0 0\n    outer loop\n{rows}    endloop\n  endfacet\n"
    text = ("solid a\n" + facet(TETRA_TRIANGLES[0]) + facet(TETRA_TRIANGLES[1]) + "endsolid a\n"
            "SOLID b\n" + facet(TETRA_TRIANGLES[2]) + facet(TETRA_TRIANGLES[3]) + "ENDSOLID b\n")
    path = tmp_path / "a.STL"
    path.write_text(text)
    back = read_mesh(path)
    assert_bits_equal(back.vertices, TETRA_TRIANGLES.reshape(-1, 3))
    assert back.coordinate_dtype == np.float64


def test_stl_writer_stores_the_winding_normal_and_its_header(tmp_path):
    # A right triangle in the plane z = 2, counter-clockwise seen from +z: normal (0, 0, 1).
    mesh = Mesh(np.array([[0, 0, 2.0], [3, 0, 2], [0, 4, 2]]), np.array([[0, 1, 2]]))
    path = tmp_path / "n.stl"
    write_mesh(mesh, path)
    data = path.read_bytes()
    assert data[:80] == b"massprops".ljust(80, b" ")
    assert struct.unpack("<I", data[80:84]) == (1,)
    assert struct.unpack("<3f", data[84:96]) == (0.0, 0.0, 1.0)
    assert len(data) == 84 + 50


# --- .vf and .vtx/.fac -------------------------------------------------------------------------
TETRA_VF = """# tetra
4
0 0 0
1 0 0
0 1 0
0 0 1
4
1 3 2
1 2 4
1 4 3
2 3 4
"""


def test_vf_reads_the_contract_example(tmp_path):
    path = tmp_path / "t.vf"
    path.write_text(TETRA_VF.replace("0 0 1\n", "0 0 1   # apex\n\n"))
    back = read_mesh(path)
    np.testing.assert_array_equal(back.vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    np.testing.assert_array_equal(back.faces, TETRA_FACES)


@pytest.mark.parametrize("given_part", [".vtx", ".fac", ".VTX"])
def test_vtx_fac_pair_is_found_from_either_file(given_part, tmp_path):
    stem = tmp_path / "part"
    suffixes = (".VTX", ".FAC") if given_part.isupper() else (".vtx", ".fac")
    vertex_part, face_part = TETRA_VF.split("\n4\n1 3 2")
    stem.with_suffix(suffixes[0]).write_text(vertex_part.replace("# tetra\n", "") + "\n")
    stem.with_suffix(suffixes[1]).write_text("4\n1 3 2" + face_part)
    back = read_mesh(stem.with_suffix(given_part))
    np.testing.assert_array_equal(back.faces, TETRA_FACES)
    assert back.name == str(stem.with_suffix(given_part))


def test_writing_vtx_writes_the_pair(tmp_path):
    write_mesh(cube(), tmp_path / "c.fac")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["c.fac", "c.vtx"]


# --- OFF ---------------------------------------------------------------------------------------
TETRA_OFF = """# tetra
OFF
4 4 6
0 0 0
1 0 0
0 1 0
0 0 1
3 0 2 1
3 0 1 3
3 0 3 2
3 1 2 3
"""
TETRA_POINTS = ["0 0 0", "1 0 0", "0 1 0", "0 0 1"]
TETRA_OFF_FACES = ["3 0 2 1", "3 0 1 3", "3 0 3 2", "3 1 2 3"]


def test_off_reader_features(tmp_path):
    """Comments, blank lines, indentation, CRLF, a COFF header with the counts on its line,
    vertex colours, face colours (RGBA floats, a colour-map integer or none): all one prism."""
    prism = pentagonal_prism()
    polygons = [" ".join(str(i) for i in p) for p in prism.polygons()]
    lines = ["# a pentagonal prism", "", "COFF 10 7 15  # counts on the header line"]
    lines += [" ".join(repr(float(c)) for c in row) + " 0.5 0.5 0.5 1" for row in prism.vertices]
    lines[5] = "\t" + lines[5] + "  # indented"
    lines += ["", f"5 {polygons[0]} 1.0 0.0 0.0 0.75", f"5 {polygons[1]} 7"]
    lines += [f"4 {p}" for p in polygons[2:6]] + [f"  4 {polygons[6]} 0 0 255"]
    path = tmp_path / "prism.off"
    path.write_bytes("\r\n".join(lines).encode())
    back = read_mesh(path)
    assert_bits_equal(back.vertices, prism.vertices)
    assert [p.tolist() for p in back.polygons()] == [p.tolist() for p in prism.polygons()]
    np.testing.assert_array_equal(back.polygon_sizes, [5, 5, 4, 4, 4, 4, 4])


OFF_HEADERS = {
    "OFF-line": ("OFF\n4 4 6", ""),
    "counts-on-header-line": ("OFF 4 4 6", ""),
    "no-blank-after-OFF": ("OFF4 4 6", ""),  # as in the ModelNet data set
    "no-header": ("4 4 6", ""),
    "no-edge-count": ("OFF\n4 4", ""),
    "NOFF-normals": ("NOFF\n4 4 6", " 0 0 1"),
    "CNOFF-normals-colours": ("CNOFF\n4 4 6", " 0 0 1 0.2 0.4 0.6 1"),
    "STOFF-texture": ("STOFF\n4 4 6", " 0.25 0.75"),
}


@pytest.mark.parametrize("case", sorted(OFF_HEADERS))
def test_off_header_variants(case):
    head, extra = OFF_HEADERS[case]
    text = "\n".join([head, *(p + extra for p in TETRA_POINTS), *TETRA_OFF_FACES]) + "\n"
    back = read_mesh(io.BytesIO(text.encode()), format="off")
    np.testing.assert_array_equal(back.vertices, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    np.testing.assert_array_equal(back.faces, TETRA_FACES)
    assert back.polygon_sizes is None


def test_reading_off_does_not_import_trimesh_or_meshio():
    code = ("import io, sys; from massprops.io import read_mesh; "
            f"read_mesh(io.BytesIO({TETRA_OFF.encode()!r}), format='off'); "
            "print('trimesh' in sys.modules or 'meshio' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


# --- streams -----------------------------------------------------------------------------------
@pytest.mark.parametrize("fmt", ["obj", "stl", "vf", "ply", "off"])
def test_read_from_a_binary_stream(fmt):
    mesh = tetrahedron()
    buffer = io.BytesIO()
    FORMATS[fmt].writer(mesh, buffer)
    back = read_mesh(io.BytesIO(buffer.getvalue()), format=fmt.upper(), name="-")
    assert back.name == "-"
    assert back.n_faces == 4


def test_text_stream_is_accepted():
    back = read_mesh(io.StringIO(TETRA_VF), format="vf")
    np.testing.assert_array_equal(back.faces, TETRA_FACES)


def test_stream_without_format_is_a_usage_error():
    with pytest.raises(UsageError, match="input_format"):
        read_mesh(io.BytesIO(TETRA_VF.encode()))


# --- bad inputs: (file name, content, error class, what the message says) ----------------------
TETRA_OBJ = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
CUBE_PLY = ("ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
            "property float z\nelement face 6\nproperty list uchar int vertex_indices\n"
            "end_header\n" + "".join(f"{i & 1} {(i >> 1) & 1} {(i >> 2) & 1}\n" for i in range(8))
            + "".join("4 " + " ".join(map(str, q)) + "\n" for q in CUBE_QUADS))
CUBE_PLY_BINARY = (b"ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty double x\n"
                   b"property double y\nproperty double z\nelement face 6\n"
                   b"property list uchar int vertex_indices\nend_header\n"
                   + np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)],
                              "<f8").tobytes()
                   + b"".join(b"\x04" + np.array(q, "<i4").tobytes() for q in CUBE_QUADS))
"""The unit cube in PLY, ASCII and binary (the ply-* cases below cut them short)."""

BAD_FILES = {
    "empty-obj": ("e.obj", b"", MeshFormatError, "empty"),
    "empty-stl": ("e.stl", b"", MeshFormatError, "empty"),
    "empty-ply": ("e.ply", b"", MeshFormatError, "empty"),
    "garbage-obj": ("g.obj", bytes(range(256)) * 4, MeshFormatError, "binary data"),
    "garbage-vf": ("g.vf", b"\x89PNG\r\n\x1a\n\0\0", MeshFormatError, "binary data"),
    "garbage-stl": ("g.stl", b"hello world", MeshFormatError, "too short"),
    "garbage-ply": ("g.ply", b"ply\nformat nonsense\n", MeshFormatError, "cannot read as PLY"),
    "not-utf8-obj": ("u.obj", TETRA_OBJ.encode() + b"# caf\xe9\n", MeshFormatError, "line 9"),
    "obj-no-faces": ("n.obj", b"v 0 0 0\nv 1 0 0\n", MeshFormatError, "0 faces"),
    "obj-nan": ("n.obj", TETRA_OBJ.replace("v 1 0 0", "v 1 nan 0").encode(), MeshFormatError,
                "line 2: vertex 2 has a non-finite"),
    "obj-inf": ("n.obj", TETRA_OBJ.replace("v 0 0 1", "v 0 0 -inf").encode(), MeshFormatError,
                "line 4"),
    "obj-word": ("w.obj", TETRA_OBJ.replace("v 0 1 0", "v 0 one 0").encode(), MeshFormatError,
                 "line 3: 'one' is not a number"),
    "obj-short-vertex": ("s.obj", TETRA_OBJ.replace("v 0 1 0", "v 0 1").encode(),
                         MeshFormatError, "line 3"),
    "obj-index-0": ("z.obj", TETRA_OBJ.replace("f 1 2 4", "f 0 2 4").encode(), MeshFormatError,
                    "line 6: vertex index 0"),
    "obj-index-range": ("r.obj", TETRA_OBJ.replace("f 2 3 4", "f 2 3 5").encode(),
                        MeshFormatError, "line 8: vertex index 5 is out of range"),
    "obj-negative-range": ("r.obj", TETRA_OBJ.replace("f 2 3 4", "f 2 3 -5").encode(),
                           MeshFormatError, "line 8: vertex index -5"),
    # a face of two vertices is skipped (an edge, not surface), but its indices are still checked
    "obj-two-vertex-face-bad-index": ("t.obj", TETRA_OBJ.replace("f 1 4 3", "f 1 9").encode(),
                                      MeshFormatError, "line 7: vertex index 9 is out of range"),
    "stl-truncated": ("t.stl", binary_stl(TETRA_TRIANGLES)[:-7], MeshFormatError, "truncated"),
    "stl-count-too-big": ("c.stl", binary_stl(TETRA_TRIANGLES, count=10**9), MeshFormatError,
                          "says 1000000000 triangles"),
    "stl-trailing": ("c.stl", binary_stl(TETRA_TRIANGLES, count=3), MeshFormatError, "trailing"),
    "stl-solid-truncated": ("t.stl", binary_stl(TETRA_TRIANGLES, header=b"solid x")[:-1],
                            MeshFormatError, "truncated"),
    "stl-zero": ("z.stl", binary_stl(TETRA_TRIANGLES[:0]), MeshFormatError, "0 triangles"),
    "stl-nan": ("n.stl", binary_stl(np.where(TETRA_TRIANGLES == 0.1, np.nan, TETRA_TRIANGLES)),
                MeshFormatError, "triangle 1"),
    "stl-ascii-broken": ("b.stl", b"solid s\n facet normal 0 0 1\n outer loop\n vertex 0 0 0\n"
                         b" vertex 1 0 0\n endloop\n endfacet\nendsolid s\n", MeshFormatError,
                         "line 2: malformed facet"),
    "stl-ascii-inf": ("i.stl", b"solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"
                      b"vertex 1 0 0\nvertex 0 1 inf\nendloop\nendfacet\nendsolid s\n",
                      MeshFormatError, "facet 1"),
    "stl-ascii-no-end": ("i.stl", b"solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n"
                         b"vertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n", MeshFormatError,
                         "endsolid"),
    "vf-vertex-count-too-large": ("a.vf", TETRA_VF.replace("4\n0 0 0", "5\n0 0 0"),
                                  MeshFormatError, "line 7: expected vertex 5 of 5"),
    "vf-vertex-count-too-small": ("a.vf", TETRA_VF.replace("4\n0 0 0", "3\n0 0 0"),
                                  MeshFormatError, "line 6: expected the face count"),
    "vf-face-count-too-large": ("a.vf", TETRA_VF.replace("4\n1 3 2", "5\n1 3 2"),
                                MeshFormatError, "ends after 4 of the 5 face lines"),
    "vf-face-count-too-small": ("a.vf", TETRA_VF.replace("4\n1 3 2", "3\n1 3 2"),
                                MeshFormatError, "line 11: unexpected data after the last face"),
    "vf-count-not-integer": ("a.vf", TETRA_VF.replace("4\n0 0 0", "4.0\n0 0 0"),
                             MeshFormatError, "line 2: expected the vertex count"),
    "vf-index-0": ("a.vf", TETRA_VF.replace("1 3 2", "0 3 2"), MeshFormatError,
                   "line 8: vertex index 0"),
    "vf-index-range": ("a.vf", TETRA_VF.replace("1 3 2", "1 3 9"), MeshFormatError,
                       "line 8: vertex index 9 is out of range"),
    "vf-negative-index": ("a.vf", TETRA_VF.replace("1 3 2", "-1 3 2"), MeshFormatError,
                          "line 8: vertex index -1 is out of range"),
    "vf-two-vertex-face": ("a.vf", TETRA_VF.replace("1 3 2", "1 3"), MeshFormatError,
                           "line 8: face 1 has 2"),
    "vf-nan": ("a.vf", TETRA_VF.replace("1 0 0", "1 nan 0"), MeshFormatError, "line 4"),
    "vf-word": ("a.vf", TETRA_VF.replace("1 0 0", "1 O 0"), MeshFormatError,
                "line 4: 'O' is not a number"),
    "vf-not-utf8": ("a.vf", TETRA_VF.encode("utf-16"), MeshFormatError, "binary data"),
    "vf-latin1": ("a.vf", ("# Träger\n" + TETRA_VF).encode("latin-1"), MeshFormatError,
                  "line 1 is not UTF-8"),
    "empty-off": ("e.off", b"", MeshFormatError, "empty"),
    "off-vertex-count-too-large": ("a.off", TETRA_OFF.replace("4 4 6", "5 4 6"), MeshFormatError,
                                   "ends after 3 of the 4 face lines"),
    "off-vertex-count-too-small": ("a.off", TETRA_OFF.replace("4 4 6", "3 4 6"), MeshFormatError,
                                   "line 7: face 1 has 0 vertex indices; expected at least 3; "
                                   "do the counts on line 3 match the file?"),
    "off-face-count-too-large": ("a.off", TETRA_OFF.replace("4 4 6", "4 5 6"), MeshFormatError,
                                 "ends after 4 of the 5 face lines"),
    "off-face-count-too-small": ("a.off", TETRA_OFF.replace("4 4 6", "4 3 6"), MeshFormatError,
                                 "line 11: unexpected data after the last face"),
    "off-counts-not-integer": ("a.off", TETRA_OFF.replace("4 4 6", "4.0 4 6"), MeshFormatError,
                               "line 3: expected the counts"),
    "off-counts-one-value": ("a.off", TETRA_OFF.replace("4 4 6", "4"), MeshFormatError,
                             "line 3: expected the counts"),
    "off-counts-missing": ("a.off", b"# header only\nOFF\n", MeshFormatError,
                           "ends after the header"),
    "off-header-garbled": ("a.off", TETRA_OFF.replace("OFF", "OFX"), MeshFormatError,
                           "line 2: expected 'OFF' or the counts"),
    "off-header-4d": ("a.off", TETRA_OFF.replace("OFF", "4OFF"), MeshFormatError,
                      "line 2: OFF variant '4OFF' is not supported"),
    "off-binary": ("a.off", TETRA_OFF.replace("OFF", "OFF BINARY"), MeshFormatError,
                   "line 2: binary OFF is not supported"),
    "off-only-comments": ("a.off", "# nothing here\n\n", MeshFormatError,
                          "only comments and blank lines"),
    "off-no-faces": ("a.off", "OFF\n3 0 0\n0 0 0\n1 0 0\n0 1 0\n", MeshFormatError, "0 faces"),
    "off-index-range": ("a.off", TETRA_OFF.replace("3 0 2 1", "3 0 2 4"), MeshFormatError,
                        "line 8: vertex index 4 is out of range"),
    "off-negative-index": ("a.off", TETRA_OFF.replace("3 0 2 1", "3 -1 2 1"), MeshFormatError,
                           "line 8: vertex index -1 is out of range"),
    "off-two-vertex-face": ("a.off", TETRA_OFF.replace("3 0 2 1", "2 0 2"), MeshFormatError,
                            "line 8: face 1 has 2"),
    "off-face-missing-index": ("a.off", TETRA_OFF.replace("3 0 2 1", "3 0 2"), MeshFormatError,
                               "line 8: face 1 announces 3 vertex indices but lists 2"),
    "off-size-not-integer": ("a.off", TETRA_OFF.replace("3 0 2 1", "3.0 0 2 1"),
                             MeshFormatError, "line 8: '3.0' is not an integer"),
    "off-index-word": ("a.off", TETRA_OFF.replace("3 0 2 1", "3 0 two 1"), MeshFormatError,
                       "line 8: 'two' is not an integer"),
    "off-nan": ("a.off", TETRA_OFF.replace("\n1 0 0\n", "\n1 nan 0\n"), MeshFormatError,
                "line 5: vertex 2 has a non-finite"),
    "off-inf": ("a.off", TETRA_OFF.replace("\n0 0 1\n", "\n0 0 -inf\n"), MeshFormatError,
                "line 7"),
    "off-word": ("a.off", TETRA_OFF.replace("\n1 0 0\n", "\n1 O 0\n"), MeshFormatError,
                 "line 5: 'O' is not a number"),
    "off-short-vertex": ("a.off", TETRA_OFF.replace("\n0 1 0\n", "\n0 1\n"), MeshFormatError,
                         "line 6: vertex 3 of 4 has 2"),
    "off-not-utf8": ("a.off", TETRA_OFF.encode("utf-16"), MeshFormatError, "binary data"),
    # issue 30: a PLY cut short was "no faces (a point cloud or a drawing?)", or an open mesh
    "ply-ascii-cut-in-faces": ("a.ply", "\n".join(CUBE_PLY.splitlines()[:-3]), MeshFormatError,
                               "truncated: the header declares 8 vertices and 6 faces, the file "
                               "holds 8 vertices and 3 faces; copy or export the file again"),
    "ply-ascii-cut-in-vertices": ("a.ply", "\n".join(CUBE_PLY.splitlines()[:14]),
                                  MeshFormatError, "truncated: the header declares 8 vertices "
                                  "and 6 faces, the file holds 5 vertices and 0 faces"),
    "ply-binary-cut-in-vertices": ("a.ply", CUBE_PLY_BINARY[:-122], MeshFormatError,
                                   "truncated: the header declares 8 vertices and 6 faces, the "
                                   "file holds 7 vertices;"),
    "unknown-extension": ("a.xyz", b"1 2 3", UnknownFormatError, "known: "),
    "no-extension": ("mesh", b"1 2 3", UnknownFormatError, ".obj"),
}


@pytest.mark.parametrize("case", sorted(BAD_FILES))
def test_bad_input_raises_a_clear_error_naming_the_file(case, tmp_path):
    filename, content, error, says = BAD_FILES[case]
    path = tmp_path / filename
    path.write_bytes(content.encode() if isinstance(content, str) else content)
    with pytest.raises(error) as caught:
        read_mesh(path)
    message = str(caught.value)
    assert message.startswith(str(path))
    assert says in message
    assert "\n" not in message


def test_missing_file(tmp_path):
    with pytest.raises(MeshFileError, match="no such file") as caught:
        read_mesh(tmp_path / "nope.obj")
    assert str(caught.value).startswith(str(tmp_path / "nope.obj"))


@pytest.mark.parametrize("suffix", [".obj", ".ply"])
def test_directory_instead_of_a_file(suffix, tmp_path):
    path = tmp_path / f"dir{suffix}"
    path.mkdir()
    with pytest.raises(MeshFileError, match="is a directory"):
        read_mesh(path)


def test_permission_denied(tmp_path, monkeypatch):
    # Simulated: the tests may run as root, for whom file modes do not deny reading.
    def denied(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr("massprops.files.open", denied, raising=False)
    with pytest.raises(MeshFileError, match="permission denied") as caught:
        read_mesh(tmp_path / "locked.obj")
    assert str(caught.value).startswith(str(tmp_path / "locked.obj"))


def test_vtx_without_its_fac_names_the_missing_file(tmp_path):
    (tmp_path / "p.vtx").write_text("1\n0 0 0\n")
    with pytest.raises(MeshFileError, match="p.fac: no such file"):
        read_mesh(tmp_path / "p.vtx")


@pytest.mark.parametrize("part", ["p.vtx", "p.fac"])
def test_missing_vtx_or_fac_given_is_reported_as_such(part, tmp_path):
    with pytest.raises(MeshFileError, match="no such file; check the path") as caught:
        read_mesh(tmp_path / part)
    assert str(caught.value).startswith(str(tmp_path / part))


def test_vtx_with_extra_lines_names_the_line(tmp_path):
    (tmp_path / "p.vtx").write_text("1\n0 0 0\n1 1 1\n")
    (tmp_path / "p.fac").write_text("1\n1 1 1\n")
    with pytest.raises(MeshFormatError, match="line 3: unexpected data after the last vertex"):
        read_mesh(tmp_path / "p.fac")


def test_float32_ply_with_mixed_polygons_through_the_fallback(tmp_path):
    """A binary PLY written here by hand: float vertices, a quad and a triangle."""
    header = (b"ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\n"
              b"property float y\nproperty float z\nelement face 2\n"
              b"property list uchar int vertex_indices\nend_header\n")
    vertices = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0.1, 2, 0]], "<f4")
    faces = struct.pack("<B4i", 4, 0, 1, 2, 3) + struct.pack("<B3i", 3, 3, 2, 4)
    path = tmp_path / "f32.ply"
    path.write_bytes(header + vertices.tobytes() + faces)
    back = read_mesh(path)
    assert back.coordinate_dtype == np.float32
    assert_bits_equal(back.vertices, vertices.astype(np.float64))
    assert canonical(back.polygons()) == canonical([[0, 1, 2, 3], [3, 2, 4]])


def test_glb_through_trimesh_is_float32(tmp_path):
    import trimesh  # builds the test file; glTF cannot be written by hand in a few lines

    mesh = tetrahedron()
    path = tmp_path / "t.glb"
    path.write_bytes(trimesh.Trimesh(mesh.vertices, mesh.faces, process=False).export(
        file_type="glb"))
    back = read_mesh(path)
    assert back.coordinate_dtype == np.float32
    assert_bits_equal(back.vertices, mesh.vertices.astype(np.float32).astype(np.float64))
    np.testing.assert_array_equal(back.faces, mesh.faces)


def test_fallback_file_without_surface_cells(tmp_path):
    import meshio  # writing the test file by hand in VTK legacy text would be longer

    path = tmp_path / "tet.vtk"
    tet = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float64)
    meshio.Mesh(tet, [("tetra", np.array([[0, 1, 2, 3]]))]).write(path)
    with pytest.raises(MeshFormatError, match="no surface cells") as caught:
        read_mesh(path)
    assert str(caught.value).startswith(str(path))


def test_unknown_format_name(tmp_path):
    with pytest.raises(UnknownFormatError, match="expected one of"):
        read_mesh(tmp_path / "a.obj", format="dwg")


def test_source_keeps_the_path_as_given():
    assert Source.from_path(Path("a") / "b.obj").name == os.path.join("a", "b.obj")


# --- output guards -----------------------------------------------------------------------------
def test_existing_output_is_kept_without_force(tmp_path):
    path = tmp_path / "out.obj"
    path.write_text("precious")
    with pytest.raises(OutputExistsError, match="force") as caught:
        write_mesh(cube(), path)
    assert str(caught.value).startswith(str(path))
    assert path.read_text() == "precious"
    write_mesh(cube(), path, force=True)
    assert_bits_equal(read_mesh(path).vertices, cube().vertices)


def test_input_is_never_overwritten_even_with_force(tmp_path):
    source = tmp_path / "in.obj"
    write_mesh(cube(), source)
    before = source.read_bytes()
    (tmp_path / "sub").mkdir()
    link = tmp_path / "link.obj"
    link.symlink_to(source)
    for target, guarded in [(source, source), (source, tmp_path / "sub" / ".." / "in.obj"),
                            (link, source)]:
        with pytest.raises(OutputExistsError, match="input"):
            write_mesh(tetrahedron(), target, force=True, protect=[guarded])
    assert source.read_bytes() == before


def test_an_input_pair_protects_both_files(tmp_path):
    write_mesh(cube(), tmp_path / "in.vtx")
    with pytest.raises(OutputExistsError, match="input"):
        write_mesh(tetrahedron(), tmp_path / "in.fac", force=True, protect=[tmp_path / "in.vtx"])


def test_failed_write_leaves_the_old_file_and_no_temporary(tmp_path, monkeypatch):
    path = tmp_path / "out.obj"
    write_mesh(tetrahedron(), path)
    before = path.read_bytes()

    def fail_midway(stream, *args, **kwargs):
        stream.write(b"f 1 2 3\n")  # some bytes reach the temporary file first
        raise RuntimeError("disk on fire")

    monkeypatch.setattr(numtext, "write_index_rows", fail_midway)
    with pytest.raises(RuntimeError, match="disk on fire"):
        write_mesh(cube(), path, force=True)
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["out.obj"]


def test_failed_fsync_is_a_file_error_and_keeps_the_old_file(tmp_path, monkeypatch):
    path = tmp_path / "out.stl"
    write_mesh(tetrahedron(), path)
    before = path.read_bytes()

    def no_space(fd):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", no_space)
    with pytest.raises(MeshFileError, match="No space left") as caught:
        write_mesh(cube(), path, force=True)
    assert str(caught.value).startswith(str(path))
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == ["out.stl"]


def test_atomic_write_bytes_for_other_outputs(tmp_path):
    """The guards serve non-mesh outputs too (trajectories, plots)."""
    path = tmp_path / "traj.csv"
    atomic_write_bytes(path, b"t,x\n0,1\n")
    assert path.read_bytes() == b"t,x\n0,1\n"
    with pytest.raises(OutputExistsError, match="force"):
        atomic_write_bytes(path, b"new")
    with pytest.raises(OutputExistsError, match="input"):
        atomic_write_bytes(path, b"new", force=True, protect=[str(path)])
    atomic_write_bytes(path, b"new", force=True)
    assert path.read_bytes() == b"new"
    assert [p.name for p in tmp_path.iterdir()] == ["traj.csv"]


def test_write_errors(tmp_path):
    with pytest.raises(UsageError, match=r"a.vtk: cannot write a mesh as '.vtk'; expected .*\.obj"):
        write_mesh(cube(), tmp_path / "a.vtk")
    with pytest.raises(MeshFileError, match="does not exist"):
        write_mesh(cube(), tmp_path / "missing" / "a.obj")
    bad = cube().with_vertices(np.where(cube().vertices == 1, np.inf, 0.0))
    with pytest.raises(MeshFormatError, match="non-finite"):
        write_mesh(bad, tmp_path / "a.obj")
    assert list(tmp_path.iterdir()) == []


def test_ply_polygons_beyond_255_vertices(tmp_path):
    n = 300
    angle = 2 * np.pi * np.arange(n) / n
    ring = np.column_stack([np.cos(angle), np.sin(angle)])
    vertices = np.vstack([np.column_stack([ring, np.zeros(n)]),
                          np.column_stack([ring, np.ones(n)])])
    sides = [[i, (i + 1) % n, n + (i + 1) % n, n + i] for i in range(n)]
    prism = make_mesh(vertices, [list(range(n - 1, -1, -1)), list(range(n, 2 * n)), *sides], "p")
    back = write_read(prism, "ply", tmp_path)
    assert b"property list uint int" in (tmp_path / "mesh.ply").read_bytes()[:400]
    assert canonical(back.polygons()) == canonical(prism.polygons())
