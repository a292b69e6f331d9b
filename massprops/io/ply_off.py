"""Writers for PLY (binary little-endian, read by the fallback) and OFF (ASCII, read by off.py);
the PLY header's counts checked against the body before the fallback reads it."""

from __future__ import annotations

import os
from typing import Any, BinaryIO, cast

import numpy as np

from massprops.errors import MeshFormatError
from massprops.files import open_input
from massprops.io import numtext
from massprops.mesh import Mesh

_INT32_MAX = int(np.iinfo(np.int32).max)
_UCHAR_MAX = 255


def write_ply(mesh: Mesh, stream: BinaryIO) -> None:
    """Write binary little-endian PLY: ``double`` x y z (exact), faces as ``list uchar int``
    vertex_indices (``list uint int`` if a polygon has more than 255 vertices), winding
    unchanged."""
    if mesh.n_vertices > _INT32_MAX:
        raise MeshFormatError(
            f"{mesh.name}: {mesh.n_vertices} vertices exceed PLY's int32 indices; write .vf instead"
        )
    flat, sizes = mesh.polygons_flat()
    small = sizes.max(initial=3) <= _UCHAR_MAX
    count_type, count_dtype = ("uchar", "u1") if small else ("uint", "<u4")
    header = (
        "ply\nformat binary_little_endian 1.0\ncomment written by massprops\n"
        f"element vertex {mesh.n_vertices}\n"
        "property double x\nproperty double y\nproperty double z\n"
        f"element face {sizes.size}\n"
        f"property list {count_type} int vertex_indices\nend_header\n"
    )
    stream.write(header.encode("ascii"))
    stream.write(mesh.vertices.astype("<f8").tobytes())
    stream.write(_face_records(flat, sizes, np.dtype(count_dtype)))


def _face_records(flat: np.ndarray, sizes: np.ndarray, count_dtype: np.dtype) -> bytes:
    """PLY list records ``count i0 i1 ...`` for polygons of any sizes, as one byte string."""
    if sizes.size and (sizes == sizes[0]).all():
        k = int(sizes[0])
        records = np.empty(sizes.size, dtype=[("n", count_dtype), ("i", "<i4", (k,))])
        records["n"] = k
        records["i"] = flat.reshape(-1, k)
        return records.tobytes()
    # Mixed sizes: scatter counts and index bytes into one buffer at computed offsets.
    width = count_dtype.itemsize
    record_bytes = width + 4 * sizes
    record_at = np.cumsum(record_bytes) - record_bytes
    out = np.zeros(int(record_bytes.sum()), dtype=np.uint8)
    count_bytes = sizes.astype(count_dtype).view(np.uint8).reshape(-1, width)
    out[record_at[:, None] + np.arange(width)] = count_bytes
    polygon = np.repeat(np.arange(sizes.size), sizes)
    slot = np.arange(flat.size) - np.repeat(np.cumsum(sizes) - sizes, sizes)
    index_at = record_at[polygon] + width + 4 * slot
    out[index_at[:, None] + np.arange(4)] = flat.astype("<i4").view(np.uint8).reshape(-1, 4)
    return out.tobytes()


def write_off(mesh: Mesh, stream: BinaryIO) -> None:
    """Write ASCII OFF: ``OFF``, ``N M 0``, ``x y z`` lines (shortest round-trip repr), then
    ``k i0 ... ik-1`` per polygon (0-based, winding unchanged)."""
    flat, sizes = mesh.polygons_flat()
    stream.write(f"OFF\n{mesh.n_vertices} {sizes.size} 0\n".encode("ascii"))
    numtext.write_float_rows(stream, mesh.vertices)
    numtext.write_index_rows(stream, flat, sizes, with_count=True)


_PLY_SIZES = {"char": 1, "uchar": 1, "int8": 1, "uint8": 1, "short": 2, "ushort": 2,
              "int16": 2, "uint16": 2, "int": 4, "uint": 4, "int32": 4, "uint32": 4,
              "float": 4, "float32": 4, "double": 8, "float64": 8}
_PLY_HEAD = 1 << 16  # a header longer than this is no mesh exporter's
_WORDS = {"vertex": ("vertex", "vertices"), "face": ("face", "faces")}


def check_ply_body(path: str | os.PathLike[str], name: str) -> None:
    """MeshFormatError naming ``name`` when the PLY file's body holds fewer elements than its
    header declares (a copy or download cut short): the libraries would read what is there and
    report "no faces" or an open mesh instead. ASCII: one element per non-blank line; binary:
    the elements of fixed size before the first with a list (the faces' sizes vary, meshio
    and trimesh measure those themselves). A header this does not understand is left to them."""
    with open_input(path, name=name) as f:
        head = f.read(_PLY_HEAD)
        end = head.find(b"end_header")
        eol = head.find(b"\n", end)
        if not head.startswith(b"ply") or end < 0 or eol < 0:
            return
        fmt, elements = _ply_header(head[:eol].decode("ascii", "replace"))
        if fmt is None or not elements:
            return
        body = head[eol + 1:]
        found: list[int | None]  # None: an element of unknown size (binary)
        if fmt == "ascii":
            text = (body + f.read()).strip()
            available = text.count(b"\n") + 1 if text else 0
            found = []
            for _, count, _ in elements:
                found.append(min(count, available))
                available -= cast(int, found[-1])
        else:
            available = os.fstat(f.fileno()).st_size - (eol + 1)
            found = []
            for _, count, stride in elements:
                if stride is None:  # a list: its size is not known from the header
                    found.append(None)
                    available = -1
                    continue
                got = count if available >= count * stride else max(available, 0) // stride
                found.append(got)
                available = available - count * stride if available >= 0 else -1
    if any(n is not None and n < c for (_, c, _), n in zip(elements, found)):
        declared = " and ".join(_count(c, e) for e, c, _ in elements)
        held = " and ".join(_count(n, e) for (e, _, _), n in zip(elements, found)
                            if n is not None)
        raise MeshFormatError(f"{name}: truncated: the header declares {declared}, the file "
                              f"holds {held}; copy or export the file again")


def _count(n: int, element: str) -> str:
    one, many = _WORDS.get(element, (f"{element} element", f"{element} elements"))
    return f"{n} {one if n == 1 else many}"


def _ply_header(text: str) -> tuple[str | None, list[tuple[str, int, int | None]]]:
    """(format, [(element, count, bytes per element or None with a list property)])."""
    fmt: str | None = None
    elements: list[list[Any]] = []  # [element, count, stride]: the stride grows per property
    for line in text.splitlines():
        words = line.split()
        if len(words) >= 2 and words[0] == "format":
            fmt = words[1]
        elif len(words) == 3 and words[0] == "element" and words[2].isdigit():
            elements.append([words[1], int(words[2]), 0])
        elif words[:1] == ["property"] and elements:
            size = _PLY_SIZES.get(words[1]) if len(words) == 3 else None
            last = elements[-1]
            last[2] = None if size is None or last[2] is None else last[2] + size
    return fmt, [(e, c, stride) for e, c, stride in elements]

