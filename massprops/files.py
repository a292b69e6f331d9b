"""Input files: every file massprops reads by its path is opened here, regular files only.

Meshes, scenes, robot descriptions and their includes, density maps: each is opened by
`open_input` / `read_input`, or checked by `check_input_file` first where a library opens it by
its path (trimesh, meshio, OpenCASCADE, xacro). A special file (a named pipe, a socket, a
device) is refused before it is opened: opening a pipe blocks until a writer comes, and reading
a device may never end. Standard input is read as a stream (``-``), never through a path.
Failures are MeshFileError (exit 1), one line naming the file.
"""

from __future__ import annotations

import os
import stat
from typing import BinaryIO

from massprops.errors import MeshFileError

__all__ = ["check_input_file", "file_problem", "open_input", "read_error", "read_input",
           "special_file_kind"]


def read_input(path: str | os.PathLike[str], *, name: str | None = None,
               what: str = "a mesh file") -> bytes:
    """The whole file at ``path`` (see `open_input`); every failure is a MeshFileError naming
    ``name`` (default: the path)."""
    shown = os.fspath(path) if name is None else name
    with open_input(path, name=shown, what=what) as f:
        try:
            return f.read()
        except OSError as exc:
            raise read_error(shown, exc, what) from exc


def open_input(path: str | os.PathLike[str], *, name: str | None = None,
               what: str = "a mesh file") -> BinaryIO:
    """``path`` opened for reading in binary, refused (MeshFileError naming ``name``, default the
    path) unless it is a regular file: missing, a directory, no permission, or a special file.

    The file is opened without blocking and checked again once open, so a pipe put in its place
    after the first check is refused too, not waited on. ``what`` says what was expected
    ("a mesh file", "a scene file", ...)."""
    shown = os.fspath(path) if name is None else name
    _refuse_special(path, shown, what)
    try:
        f = open(path, "rb", opener=_without_blocking)
    except OSError as exc:
        raise read_error(shown, exc, what) from exc
    try:
        mode = os.fstat(f.fileno()).st_mode
    except OSError as exc:
        f.close()
        raise read_error(shown, exc, what) from exc
    if not stat.S_ISREG(mode):
        f.close()
        raise _not_regular(shown, mode, what)
    if _NONBLOCK:  # back to ordinary reads (no effect on a regular file, but say what we mean)
        os.set_blocking(f.fileno(), True)
    return f


def check_input_file(path: str | os.PathLike[str], *, name: str | None = None,
                     what: str = "a mesh file") -> None:
    """Raise MeshFileError naming ``name`` (default: the path) unless ``path`` names a regular
    file (after links): for a missing path, a directory, or a special file (a named pipe, a
    socket, a device), which is never opened. For inputs a library opens by its path."""
    shown = os.fspath(path) if name is None else name
    try:
        mode = os.stat(path).st_mode
    except OSError as exc:
        raise read_error(shown, exc, what) from exc
    except ValueError as exc:  # a NUL byte in the name: no such file can exist
        raise MeshFileError(f"{shown}: no such file; check the path") from exc
    if not stat.S_ISREG(mode):
        raise _not_regular(shown, mode, what)


def file_problem(path: str | os.PathLike[str]) -> str | None:
    """None if ``path`` names a regular file (after links), else what it is instead, in words
    that follow its name: "does not exist", "is a directory, not a file", "is a named pipe
    (FIFO), not a regular file". For readers that place the problem themselves (a scene key)."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return "does not exist"
    kind = special_file_kind(mode)
    if kind is None:
        return None
    return f"is {kind}, not a {'' if stat.S_ISDIR(mode) else 'regular '}file"


def _refuse_special(path: str | os.PathLike[str], name: str, what: str) -> None:
    """MeshFileError if ``path`` is there and not a regular file; anything else (missing, no
    permission) is left for the open to say."""
    try:
        mode = os.stat(path).st_mode
    except (OSError, ValueError):
        return
    if not stat.S_ISREG(mode):
        raise _not_regular(name, mode, what)


def special_file_kind(mode: int) -> str | None:
    """What a non-regular file of ``st_mode`` is, in words ("a named pipe (FIFO)"); None for a
    regular file."""
    if stat.S_ISREG(mode):
        return None
    for test, words in _SPECIAL_KINDS:
        if test(mode):
            return words
    return "a special file"


_SPECIAL_KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a named pipe (FIFO)"),
    (stat.S_ISSOCK, "a socket"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
)

_NONBLOCK = getattr(os, "O_NONBLOCK", 0)  # POSIX; elsewhere a pipe has no path to open


def _without_blocking(path: str, flags: int) -> int:
    """`open`'s opener: O_NONBLOCK, so that opening a named pipe returns at once (then refused)
    instead of waiting for a writer."""
    return os.open(path, flags | _NONBLOCK)


def _not_regular(name: str, mode: int, what: str) -> MeshFileError:
    kind = special_file_kind(mode)
    if stat.S_ISDIR(mode):
        return MeshFileError(f"{name}: is a directory; expected {what}")
    return MeshFileError(f"{name}: is {kind}, not a regular file; expected {what}")


def read_error(name: str, exc: OSError, what: str = "a mesh file") -> MeshFileError:
    """The MeshFileError for an OSError met while opening or reading ``name``."""
    if isinstance(exc, FileNotFoundError):
        return MeshFileError(f"{name}: no such file; check the path")
    if isinstance(exc, IsADirectoryError):
        return MeshFileError(f"{name}: is a directory; expected {what}")
    if isinstance(exc, PermissionError):
        return MeshFileError(f"{name}: permission denied; make the file readable")
    return MeshFileError(f"{name}: cannot read the file ({exc.strerror or exc})")
