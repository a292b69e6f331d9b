"""STL, binary and ASCII (told apart by content, not extension), read as a triangle soup."""

from __future__ import annotations

import itertools
import os
import re
import stat
from io import BufferedIOBase
from pathlib import Path
from typing import BinaryIO

import numpy as np

from massprops.errors import MeshFormatError
from massprops.io import validate
from massprops.io.source import Source, text_content
from massprops.mesh import Mesh
from massprops.parallel import in_halves

_HEADER_BYTES = 80
_COUNT_BYTES = 4
_RECORD = np.dtype([("normal", "<f4", (3,)), ("v", "<f4", (9,)), ("attr", "<u2")])  # 50 bytes
_WRITER_HEADER = b"massprops".ljust(_HEADER_BYTES, b" ")
_FLOAT32_MAX = float(np.finfo(np.float32).max)
_BLOCK = 1 << 14  # records per read: the 800 KB buffer and its 1.2 MB of float64 stay in L2

_NUMBER = rb"\s+(\S+)"
_FACET = re.compile(
    rb"facet\s+normal(?:\s+\S+){3}\s+outer\s+loop"
    + (rb"\s+vertex" + _NUMBER * 3) * 3
    + rb"\s+endloop\s+endfacet",
    re.IGNORECASE,
)
_FACET_START = re.compile(rb"(?<![A-Za-z])facet\b", re.IGNORECASE)
_SOLID_LINE = re.compile(rb"^\s*(?:end)?solid\b[^\n]*$", re.IGNORECASE | re.MULTILINE)


def read_stl(source: Source) -> Mesh:
    """Read a binary or ASCII STL file as a triangle soup.

    Binary when the size is exactly 84 + 50 n bytes for the header's count n, even if the 80-byte
    header starts with ``solid``; else ASCII when the text starts with ``solid``. The stored normal
    is ignored: the vertex order (counter-clockwise from outside) decides the orientation.

    Returns a Mesh with vertices (3m, 3) float64 in file order (file units; coordinate_dtype
    float32 for binary) and faces ``arange(3m).reshape(m, 3)``: shared corners are NOT welded.
    """
    if source.path is not None:
        mesh = _read_binary_file(source.path, source.name)
        if mesh is not None:
            return mesh
    data = source.read_bytes()
    n = _header_count(data)
    if n is not None and len(data) == _HEADER_BYTES + _COUNT_BYTES + _RECORD.itemsize * n:
        return _read_binary(data, n, source.name)
    if _looks_ascii(data):
        return _read_ascii(data, source.name)
    raise _size_error(data, n, source.name)


def _header_count(data: bytes) -> int | None:
    """The triangle count of a binary header, or None if the file is shorter than a header."""
    if len(data) < _HEADER_BYTES + _COUNT_BYTES:
        return None
    return int(np.frombuffer(data, dtype="<u4", count=1, offset=_HEADER_BYTES)[0])


def _looks_ascii(data: bytes) -> bool:
    """True if the file is ASCII STL text: it starts with ``solid`` (as binary headers may too)
    and holds no NUL byte (binary records nearly always do: small counts, zero attributes)."""
    head = data[:1024].removeprefix(b"\xef\xbb\xbf").lstrip()  # a BOM from a text editor
    return head.lower().startswith(b"solid") and b"\0" not in data


def _size_error(data: bytes, n: int | None, name: str) -> MeshFormatError:
    if n is None:
        return MeshFormatError(
            f"{name}: {len(data)} bytes is too short for binary STL (84-byte header) and the "
            f"text does not start with 'solid'; expected an STL file"
        )
    expected = _HEADER_BYTES + _COUNT_BYTES + _RECORD.itemsize * n
    problem = "truncated" if expected > len(data) else "has trailing data"
    return MeshFormatError(
        f"{name}: binary STL header says {n} triangles ({expected} bytes) but the file has "
        f"{len(data)} bytes ({problem}); re-export the file"
    )


def _read_binary(data: bytes, n: int, name: str) -> Mesh:
    if n == 0:
        raise MeshFormatError(f"{name}: binary STL with 0 triangles; expected a surface mesh")
    # The size check above bounds n by the file's length: no allocation trusts the header.
    records = np.frombuffer(data, dtype=_RECORD, count=n, offset=_HEADER_BYTES + _COUNT_BYTES)
    vertices = records["v"].reshape(-1, 3).astype(np.float64)
    if not np.isfinite(vertices).all():  # one flat pass; the row-wise search only on failure
        validate.require_finite(vertices, name, lambda i: f"triangle {i // 3 + 1}")
    return _soup(vertices, np.dtype(np.float32), name)


def _read_binary_file(path: Path, name: str) -> Mesh | None:
    """A well-formed binary STL file read straight into the mesh arrays, else None (the caller
    then reads the bytes and explains what is wrong, or reads ASCII).

    Block by block, on two threads where the platform has ``os.preadv``: the 50-byte records are
    never held whole in memory, and the float32 -> float64 widening, the finiteness check and the
    soup's face indices are written while a block is in cache.
    """
    try:
        # Decided from the path, before any open: opening a FIFO blocks until a writer comes, so
        # anything but a regular file is left to the caller's read, which refuses it unopened
        # (massprops.files).
        if not stat.S_ISREG(os.stat(path).st_mode):
            return None
        with open(path, "rb") as f:
            status = os.fstat(f.fileno())
            if not stat.S_ISREG(status.st_mode):  # replaced by a pipe since the stat: give up
                return None
            n = _header_count(f.read(_HEADER_BYTES + _COUNT_BYTES))
            if not n or status.st_size != _HEADER_BYTES + _COUNT_BYTES + _RECORD.itemsize * n:
                return None
            soup = Mesh(np.empty((3 * n, 3)), np.empty((n, 3), np.int64), None,
                        coordinate_dtype=np.dtype(np.float32), name=name)
            if hasattr(os, "preadv"):
                fd = f.fileno()
                parts = in_halves(lambda lo, hi: _fill(fd, soup, lo, hi), n, _BLOCK)
            else:
                parts = [_fill(f, soup, 0, n)]
    except OSError:
        return None
    if None in parts:  # the file shrank while being read
        return None
    if not all(parts):
        validate.require_finite(soup.vertices, name, lambda i: f"triangle {i // 3 + 1}")
    return soup


def _fill(file: int | BufferedIOBase, soup: Mesh, start: int, stop: int) -> bool | None:
    """Fill triangles start .. stop of ``soup`` from the records of ``file`` (a descriptor read
    with os.preadv, or a file object read in order): the corners widened to float64 and the
    faces ``arange(3m).reshape(m, 3)``. Returns whether every coordinate is finite, or None if the
    file ended early."""
    buffer = np.empty(min(_BLOCK, stop - start) * _RECORD.itemsize, np.uint8)
    corners, faces = soup.vertices.reshape(-1, 9), soup.faces.reshape(-1)
    finite = True
    for lo in range(start, stop, _BLOCK):
        hi = min(lo + _BLOCK, stop)
        raw = buffer[: (hi - lo) * _RECORD.itemsize]
        offset = _HEADER_BYTES + _COUNT_BYTES + lo * _RECORD.itemsize
        # numpy's stubs give ndarray __buffer__ only from Python 3.12 (mypy checks 3.10)
        if isinstance(file, int):
            got = os.preadv(file, [raw], offset)  # type: ignore[list-item]
        else:
            file.seek(offset)
            got = file.readinto(raw)  # type: ignore[arg-type]
        if got != raw.size:
            return None
        block = corners[lo:hi]
        np.copyto(block, raw.view(_RECORD)["v"])
        finite = finite and bool(np.isfinite(block).all())
        faces[3 * lo : 3 * hi] = np.arange(3 * lo, 3 * hi)
    return finite


def _read_ascii(data: bytes, name: str) -> Mesh:
    data = text_content(data, name, "ASCII STL")
    corners = _FACET.findall(data)
    _require_only_facets(data, len(corners), name)
    if not corners:
        raise MeshFormatError(f"{name}: ASCII STL with no facets; expected a surface mesh")
    tokens = list(itertools.chain.from_iterable(corners))
    try:
        vertices = np.array(tokens, dtype=np.float64).reshape(-1, 3)
    except ValueError as exc:
        raise _bad_number(data, tokens, name) from exc
    validate.require_finite(vertices, name, lambda i: f"facet {i // 3 + 1}")
    return _soup(vertices, np.dtype(np.float64), name)


def _require_only_facets(data: bytes, n_complete: int, name: str) -> None:
    """Raise if the text holds anything but ``solid`` lines and ``n_complete`` complete facets."""
    if len(_FACET_START.findall(data)) != n_complete:
        raise MeshFormatError(
            f"{name}: line {_first_broken_facet(data)}: malformed facet; expected 'facet normal "
            f"nx ny nz / outer loop / vertex x y z (3 times) / endloop / endfacet'"
        )
    rest = _SOLID_LINE.sub(b"", _FACET.sub(b"", data))
    if rest.strip():
        stray = rest.split()[0].decode("utf-8", "replace")
        raise MeshFormatError(
            f"{name}: unexpected text {stray!r} outside the facets; expected only 'solid', "
            f"facets and 'endsolid'"
        )
    if not data.rstrip().rsplit(b"\n", 1)[-1].lstrip().lower().startswith(b"endsolid"):
        raise MeshFormatError(f"{name}: no final 'endsolid' line (truncated?); re-export the file")


def _first_broken_facet(data: bytes) -> int:
    """Line number of the first ``facet`` that does not start a complete facet (slow path)."""
    for start in _FACET_START.finditer(data):
        if not _FACET.match(data, start.start()):
            return data.count(b"\n", 0, start.start()) + 1
    return data.count(b"\n") + 1


def _bad_number(data: bytes, tokens: list[bytes], name: str) -> MeshFormatError:
    for k, token in enumerate(tokens):
        try:
            float(token)
        except ValueError:
            text = token.decode("utf-8", "replace")
            return MeshFormatError(
                f"{name}: facet {k // 9 + 1}: {text!r} is not a number; expected 'vertex x y z'"
            )
    return MeshFormatError(f"{name}: unreadable vertex coordinates; expected 'vertex x y z'")


def _soup(vertices: np.ndarray, dtype: np.dtype, name: str) -> Mesh:
    faces = np.arange(vertices.shape[0], dtype=np.int64).reshape(-1, 3)
    return Mesh(vertices, faces, None, coordinate_dtype=dtype, name=name)


def write_stl(mesh: Mesh, stream: BinaryIO) -> None:
    """Write binary STL: header ``massprops``, one record per triangle of ``mesh.faces``.

    Lossy: coordinates are rounded to float32 (relative error <= 6e-8) and polygons are written as
    their fan triangles. The normal is the unit right-hand normal of the winding (zero for a
    degenerate triangle).
    """
    if mesh.vertices.size and np.abs(mesh.vertices).max() > _FLOAT32_MAX:
        raise MeshFormatError(
            f"{mesh.name}: coordinates beyond the float32 range cannot be stored in STL; "
            f"write OBJ, PLY or .vf instead"
        )
    corners = mesh.vertices[mesh.faces]  # (m, 3, 3)
    normal = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    length = np.linalg.norm(normal, axis=1, keepdims=True)
    unit = np.divide(normal, length, out=np.zeros_like(normal), where=length > 0)
    records = np.zeros(corners.shape[0], dtype=_RECORD)
    records["normal"] = unit
    records["v"] = corners.reshape(-1, 9)
    stream.write(_WRITER_HEADER)
    stream.write(np.uint32(corners.shape[0]).astype("<u4").tobytes())
    stream.write(records.tobytes())
