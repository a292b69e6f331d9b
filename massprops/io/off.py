"""Object File Format (OFF, Geomview), ASCII: polygons of any size, 0-based indices.

Layout: an optional header line ``OFF``, the counts ``n_vertices n_faces n_edges``, n_vertices
lines ``x y z``, n_faces lines ``k i1 ... ik``. ``#`` comments and blank lines are ignored; the
counts must match the lines that follow, and an error names the line where the two part ways.

Tolerated because common in the wild: the ``C``/``N``/``ST`` header prefixes (COFF, NOFF, CNOFF,
STOFF: colours, normals, texture coordinates as extra vertex columns, ignored), extra columns
after the k indices of a face (a face colour, ignored), the counts on the header line
(``OFF 8 6 12``, or ``OFF8 6 12`` as in ModelNet), a missing n_edges (never used). Refused with a
clear error: 4OFF/nOFF (other dimensions) and binary OFF. The reader is line-based: one vertex
or face per line, as every writer we know emits.
"""

from __future__ import annotations

import re

import numpy as np

from massprops.errors import MeshFormatError
from massprops.io import validate
from massprops.io.source import Source
from massprops.io.textlines import first_columns, line_of_token, parse_numbers, token_starts
from massprops.io.vf import LineCursor
from massprops.mesh.value import Mesh, fan_triangulate

# Geomview's [ST][C][N]OFF: each prefix only appends columns to the vertex lines, which are
# ignored. Case-sensitive on purpose: "nOFF" (n-dimensional) is not "NOFF" (normals).
_HEADER = re.compile(rb"(?:ST)?C?N?OFF(?![A-Za-z])")
_COUNTS = "'n_vertices n_faces n_edges'"
_NEWLINE = 10


def read_off(source: Source) -> Mesh:
    """Read an ASCII OFF file.

    Returns a Mesh: vertices (n, 3) float64 in file units, faces (m, 3) int64 0-based, a polygon
    of k vertices fan-triangulated into k - 2 triangles (``polygon_sizes`` records the layout),
    winding as in the file. Raises MeshFormatError naming the file and line for a missing or
    garbled header or counts, counts that disagree with the data, non-numeric or non-finite
    coordinates, k < 3, too few indices for k, or an index outside 0..n_vertices - 1.
    """
    reader = LineCursor.open(source, "OFF")
    n_vertices, n_faces = _counts(reader)
    vertices = _vertices(reader, n_vertices)
    flat, sizes = _faces(reader, n_vertices, n_faces)
    reader.end("face")
    validate.require_content(n_vertices, n_faces, reader.name)
    faces, polygon_sizes = fan_triangulate(flat, sizes)
    return Mesh(vertices, faces, polygon_sizes, name=reader.name)


def _counts(reader: LineCursor) -> tuple[int, int]:
    """Read the optional header and the counts line; returns (n_vertices, n_faces)."""
    name = reader.name
    if reader.at >= reader.rows.size:
        raise MeshFormatError(
            f"{name}: only comments and blank lines; expected 'OFF' and the counts {_COUNTS}"
        )
    line = reader.line(reader.at)
    text = _row_text(reader)
    header = _HEADER.match(text)
    if header is None:
        _refuse_other_headers(text, name, line)
    else:
        text = text[header.end() :].strip()  # counts may share the header line
        if text.split()[:1] == [b"BINARY"]:
            raise MeshFormatError(
                f"{name}: line {line}: binary OFF is not supported; convert it to ASCII OFF "
                f"(or PLY)"
            )
        if not text:
            reader.at += 1
            if reader.at >= reader.rows.size:
                raise MeshFormatError(
                    f"{name}: the file ends after the header; expected the counts {_COUNTS}"
                )
            line = reader.line(reader.at)
            text = _row_text(reader)
    tokens = text.split()
    if not 2 <= len(tokens) <= 3 or not all(t.isdigit() for t in tokens):
        expected = f"the counts {_COUNTS}" if header else f"'OFF' or the counts {_COUNTS}"
        got = text.decode("utf-8", "replace")[:60]
        raise MeshFormatError(
            f"{name}: line {line}: expected {expected} (integers >= 0), got {got!r}"
        )
    reader.at += 1
    reader.count_lines.update(vertex=line, face=line)
    return int(tokens[0]), int(tokens[1])


def _refuse_other_headers(text: bytes, name: str, line: int) -> None:
    """Raise for a header of an OFF variant this reader does not read (4OFF, nOFF, ...)."""
    first = text.split()[0]
    if first.upper().endswith(b"OFF"):
        raise MeshFormatError(
            f"{name}: line {line}: OFF variant {first.decode('utf-8', 'replace')!r} is not "
            f"supported; expected a 3-D header: OFF, COFF, NOFF, CNOFF or STOFF"
        )


def _row_text(reader: LineCursor) -> bytes:
    """The text of the reader's next data row, without surrounding blanks."""
    row = reader.rows[reader.at]
    return reader.lines.data[reader.lines.starts[row] : reader.lines.ends[row]].strip()


def _vertices(reader: LineCursor, n: int) -> np.ndarray:
    """The n vertex lines: (n, 3) float64, columns after x y z ignored."""
    block, counts, line_numbers = reader.block("vertex", n)
    short = counts < 3
    if short.any():
        i = int(np.argmax(short))
        raise MeshFormatError(
            f"{reader.name}: line {line_numbers[i]}: vertex {i + 1} of {n} has {int(counts[i])} "
            f"value(s); expected 'x y z'; does the vertex count on line "
            f"{reader.count_lines['vertex']} match the file?"
        )
    flat = parse_numbers(
        block, counts, np.float64, name=reader.name, line_numbers=line_numbers, what="'x y z'"
    )
    vertices = np.ascontiguousarray(first_columns(flat, counts, 3))
    validate.require_finite(vertices, reader.name, lambda i: f"line {line_numbers[i]}")
    return vertices


def _faces(reader: LineCursor, n_vertices: int, m: int) -> tuple[np.ndarray, np.ndarray]:
    """The m face lines: (flat 0-based indices (sum(sizes),) int64, sizes (m,) int64)."""
    name = reader.name
    block, counts, line_numbers = reader.block("face", m)
    starts = token_starts(block)
    try:
        sizes = _face_sizes(block, counts, starts, line_numbers, name)
    except MeshFormatError as exc:
        # A wrong vertex count shifts a vertex line into the faces: its "k" fails first.
        raise MeshFormatError(
            f"{exc}; do the counts on line {reader.count_lines['face']} match the file?"
        ) from exc
    indices = _columns(block, counts, starts, np.ones_like(sizes), 1 + sizes)
    raw = parse_numbers(
        indices, sizes, np.int64, name=name, line_numbers=line_numbers,
        what="0-based vertex indices 'k i1 ... ik'",
    )

    def token_line(k: int) -> str:
        return f"line {line_numbers[line_of_token(sizes, k)]}"

    return validate.require_in_range(raw, n_vertices, name, token_line), sizes


def _face_sizes(
    block: bytes, counts: np.ndarray, starts: np.ndarray, line_numbers: np.ndarray, name: str
) -> np.ndarray:
    """(m,) int64: the leading k of each face line, checked: k >= 3 and k indices follow."""
    one = np.ones_like(counts)
    first = _columns(block, counts, starts, np.zeros_like(counts), one)
    sizes = parse_numbers(
        first, one, np.int64, name=name, line_numbers=line_numbers,
        what="the vertex count k of 'k i1 ... ik'",
    )
    validate.require_polygon_sizes(sizes, name, lambda i: f"line {line_numbers[i]}")
    short = sizes > counts - 1
    if short.any():
        i = int(np.argmax(short))
        raise MeshFormatError(
            f"{name}: line {line_numbers[i]}: face {i + 1} announces {int(sizes[i])} vertex "
            f"indices but lists {int(counts[i]) - 1}; expected 'k i1 ... ik'"
        )
    return sizes


def _columns(
    block: bytes, counts: np.ndarray, starts: np.ndarray, begin: np.ndarray, stop: np.ndarray
) -> bytes:
    """Tokens begin[l] <= j < stop[l] (0-based within the line) of each line l of ``block``,
    one line each, as a new block; vectorised (face lines may carry colours after the indices).

    block : newline-terminated lines without leading blanks.
    counts : (L,) tokens per line; starts : (T,) offset of each token (``token_starts``).
    begin, stop : (L,) int, 0 <= begin < stop <= counts.
    """
    buf = np.frombuffer(block, dtype=np.uint8).copy()
    newline = np.flatnonzero(buf == _NEWLINE)
    first = np.cumsum(counts) - counts  # flat number of each line's first token
    lo = starts[first + begin]
    last = np.minimum(first + stop, starts.size - 1)  # clipped: used only where stop < counts
    hi = np.where(stop < counts, starts[last], newline + 1)  # one past the kept bytes
    buf[hi - 1] = _NEWLINE  # the blank before the first dropped token now ends the line
    # Keep [lo, hi) of every line with a running sum of +1/-1 steps (as TextLines.gather does);
    # where one line's hi is the next line's lo the steps cancel and the run goes on.
    step = np.zeros(buf.size + 1, dtype=np.int8)
    step[lo] = 1
    step[hi] -= 1
    keep = np.cumsum(step[:-1], dtype=np.int8).view(bool)
    return buf[keep].tobytes()
