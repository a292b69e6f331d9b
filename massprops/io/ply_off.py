"""Writers for PLY (binary little-endian, read by the fallback) and OFF (ASCII, read by off.py)."""

from __future__ import annotations

from typing import BinaryIO

import numpy as np

from massprops.errors import MeshFormatError
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
