"""Safe output files: one rule for every file a command writes, and atomic writes.

The rule (`check_output`), checked by each command before any work and again by each writer:
the file's extension names a format of what is written (else UsageError, exit 2, naming the
file, its extension and the accepted ones); it is no input of the command, does not exist
unless forced, and its folder exists and is writable (`check_destination`, exit 1).

A file is written to a temporary name in the target's directory (same filesystem, so the final
rename is atomic), flushed and fsync'ed, then renamed over the target. A crash or an exception at
any point leaves either the old file or the complete new one, never a torn mix, and no temporary.
"""

from __future__ import annotations

import contextlib
import os
import stat
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import BinaryIO, NamedTuple

from massprops.errors import (
    MassPropsError,
    MeshFileError,
    OutputExistsError,
    UsageError,
    setting_ref,
)

_TEMP_ATTEMPTS = 100


class OutputKind(NamedTuple):
    """What a command writes to one file: ``what`` in words ("a trajectory"), the
    ``extensions`` (lower case, with the dot) of the formats it can be written in, and the
    ``setting`` (`massprops.errors.setting_ref`) that names the file, None for an argument."""

    what: str
    extensions: tuple[str, ...]
    setting: str | None = None


def check_output(path: str | os.PathLike[str], kind: OutputKind, *, force: bool,
                 protect: Iterable[str | os.PathLike[str]] = ()) -> Path:
    """``path`` as a Path once it passes the rule (the module docstring): UsageError for an
    extension ``kind`` cannot be written in; then `check_destination`."""
    path = check_extension(path, kind)
    check_destination(path, force=force, protect=[Path(os.fspath(p)) for p in protect])
    return path


def check_extension(path: str | os.PathLike[str], kind: OutputKind) -> Path:
    """``path`` as a Path; UsageError naming it, its extension and the accepted ones unless its
    extension (case-insensitive) is one of ``kind``'s."""
    path = Path(os.fspath(path))
    if path.suffix.lower() not in kind.extensions:
        given = f"as {path.suffix!r}" if path.suffix else "without an extension"
        where = "" if kind.setting is None else f" ({setting_ref(kind.setting)})"
        raise UsageError(f"{path}: cannot write {kind.what} {given}{where}; expected "
                         f"{_choices(kind.extensions)}")
    return path


def _choices(extensions: Iterable[str]) -> str:
    names = sorted(extensions)
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} or {names[-1]}"


def atomic_write_bytes(
    path: Path,
    data: bytes,
    *,
    force: bool = False,
    protect: Iterable[str | os.PathLike[str]] = (),
    kind: OutputKind | None = None,
) -> None:
    """Write ``data`` to ``path`` with every guard of this module (for non-mesh outputs such as
    trajectories and plots): `check_output` (``kind`` given) or `check_destination`, then
    `atomic_write`."""
    path = Path(path)
    if kind is not None:
        check_output(path, kind, force=force, protect=protect)
    else:
        check_destination(path, force=force, protect=[Path(p) for p in protect])
    atomic_write(path, lambda stream: stream.write(data), overwrite=force)


def check_destination(path: Path, *, force: bool, protect: Iterable[Path]) -> None:
    """Raise unless ``path`` may be written.

    OutputExistsError if ``path`` is (resolves to, or is a link to) any path in ``protect``, even
    with ``force``, or if it exists and not ``force``; MeshFileError if it is a directory or its
    directory does not exist or is not writable.
    """
    for guarded in protect:
        if same_file(path, guarded):
            raise OutputExistsError(
                f"{path}: is an input of this command ({guarded}); choose another output path"
            )
    if path.is_dir():
        raise MeshFileError(f"{path}: is a directory; expected an output file path")
    if (path.exists() or path.is_symlink()) and not force:
        raise OutputExistsError(f"{path}: already exists; use {setting_ref('force')} to "
                                f"overwrite it")
    parent = path.parent
    if not parent.is_dir():
        raise MeshFileError(f"{path}: the directory {parent} does not exist; create it first")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise MeshFileError(f"{path}: the directory {parent} is not writable; choose another "
                            "folder or make it writable")


def same_file(a: Path, b: Path | str | os.PathLike[str]) -> bool:
    """True if ``a`` and ``b`` name the same file: same inode if both exist, else same real path."""
    try:
        return os.path.samefile(a, b)
    except OSError:  # one does not exist (yet): compare where the paths lead
        return os.path.normcase(os.path.realpath(a)) == os.path.normcase(os.path.realpath(b))


def atomic_write(path: Path, write: Callable[[BinaryIO], object], *, overwrite: bool) -> None:
    """Create or replace ``path`` with what ``write(stream)`` writes, atomically.

    overwrite : False refuses (OutputExistsError) a file that appeared since the check.
    Exceptions of ``write`` propagate after the temporary file is removed; OSErrors of the
    filesystem become MeshFileError naming ``path``.
    """
    fd, tmp = _create_temp(path)
    try:
        with os.fdopen(fd, "wb") as stream:
            write(stream)
            stream.flush()
            os.fsync(stream.fileno())
        _keep_mode(tmp, path)
        _publish(tmp, path, overwrite)
        _sync_directory(path.parent)
    except MassPropsError:
        raise
    except OSError as exc:
        raise _write_error(path, exc) from exc
    finally:
        # After a rename the name is gone; after a failure (or a hard-link publish) it is not.
        with contextlib.suppress(OSError):
            os.unlink(tmp)


def _create_temp(path: Path) -> tuple[int, Path]:
    """Open a new, uniquely named file beside ``path``; mode 0o666 minus the umask, as a plain
    ``open`` would give (``tempfile.mkstemp`` would leave 0o600)."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
    for _ in range(_TEMP_ATTEMPTS):
        tmp = path.parent / f".{path.name}.{os.urandom(4).hex()}.tmp"
        try:
            return os.open(tmp, flags, 0o666), tmp
        except FileExistsError:
            continue
        except OSError as exc:
            raise _write_error(path, exc) from exc
    raise MeshFileError(f"{path}: cannot create a temporary file beside it; check the directory")


def _keep_mode(tmp: Path, path: Path) -> None:
    """Give the new file the permission bits of the file it replaces, if any."""
    with contextlib.suppress(FileNotFoundError):
        os.chmod(tmp, stat.S_IMODE(os.stat(path).st_mode))


def _publish(tmp: Path, path: Path, overwrite: bool) -> None:
    if overwrite:
        os.replace(tmp, path)
        return
    try:
        # A hard link fails if the target exists, closing the window between the existence check
        # and the rename in which another process could create the file.
        os.link(tmp, path)
    except FileExistsError as exc:
        raise OutputExistsError(
            f"{path}: already exists; use {setting_ref('force')} to overwrite it"
        ) from exc
    except OSError:  # a filesystem without hard links: check, then rename
        if path.exists():
            raise OutputExistsError(
                f"{path}: already exists; use {setting_ref('force')} to overwrite it"
            ) from None
        os.replace(tmp, path)


def _sync_directory(directory: Path) -> None:
    """fsync the directory so the rename itself survives a crash (POSIX; best effort)."""
    if os.name != "posix":
        return
    with contextlib.suppress(OSError):
        fd = os.open(directory, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _write_error(path: Path, exc: OSError) -> MeshFileError:
    if isinstance(exc, PermissionError):
        return MeshFileError(f"{path}: permission denied; choose a writable directory")
    return MeshFileError(f"{path}: cannot write the file ({exc.strerror or exc})")
