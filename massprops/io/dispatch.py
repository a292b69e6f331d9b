"""read_mesh and write_mesh: pick the format, apply the unit, guard the output files."""

from __future__ import annotations

import dataclasses
import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import BinaryIO, Union, cast

import numpy as np

from massprops.errors import MeshFormatError, UnknownFormatError, UsageError, setting_ref
from massprops.io.atomic import OutputKind, atomic_write, check_destination, check_extension
from massprops.io.registry import FORMATS, UNITS, Format, Writer, format_named, format_of_path
from massprops.io.source import Source
from massprops.mesh import Mesh

PathLike = Union[str, "os.PathLike[str]"]


def read_mesh(
    source: PathLike | BinaryIO,
    *,
    format: str | None = None,
    unit: str = "m",
    name: str | None = None,
) -> Mesh:
    """Read a mesh file.

    source : a path, or a binary file object (e.g. ``sys.stdin.buffer``; then ``format`` is
        required).
    format : a name of ``FORMATS`` (case-insensitive); default: from the path's extension.
    unit : the unit of the file's coordinates, a key of ``UNITS``; vertices are returned in metres.
    name : what messages and the Mesh call the input; default: the path as given (``<stdin>``
        for a stream without a name).

    Returns a Mesh: vertices (n, 3) float64 in metres, faces (m, 3) int64 0-based (polygons
    fan-triangulated, ``polygon_sizes`` set), coordinate_dtype float32 for binary STL else
    float64, coordinate_scale = ``UNITS[unit]``.
    Raises MeshFileError (cannot open/read), MeshFormatError (bad content), UnknownFormatError
    (no reader for the extension or name), UsageError (unknown unit, stream without format).
    """
    scale = unit_scale(unit)
    src = _source(source, name)
    fmt = _input_format(src, format)
    if fmt.reader is None:
        raise UnknownFormatError(f"{src.name}: massprops cannot read this format")
    mesh = fmt.reader(src)
    if scale == 1.0:  # the common case: no copy
        return dataclasses.replace(mesh, coordinate_scale=1.0)
    return dataclasses.replace(mesh, vertices=mesh.vertices * scale, coordinate_scale=scale)


def write_mesh(
    mesh: Mesh, path: PathLike, *, force: bool = False, protect: Sequence[PathLike] = ()
) -> None:
    """Write ``mesh`` to ``path`` in the format of its extension.

    Coordinates are written in the unit the mesh was read in (vertices / Mesh.coordinate_scale),
    so a part read with ``--unit mm`` is written back in millimetres.

    Never writes over a path in ``protect`` (compared as files: links and different spellings of
    one path count), nor over an existing file unless ``force``: OutputExistsError. A format of
    two files (NAME.vtx + NAME.fac) writes both, each guarded the same way; an input given as
    either part protects both. Each file is written atomically (temporary file, fsync, rename):
    on any failure the old file is left intact and no temporary remains.
    """
    target = Path(os.fspath(path))
    files = check_mesh_output(target, force=force, protect=protect)
    _require_finite_output(mesh, target)
    if mesh.coordinate_scale != 1.0:
        mesh = mesh.with_vertices(mesh.vertices / mesh.coordinate_scale)
    for file, writer in files:
        if writer is None:  # a registry entry without a writer never passes for_writing
            raise UnknownFormatError(f"{file}: no writer for this format")
        # cast: mypy infers no lambda whose default binds the loop variable
        write = cast(Callable[[BinaryIO], None], lambda stream, w=writer: w(mesh, stream))
        atomic_write(file, write, overwrite=force)


def mesh_output() -> OutputKind:
    """A mesh file written by ``align``: the extensions of the formats with a writer."""
    return OutputKind("a mesh", tuple(sorted(ext for f in FORMATS.values() if f.can_write
                                             for ext in f.extensions)))


def check_mesh_output(path: PathLike, *, force: bool = False,
                      protect: Sequence[PathLike] = ()) -> list[tuple[Path, Writer | None]]:
    """The files that writing a mesh to ``path`` makes, each with its writer, once they pass
    the output rule (`massprops.io.atomic`): an extension with a writer (else UsageError, exit
    2), and each file (both of NAME.vtx + NAME.fac) no input, not existing unless ``force``, in
    a writable folder. ``align`` checks this before any work, `write_mesh` again."""
    target = check_extension(path, mesh_output())
    files = format_of_path(target, for_writing=True).files(target)
    guarded = _with_companions(protect)
    for file, _ in files:
        check_destination(file, force=force, protect=guarded)
    return files


def unit_scale(unit: str) -> float:
    """Metres per ``unit``; UsageError listing the units if unknown."""
    if unit not in UNITS:
        raise UsageError(f"unknown unit {unit!r}; expected one of: {', '.join(UNITS)}")
    return UNITS[unit]


def _source(source: PathLike | BinaryIO, name: str | None) -> Source:
    if isinstance(source, (str, bytes, os.PathLike)):
        return Source.from_path(source, name)  # type: ignore[arg-type]
    if not hasattr(source, "read"):
        raise TypeError(f"read_mesh: expected a path or a binary file object, got {type(source)}")
    stream_name = getattr(source, "name", None)
    default = stream_name if isinstance(stream_name, str) else "<stdin>"
    return Source(name=default if name is None else name, stream=source)


def _input_format(src: Source, format_name: str | None) -> Format:
    if format_name is not None:
        try:
            fmt = format_named(format_name)
        except UnknownFormatError as exc:
            raise UnknownFormatError(f"{src.name}: {exc}") from exc
        if fmt.reader is None:
            raise UnknownFormatError(f"{src.name}: massprops cannot read {format_name!r} files")
        return fmt
    if src.path is None:
        raise UsageError(
            f"{src.name}: the format of a stream cannot be guessed; name it "
            f"({setting_ref('input_format')})"
        )
    return format_of_path(src.path, name=src.name)


def _with_companions(protect: Sequence[PathLike]) -> list[Path]:
    """The protected paths plus the other parts of multi-file formats (NAME.fac for NAME.vtx)."""
    guarded = []
    for p in protect:
        path = Path(os.fspath(p))
        guarded.append(path)
        try:
            fmt = format_of_path(path)
        except UnknownFormatError:
            continue
        guarded.extend(part for part, _ in fmt.files(path) if part != path)
    return guarded


def _require_finite_output(mesh: Mesh, target: Path) -> None:
    """Refuse to write NaN/inf coordinates: no reader (ours included) would take them back."""
    bad = ~np.isfinite(mesh.vertices).all(axis=1)
    if bad.any():
        i = int(np.argmax(bad))
        raise MeshFormatError(
            f"{mesh.name}: vertex {i + 1} has a non-finite coordinate; refusing to write {target}"
        )
