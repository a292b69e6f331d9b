"""The native ``.vf`` format and its two-file form ``NAME.vtx`` + ``NAME.fac``.

``.vf``: ``#`` comments, the vertex count N, N lines ``x y z``, the face count M, M lines of
1-based vertex indices (any number per face, counter-clockwise seen from outside). ``.vtx`` holds
the first two blocks, ``.fac`` the last two. Blank lines are ignored; every count must match the
lines that follow it, and an error names the line where the two part ways.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import BinaryIO

import numpy as np

from massprops.errors import MeshFileError, MeshFormatError
from massprops.files import check_input_file
from massprops.io import numtext, validate
from massprops.io.source import Source, text_content
from massprops.io.textlines import TextLines, parse_numbers, strip_comments
from massprops.mesh.value import Mesh, fan_triangulate

VERTEX_SUFFIX = ".vtx"
FACE_SUFFIX = ".fac"


@dataclass
class LineCursor:
    """A cursor over the non-blank lines of one text file."""

    name: str
    lines: TextLines
    counts: np.ndarray  # (L,) tokens on each file line
    rows: np.ndarray  # 0-based file lines that hold data, in order
    at: int = 0  # next entry of rows to read
    count_lines: dict[str, int] = field(default_factory=dict)  # "vertex" -> line of its count

    @classmethod
    def open(cls, source: Source, format_name: str) -> LineCursor:
        data = text_content(source.read_bytes(), source.name, format_name)
        lines = TextLines.from_bytes(strip_comments(data))
        counts = lines.token_counts()
        return cls(source.name, lines, counts, np.flatnonzero(counts > 0))

    def line(self, at: int) -> int:
        """1-based file line of data row ``at``."""
        return int(self.rows[at]) + 1

    def count(self, what: str, hint: str = "") -> int:
        """Read the count line for ``what`` ("vertex" or "face")."""
        if self.at >= self.rows.size:
            raise MeshFormatError(f"{self.name}: the file ends before the {what} count{hint}")
        row = self.rows[self.at]
        text = self.lines.data[self.lines.starts[row] : self.lines.ends[row]].strip()
        if self.counts[row] != 1 or not text.isdigit():
            got = text.decode("utf-8", "replace")[:60]
            raise MeshFormatError(
                f"{self.name}: line {row + 1}: expected the {what} count (one integer >= 0), "
                f"got {got!r}{hint}"
            )
        self.count_lines[what] = int(row) + 1
        self.at += 1
        return int(text)

    def block(self, what: str, n: int) -> tuple[bytes, np.ndarray, np.ndarray]:
        """The next ``n`` data rows: (bytes, tokens per row, 1-based file lines)."""
        rows = self.rows[self.at : self.at + n]
        if rows.size < n:
            raise MeshFormatError(
                f"{self.name}: the file ends after {rows.size} of the {n} {what} lines that the "
                f"count on line {self.count_lines[what]} announces; fix the count or the file"
            )
        self.at += n
        return self.lines.gather(rows), self.counts[rows], rows + 1

    def vertices(self) -> np.ndarray:
        """The vertex count and block: (n, 3) float64."""
        n = self.count("vertex")
        block, counts, line_numbers = self.block("vertex", n)
        bad = counts != 3
        if bad.any():
            i = int(np.argmax(bad))
            hint = (
                f"; is the vertex count on line {self.count_lines['vertex']} ({n}) too large?"
                if counts[i] == 1
                else ""
            )
            raise MeshFormatError(
                f"{self.name}: line {line_numbers[i]}: expected vertex {i + 1} of {n} as "
                f"'x y z', got {_values(int(counts[i]))}{hint}"
            )
        flat = parse_numbers(
            block, counts, np.float64, name=self.name, line_numbers=line_numbers, what="'x y z'"
        )
        vertices = flat.reshape(-1, 3)
        validate.require_finite(vertices, self.name, lambda i: f"line {line_numbers[i]}")
        return vertices

    def faces(self, n_vertices: int, hint: str = "") -> tuple[np.ndarray, np.ndarray]:
        """The face count and block: (flat 0-based indices, sizes)."""
        m = self.count("face", hint)
        block, sizes, line_numbers = self.block("face", m)
        validate.require_polygon_sizes(sizes, self.name, lambda i: f"line {line_numbers[i]}")
        raw = parse_numbers(
            block, sizes, np.int64, name=self.name, line_numbers=line_numbers,
            what="1-based vertex indices",
        )
        cumulative = np.cumsum(sizes)

        def token_line(k: int) -> str:
            return f"line {line_numbers[int(np.searchsorted(cumulative, k, side='right'))]}"

        return validate.one_based_indices(raw, n_vertices, self.name, token_line), sizes

    def end(self, what: str) -> None:
        """Raise if data follows the last ``what`` line."""
        if self.at < self.rows.size:
            raise MeshFormatError(
                f"{self.name}: line {self.line(self.at)}: unexpected data after the last {what}; "
                f"does the {what} count on line {self.count_lines[what]} match the file?"
            )


def read_vf(source: Source) -> Mesh:
    """Read a ``.vf`` file. Returns a Mesh (vertices in file units, polygons fan-triangulated)."""
    reader = LineCursor.open(source, "VF")
    vertices = reader.vertices()
    hint = f"; does the vertex count on line {reader.count_lines['vertex']} match the file?"
    flat, sizes = reader.faces(vertices.shape[0], hint)
    reader.end("face")
    return _mesh(vertices, flat, sizes, source.name)


def read_vtx_fac(source: Source) -> Mesh:
    """Read the pair ``NAME.vtx`` + ``NAME.fac`` given either path (the other must be beside it)."""
    if source.path is None:
        raise MeshFileError(
            f"{source.name}: the vtx/fac format is two files and cannot be read from a stream; "
            f"pass the path of NAME.vtx or NAME.fac"
        )
    # the file named by the user first, so a typo (or a pipe) is reported as such
    check_input_file(source.path, name=source.name)
    vtx_path, fac_path = companion_paths(source.path, for_reading=True)
    vtx = LineCursor.open(_part_source(source, vtx_path), "VTX")
    vertices = vtx.vertices()
    vtx.end("vertex")
    fac = LineCursor.open(_part_source(source, fac_path), "FAC")
    flat, sizes = fac.faces(vertices.shape[0])
    fac.end("face")
    return _mesh(vertices, flat, sizes, source.name)


def companion_paths(path: Path, *, for_reading: bool = False) -> tuple[Path, Path]:
    """(NAME.vtx, NAME.fac) for ``path`` = either of them; the suffixes follow ``path``'s case.

    for_reading : if the same-case companion does not exist, also try the other case and raise
        MeshFileError naming the missing file if neither does.
    """
    case = str.upper if path.suffix.isupper() else str.lower
    pair = (path.with_suffix(case(VERTEX_SUFFIX)), path.with_suffix(case(FACE_SUFFIX)))
    if not for_reading:
        return pair
    found = []
    for part in pair:
        candidates = [part, part.with_suffix(part.suffix.swapcase())]
        existing = [c for c in candidates if c == path or c.exists()]
        if not existing:
            raise MeshFileError(
                f"{part}: no such file; the vtx/fac format needs both {pair[0].name} and "
                f"{pair[1].name} in the same directory"
            )
        found.append(existing[0])
    return found[0], found[1]


def _values(n: int) -> str:
    return f"{n} value" if n == 1 else f"{n} values"


def _part_source(source: Source, path: Path) -> Source:
    return source if path == source.path else Source.from_path(path)


def _mesh(vertices: np.ndarray, flat: np.ndarray, sizes: np.ndarray, name: str) -> Mesh:
    validate.require_content(vertices.shape[0], sizes.size, name)
    faces, polygon_sizes = fan_triangulate(flat, sizes)
    return Mesh(np.ascontiguousarray(vertices), faces, polygon_sizes, name=name)


def write_vf(mesh: Mesh, stream: BinaryIO) -> None:
    """Write ``.vf``: counts, ``x y z`` lines (shortest round-trip repr, bit-identical on reading),
    1-based faces as the file's polygons, winding unchanged."""
    stream.write(b"# massprops .vf: vertex count, x y z lines, face count, 1-based faces (CCW)\n")
    write_vtx(mesh, stream)
    write_fac(mesh, stream)


def write_vtx(mesh: Mesh, stream: BinaryIO) -> None:
    """Write the vertex part: count, then ``x y z`` lines."""
    stream.write(f"{mesh.n_vertices}\n".encode("ascii"))
    numtext.write_float_rows(stream, mesh.vertices)


def write_fac(mesh: Mesh, stream: BinaryIO) -> None:
    """Write the face part: count, then one line of 1-based indices per polygon."""
    flat, sizes = mesh.polygons_flat()
    stream.write(f"{sizes.size}\n".encode("ascii"))
    numtext.write_index_rows(stream, flat, sizes, base=1)
