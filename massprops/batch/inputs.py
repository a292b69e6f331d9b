"""Which files a batch inspects: arguments, directories, globs and lists of paths, lazily.

Rules (deterministic, so a run is reproducible and diffable):
- a file argument is taken as given, whatever its extension (the reader says if it cannot read
  it); ``-`` is standard input;
- a directory gives its files with an extension massprops reads (`mesh_extensions`,
  case-insensitive), sorted by name; with ``recursive`` its sub-directories too, depth first,
  files and sub-directories in one name order; symbolic links to directories are not followed
  (no cycles). Of a NAME.vtx + NAME.fac pair only NAME.vtx is listed (one mesh, two files);
- an argument with glob characters (``*?[``) that names no existing file is expanded
  (``**`` crosses directories), matches sorted; a pattern matching nothing is passed on as a
  path, so it fails like any missing file;
- ``files_from``: one path per line (``null``: NUL-separated, as ``find -print0`` writes them),
  ``-`` = standard input, read as it arrives; blank entries are skipped, a trailing CR of a
  line is dropped; each entry is then treated like an argument, except that it is never
  globbed (a name from a list is a name).

A directory without any mesh file, an unlistable directory, an unreadable list, or a special
file (a named pipe, a socket, a device) with a mesh's name in a directory yields a `BadInput`
at its place, so the batch reports it (never opening it) and goes on.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterable, Iterator
from functools import lru_cache
from typing import BinaryIO, NamedTuple

from massprops.errors import MeshFileError, setting_ref
from massprops.files import check_input_file

_GLOB_CHARS = frozenset("*?[")
_LIST_BLOCK = 1 << 16


class BadInput(NamedTuple):
    """An input that names no mesh: ``name`` as the user wrote it, ``error`` to report."""

    name: str
    error: MeshFileError


@lru_cache(maxsize=1)
def mesh_extensions() -> frozenset[str]:
    """Lower-case extensions (with the dot) of every format massprops reads."""
    # deferred: the readers' registry loads the readers; listing paths needs it once
    from massprops.io.registry import FORMATS

    return frozenset(ext for f in FORMATS.values() if f.reader is not None
                     for ext in f.extensions)


@lru_cache(maxsize=1)
def _secondary_parts() -> dict[str, str]:
    """Extension of a later part of a multi-file format -> extension of its first part."""
    # deferred: the readers' registry loads the readers; listing paths needs it once
    from massprops.io.registry import FORMATS

    return {ext: f.parts[0][0] for f in FORMATS.values() if f.parts
            for ext, _ in f.parts[1:]}


def expand_inputs(args: Iterable[str], *, recursive: bool = False,
                  files_from: str | None = None, null: bool = False,
                  stdin: BinaryIO | None = None) -> Iterator[str | BadInput]:
    """The batch's inputs in order: ``args`` expanded, then the entries of ``files_from``.

    Yields paths (str, as given or joined onto their directory) and `BadInput` records; see the
    module docstring for the rules. ``stdin``: the binary stream ``-`` means (default
    ``sys.stdin.buffer``). Nothing is read before it is needed.
    """
    for arg in args:
        yield from _expand(os.fspath(arg), recursive, glob=True)
    if files_from is not None:
        for entry in _list_entries(files_from, null, stdin):
            if isinstance(entry, BadInput):
                yield entry
            else:  # a listed "-" is a file of that name, not standard input
                yield from _expand(os.path.join(".", "-") if entry == "-" else entry,
                                   recursive, glob=False)


def _expand(arg: str, recursive: bool, glob: bool) -> Iterator[str | BadInput]:
    if arg == "-":
        yield arg
    elif os.path.isdir(arg):
        yield from _directory(arg, recursive)
    elif glob and not _GLOB_CHARS.isdisjoint(arg) and not os.path.lexists(arg):
        import glob as globbing  # only a pattern needs it

        matches = sorted(globbing.glob(arg, recursive=True))
        if not matches:
            yield arg  # fails as a missing file, as an unexpanded shell pattern would
        for match in matches:
            yield from _directory(match, recursive) if os.path.isdir(match) else (match,)
    else:
        yield arg


def _directory(top: str, recursive: bool) -> Iterator[str | BadInput]:
    found = False
    for path in _walk(top, recursive):
        if isinstance(path, BadInput):
            yield path
            continue
        found = True
        yield path
    if not found:
        known = ", ".join(sorted(mesh_extensions()))
        yield BadInput(top, MeshFileError(
            f"{top}: no mesh files in this directory{' or below' if recursive else ''} "
            f"(extensions read: {known})"
            + ("" if recursive else f"; {setting_ref('recursive')} descends")))


def _walk(folder: str, recursive: bool) -> Iterator[str | BadInput]:
    try:
        with os.scandir(folder) as it:
            entries = sorted(it, key=lambda e: e.name)
    except OSError as exc:
        yield BadInput(folder, MeshFileError(
            f"{folder}: cannot list the directory ({exc.strerror or exc})"))
        return
    extensions, secondary = mesh_extensions(), _secondary_parts()
    names = {e.name for e in entries}
    for entry in entries:
        path = os.path.join(folder, entry.name)
        try:
            is_dir = entry.is_dir(follow_symlinks=False)
        except OSError:
            is_dir = False
        if is_dir:
            if recursive:
                yield from _walk(path, recursive)
            continue
        stem, ext = os.path.splitext(entry.name)
        ext = ext.lower()
        if ext not in extensions:
            continue
        first = secondary.get(ext)
        if first is not None and (stem + first in names or stem + first.upper() in names):
            continue  # NAME.fac beside NAME.vtx: the pair is one mesh, listed once
        special = _special(entry, path)
        yield path if special is None else BadInput(path, special)


def _special(entry: os.DirEntry, path: str) -> MeshFileError | None:
    """The error for a directory entry with a mesh's name that is a special file (a named
    pipe, a socket, a device: never opened, `massprops.files`), else None (a regular file; a
    broken link is left for the reader to report)."""
    try:
        if entry.is_file():
            return None
        entry.stat()  # a broken link raises here
    except OSError:
        return None
    try:
        check_input_file(path)
    except MeshFileError as exc:
        return exc
    return None


def _list_entries(files_from: str, null: bool, stdin: BinaryIO | None
                  ) -> Iterator[str | BadInput]:
    """The entries of a list file as they arrive (a BadInput if it cannot be read)."""
    sep = b"\0" if null else b"\n"
    try:
        stream = (stdin or sys.stdin.buffer) if files_from == "-" else open(files_from, "rb")
    except OSError as exc:
        yield BadInput(files_from, MeshFileError(
            f"{files_from}: cannot read the list of files ({exc.strerror or exc})"))
        return
    read = getattr(stream, "read1", stream.read)  # read1: what has arrived, not a full block
    rest = b""
    try:
        while True:
            block = read(_LIST_BLOCK)
            if not block:
                break
            *entries, rest = (rest + block).split(sep)
            yield from _names(entries, null)
        yield from _names([rest], null)
    except OSError as exc:
        yield BadInput(files_from, MeshFileError(
            f"{files_from}: cannot read the list of files ({exc.strerror or exc})"))
    finally:
        if stream is not stdin and files_from != "-":
            stream.close()


def _names(entries: list[bytes], null: bool) -> Iterator[str]:
    for raw in entries:
        if not null and raw.endswith(b"\r"):
            raw = raw[:-1]
        if raw:
            yield os.fsdecode(raw)


def stands_for_many(arg: str) -> bool:
    """Whether argument ``arg`` is expanded into a list (a directory, or a glob pattern that
    names no file), rather than being one input."""
    if os.path.isdir(arg):
        return True
    return not _GLOB_CHARS.isdisjoint(arg) and not os.path.lexists(arg)
