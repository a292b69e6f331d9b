"""Every other format (PLY, VTK, glTF, ...): meshio first, then trimesh.

Both libraries are imported only when such a file is read (trimesh alone costs ~0.7 s of start-up).
They are kept on a short leash: warnings silenced, their prints captured (meshio reports a failed
read by printing and calling ``sys.exit``), trimesh asked for the file's own vertices and winding
(``process=False``: no merging, no re-winding), and any failure turned into one MeshFormatError.
"""

from __future__ import annotations

import contextlib
import io
import os
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass

import numpy as np

from massprops.errors import MeshFormatError
from massprops.files import open_input, read_error
from massprops.io import validate
from massprops.io.source import Source
from massprops.mesh.value import Mesh, fan_triangulate

_SURFACE_CELLS = ("triangle", "quad", "polygon")


@dataclass(frozen=True)
class FallbackReader:
    """Reader for one format name of meshio and/or trimesh (None: that library cannot read it)."""

    meshio_format: str | None
    trimesh_type: str | None
    extension: str  # for a stream spilled to a temporary file, so the libraries see its type
    float32_only: bool = False  # the format stores positions as float32 (glTF) whatever is read
    check: Callable[[str, str], None] | None = None  # (path, name): the format's own checks

    def __call__(self, source: Source) -> Mesh:
        """Returns a Mesh in file units: the file's vertices (float64) and its polygonal cells
        (triangles, quads, polygons) fan-triangulated, 0-based, winding as in the file;
        coordinate_dtype float32 if the file stores float32 coordinates."""
        failures = []
        with _local_path(source, self.extension) as path:
            if self.check is not None:
                self.check(path, source.name)
            for library, fmt, read in (
                ("meshio", self.meshio_format, _read_meshio),
                ("trimesh", self.trimesh_type, _read_trimesh),
            ):
                if fmt is None:
                    continue
                try:
                    points, flat, sizes, stored = read(path, fmt)
                except _NoSurface as exc:
                    raise MeshFormatError(f"{source.name}: {exc}") from exc
                except Exception as exc:  # noqa: BLE001 - third-party readers raise anything
                    failures.append(f"{library}: {_one_line(exc)}")
                    continue
                if self.float32_only:
                    stored = np.dtype(np.float32)
                return _mesh(points, flat, sizes, stored, source.name)
        fmt_name = (self.meshio_format or self.trimesh_type or "?").upper()
        raise MeshFormatError(
            f"{source.name}: cannot read as {fmt_name} ({'; '.join(failures)}); check the file"
        )


class _NoSurface(Exception):
    """The file was read but holds no polygonal surface cells (e.g. only tetrahedra or points)."""


def _read_meshio(path: str, fmt: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.dtype]:
    import meshio

    with _quiet() as printed:
        try:
            mesh = meshio.read(path, file_format=fmt)
        except SystemExit as exc:
            raise RuntimeError(printed.getvalue() or "meshio gave up") from exc
    flats, sizes, others = [], [], []
    for block in mesh.cells:
        # Exact names: "triangle6" and "quad8" list mid-side nodes, not a polygon's corners.
        if block.type not in _SURFACE_CELLS:
            others.append(block.type)
            continue
        for row in _rows(block.data):
            flats.append(row)
            sizes.append(np.full(row.shape[0], row.shape[1], dtype=np.int64))
    if not flats:
        found = ", ".join(sorted(set(others))) or "no cells"
        raise _NoSurface(
            f"no surface cells (found: {found}); expected triangles, quads or polygons"
        )
    flat = np.concatenate([f.reshape(-1) for f in flats]).astype(np.int64)
    stored = np.dtype(np.float32 if mesh.points.dtype.itemsize == 4 else np.float64)
    return np.asarray(mesh.points, dtype=np.float64), flat, np.concatenate(sizes), stored


def _rows(data) -> list[np.ndarray]:
    """A meshio cell block's connectivity as 2-D int arrays (one per polygon size)."""
    array = np.asarray(data) if not isinstance(data, list) else None
    if array is not None and array.ndim == 2:
        return [array.astype(np.int64)]
    return [np.asarray(cell, dtype=np.int64).reshape(1, -1) for cell in data]


def _read_trimesh(
    path: str, file_type: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.dtype]:
    import trimesh

    with _quiet():
        mesh = trimesh.load_mesh(path, file_type=file_type, process=False)
    faces = np.asarray(getattr(mesh, "faces", np.empty((0, 3))), dtype=np.int64)
    if faces.size == 0:
        raise _NoSurface("no faces (a point cloud or a drawing?); expected a surface mesh")
    sizes = np.full(faces.shape[0], faces.shape[1], dtype=np.int64)
    # trimesh converts to float64 whatever the file held: float32 formats say so in the registry.
    vertices = np.asarray(mesh.vertices, dtype=np.float64)
    return vertices, faces.reshape(-1), sizes, np.dtype(np.float64)


def _mesh(
    points: np.ndarray, flat: np.ndarray, sizes: np.ndarray, stored: np.dtype, name: str
) -> Mesh:
    if points.ndim != 2 or points.shape[1] != 3:
        raise MeshFormatError(
            f"{name}: points of shape {points.shape}; expected 3-D points (n, 3)"
        )
    validate.require_content(points.shape[0], sizes.size, name)
    validate.require_finite(points, name, lambda i: f"point {i + 1}")
    validate.require_polygon_sizes(sizes, name, lambda i: f"cell {i + 1}")
    validate.require_in_range(flat, points.shape[0], name, lambda k: f"index {k + 1}")
    faces, polygon_sizes = fan_triangulate(flat, sizes)
    return Mesh(np.ascontiguousarray(points), faces, polygon_sizes, stored, name=name)


@contextlib.contextmanager
def _quiet() -> Iterator[io.StringIO]:
    """Silence warnings and capture anything the library prints (the library must not print)."""
    printed = io.StringIO()
    with (
        warnings.catch_warnings(),
        contextlib.redirect_stdout(printed),
        contextlib.redirect_stderr(printed),
    ):
        warnings.simplefilter("ignore")
        yield printed


@contextlib.contextmanager
def _local_path(source: Source, extension: str) -> Iterator[str]:
    """A path the libraries can open: the file itself, or a stream spilled to a temporary file."""
    if source.path is not None:
        _require_readable(source)
        yield str(source.path)
        return
    data = source.read_bytes()
    import tempfile  # only a stream read through meshio/trimesh needs it: not at start-up

    fd, tmp = tempfile.mkstemp(suffix=extension, prefix="massprops-")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        yield tmp
    finally:
        os.unlink(tmp)


def _require_readable(source: Source) -> None:
    """The same MeshFileError/MeshFormatError as the own readers for missing or empty files."""
    with open_input(source.path, name=source.name) as f:  # type: ignore[arg-type]
        try:
            empty = not f.read(1)
        except OSError as exc:
            raise read_error(source.name, exc) from exc
    if empty:
        raise MeshFormatError(f"{source.name}: the file is empty; expected a mesh")


def _one_line(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= 160 else text[:157] + "..."
