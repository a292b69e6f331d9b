"""Wavefront OBJ: vertices (``v``) and polygon faces (``f``); everything else is ignored."""

from __future__ import annotations

import re
from typing import BinaryIO

import numpy as np

from massprops.errors import MeshFormatError
from massprops.io import numtext, validate
from massprops.io.source import Source, text_content
from massprops.io.textlines import (
    TextLines,
    first_columns,
    line_of_token,
    parse_numbers,
    strip_comments,
    token_counts,
)
from massprops.mesh.value import Mesh, fan_triangulate

_CONTINUATION = re.compile(rb"\\[ \t]*\r?\n")
_AFTER_SLASH = re.compile(rb"/\S*")  # "7/1/3", "7//3", "7/1" -> "7": only the vertex index counts


def read_obj(source: Source) -> Mesh:
    """Read an OBJ file.

    Keeps every ``f`` line of every ``o``/``g`` object in file order, one mesh; a polygon of k
    vertices becomes k - 2 fan triangles (``polygon_sizes`` records it). Index tokens may be
    ``v``, ``v/vt``, ``v//vn`` or ``v/vt/vn``; negative indices count back from the latest vertex.
    Extra vertex columns (w, colours) are ignored. ``\\`` continues a line (line numbers in
    messages then count the joined lines as one). Faces of fewer than 3 vertices and polyline
    (``l``) lines are skipped, with one note (``Mesh.notes``) giving their counts and first lines.

    Returns a Mesh with vertices (n, 3) float64 in file units, faces (m, 3) int64 0-based.
    """
    name = source.name
    # Comments go first: a backslash ending a comment does not continue it onto the next line.
    data = strip_comments(text_content(source.read_bytes(), name, "OBJ"))
    if b"\\" in data:
        data = _CONTINUATION.sub(b" ", data)
    lines = TextLines.from_bytes(data)
    vertex_lines = lines.select(b"v")
    face_lines = lines.select(b"f")
    if not (vertex_lines.size and face_lines.size):
        validate.require_content(vertex_lines.size, face_lines.size, name)
    vertices = _read_vertices(lines, vertex_lines, name)
    flat, sizes = _read_faces(lines, vertex_lines, face_lines, vertices.shape[0], name)
    # Faces of fewer than 3 vertices and polylines ('l') are edges, not surface: a scene export
    # may hold a few among its faces, which must not make the whole file fail.
    short = sizes < 3
    polylines = lines.select(b"l") if b"l" in data else face_lines[:0]  # memchr-fast filter
    notes = _skipped_note(face_lines[short], polylines)
    if short.any():
        validate.require_content(vertex_lines.size, int(np.count_nonzero(~short)), name)
        flat, sizes = flat[np.repeat(~short, sizes)], sizes[~short]
    faces, polygon_sizes = fan_triangulate(flat, sizes)
    return Mesh(vertices, faces, polygon_sizes, name=name, notes=notes)


def _skipped_note(short_faces: np.ndarray, polylines: np.ndarray) -> tuple[str, ...]:
    """The one warning for skipped edge elements (0-based line indices), or none."""
    kinds = ((short_faces, "face with fewer than 3 vertices", "faces with fewer than 3 vertices"),
             (polylines, "polyline ('l') line", "polyline ('l') lines"))
    parts = [f"{lines.size} {one if lines.size == 1 else many} (first on line {lines[0] + 1})"
             for lines, one, many in kinds if lines.size]
    return (f"skipped {' and '.join(parts)}: edges, not surface",) if parts else ()


def _read_vertices(lines: TextLines, vertex_lines: np.ndarray, name: str) -> np.ndarray:
    """(n, 3) float64 from the ``v`` lines (0-based line indices ``vertex_lines``)."""
    block = lines.gather(vertex_lines, skip=1)
    counts = token_counts(block)
    line_numbers = vertex_lines + 1
    short = counts < 3
    if short.any():
        i = int(np.argmax(short))
        raise MeshFormatError(
            f"{name}: line {line_numbers[i]}: vertex with {int(counts[i])} coordinates; "
            f"expected 'v x y z'"
        )
    flat = parse_numbers(
        block, counts, np.float64, name=name, line_numbers=line_numbers, what="'v x y z'"
    )
    vertices = first_columns(flat, counts, 3)
    validate.require_finite(vertices, name, lambda i: f"line {line_numbers[i]}")
    return np.ascontiguousarray(vertices)


def _read_faces(
    lines: TextLines,
    vertex_lines: np.ndarray,
    face_lines: np.ndarray,
    n_vertices: int,
    name: str,
) -> tuple[np.ndarray, np.ndarray]:
    """(flat 0-based indices, sizes) of the ``f`` lines' polygons, every index range-checked
    (also those of faces with fewer than 3 vertices, which the caller skips)."""
    block = lines.gather(face_lines, skip=1)
    sizes = token_counts(block)
    line_numbers = face_lines + 1
    raw = _vertex_indices(block, sizes, name, line_numbers)

    def token_line(k: int) -> str:
        return f"line {line_numbers[line_of_token(sizes, k)]}"

    def vertices_before() -> np.ndarray:
        # Vertices defined above each face line: what a relative index counts back from.
        return np.repeat(np.searchsorted(vertex_lines, face_lines), sizes)

    flat = validate.one_based_indices(raw, n_vertices, name, token_line, vertices_before)
    return flat, sizes


def _vertex_indices(
    block: bytes, sizes: np.ndarray, name: str, line_numbers: np.ndarray
) -> np.ndarray:
    """(sum(sizes),) int64: the vertex index of every ``v``, ``v/vt``, ``v//vn``, ``v/vt/vn``
    token of the ``f`` lines in ``block``, as written (1-based or negative)."""
    if b"/" in block:
        # One C-level pass; measured no slower than replacing the slashes by spaces and keeping
        # every 2nd/3rd number (which would need its own checks of the token shapes).
        block = _AFTER_SLASH.sub(b"", block)
    return parse_numbers(
        block, sizes, np.int64, name=name, line_numbers=line_numbers, what="'f i j k ...'"
    )


def write_obj(mesh: Mesh, stream: BinaryIO) -> None:
    """Write ``v x y z`` lines (shortest round-trip repr: they read back bit-identical) and one
    ``f`` line per file polygon (1-based, winding unchanged)."""
    stream.write(b"# written by massprops\n")
    numtext.write_float_rows(stream, mesh.vertices, prefix="v ")
    flat, sizes = mesh.polygons_flat()
    numtext.write_index_rows(stream, flat, sizes, prefix="f ", base=1)
