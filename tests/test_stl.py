"""Binary STL read straight from a path (blocks on two threads): the same mesh as the records say,
whatever the block layout, with or without os.preadv, and a file that shrinks mid-read is refused.

The truth is an independent decoding of the hand-packed records (struct), not the reader itself.
"""

from __future__ import annotations

import io
import os
import struct
import threading

import numpy as np
import pytest

from massprops.errors import MeshFileError, MeshFormatError
from massprops.io import read_mesh, stl

RNG = np.random.default_rng(7)


def packed(triangles: np.ndarray) -> bytes:
    """Header, count and 50-byte records (random normal and attribute: both must be ignored)."""
    records = b"".join(struct.pack("<3f9fH", *RNG.normal(size=3), *t.reshape(-1),
                                   int(RNG.integers(0, 65536)))
                       for t in triangles)
    return b"binary".ljust(80, b"\0") + struct.pack("<I", len(triangles)) + records


def decoded(data: bytes) -> np.ndarray:
    """(3m, 3) float64 corners, decoded record by record with struct."""
    (n,) = struct.unpack_from("<I", data, 80)
    rows = [struct.unpack_from("<9f", data, 84 + 50 * i + 12) for i in range(n)]
    return np.array(rows, dtype=np.float64).reshape(-1, 3)


def triangles(m: int) -> np.ndarray:
    return RNG.normal(scale=100.0, size=(m, 3, 3)).astype(np.float32)


@pytest.mark.parametrize("m", [1, stl._BLOCK - 1, stl._BLOCK, 2 * stl._BLOCK + 5],
                         ids=["one", "under-a-block", "one-block", "two-threads"])
def test_binary_stl_from_a_path_matches_its_records(tmp_path, m):
    data = packed(triangles(m))
    path = tmp_path / "soup.stl"
    path.write_bytes(data)
    mesh = read_mesh(path)
    expected = decoded(data)
    assert mesh.vertices.dtype == np.float64 and mesh.vertices.tobytes() == expected.tobytes()
    np.testing.assert_array_equal(mesh.faces, np.arange(3 * m).reshape(m, 3))
    assert mesh.faces.dtype == np.int64 and mesh.coordinate_dtype == np.float32


def test_a_path_and_a_stream_read_alike(tmp_path):
    data = packed(triangles(2 * stl._BLOCK + 1))
    path = tmp_path / "soup.stl"
    path.write_bytes(data)
    from_stream = read_mesh(io.BytesIO(data), format="stl", name=str(path))
    from_path = read_mesh(path)
    assert from_path.vertices.tobytes() == from_stream.vertices.tobytes()
    np.testing.assert_array_equal(from_path.faces, from_stream.faces)


def test_without_preadv_the_blocks_are_read_in_order(tmp_path, monkeypatch):
    data = packed(triangles(2 * stl._BLOCK + 3))
    path = tmp_path / "soup.stl"
    path.write_bytes(data)
    monkeypatch.delattr(os, "preadv", raising=False)
    assert read_mesh(path).vertices.tobytes() == decoded(data).tobytes()


def test_a_non_finite_corner_deep_in_the_second_half_is_named(tmp_path):
    tris = triangles(2 * stl._BLOCK + 3)
    tris[2 * stl._BLOCK, 1, 2] = np.inf
    tris[2 * stl._BLOCK + 1, 0, 0] = np.nan
    path = tmp_path / "inf.stl"
    path.write_bytes(packed(tris))
    first = 2 * stl._BLOCK
    with pytest.raises(MeshFormatError, match=rf"inf.stl: triangle {first + 1}: vertex "
                                              rf"{3 * first + 2} has a non-finite coordinate"):
        read_mesh(path)


def test_a_file_that_shrinks_while_read_falls_back_to_the_size_check(tmp_path, monkeypatch):
    """The size is checked, then the file is cut short before the blocks are read: the short
    read is noticed and the file's actual size reported."""
    data = packed(triangles(5))
    path = tmp_path / "cut.stl"
    path.write_bytes(data)
    real_fstat = os.fstat

    def fstat_then_truncate(fd):
        result = real_fstat(fd)
        os.truncate(path, len(data) - 7)
        return result

    monkeypatch.setattr(stl.os, "fstat", fstat_then_truncate)
    with pytest.raises(MeshFormatError, match=r"cut.stl: binary STL header says 5 triangles .* "
                                              r"has 327 bytes \(truncated\)"):
        read_mesh(path)


def test_a_binary_stl_from_a_named_pipe_is_refused_unopened(tmp_path):
    """A pipe (e.g. bash's <(cat x.stl)) is a special file: refused before it is opened, even
    with a writer waiting (issue 30; standard input, '-', is the way to stream a mesh)."""
    fifo = tmp_path / "pipe.stl"
    os.mkfifo(fifo)
    # daemon: the writer blocks in open() until a reader comes, which massprops never is
    writer = threading.Thread(target=fifo.write_bytes, args=(packed(triangles(3)),), daemon=True)
    writer.start()
    with pytest.raises(MeshFileError, match="pipe.stl: is a named pipe"):
        read_mesh(fifo)
    assert writer.is_alive()  # nobody opened the pipe for reading
    with open(fifo, "rb") as release:  # let the writer finish
        release.read()
    writer.join(timeout=10)
    assert not writer.is_alive()


@pytest.mark.timeout(10)
def test_the_fast_path_never_opens_a_named_pipe(tmp_path):
    """Whether to take the fast path is decided from a stat of the path: a pipe is left to the
    caller's single read. Opening it here would block (no writer): the timeout fails the test."""
    fifo = tmp_path / "pipe.stl"
    os.mkfifo(fifo)
    assert stl._read_binary_file(fifo, "pipe.stl") is None
