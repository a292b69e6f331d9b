"""Where a mesh's bytes come from (a path or a binary stream), and the errors of getting them.

A path is read by `massprops.files.read_input` (regular files only, as every input of
massprops); a stream (standard input, ``-``) as it comes.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import BinaryIO

from massprops.errors import MeshFormatError
from massprops.files import read_error, read_input

__all__ = ["Source", "read_error", "text_content"]

_BOM = b"\xef\xbb\xbf"


@dataclass(frozen=True)
class Source:
    """A mesh input: exactly one of ``path`` and ``stream`` is set.

    name : what messages call the input (the path as given, or e.g. ``<stdin>``).
    path : the file to read, or None for a stream.
    stream : a binary file object opened for reading (e.g. ``sys.stdin.buffer``), or None.
    """

    name: str
    path: Path | None = None
    stream: BinaryIO | None = None

    @classmethod
    def from_path(cls, path: str | os.PathLike[str], name: str | None = None) -> Source:
        text = os.fsdecode(path)
        return cls(name=text if name is None else name, path=Path(text))

    def read_bytes(self) -> bytes:
        """The whole input; MeshFileError if unreadable, MeshFormatError if empty."""
        data = self._read_path(self.path) if self.path is not None else self._read_stream()
        if not data:
            raise MeshFormatError(f"{self.name}: the file is empty; expected a mesh")
        return data

    def _read_path(self, path: Path) -> bytes:
        return read_input(path, name=self.name)

    def _read_stream(self) -> bytes:
        try:
            data = self.stream.read()  # type: ignore[union-attr]
        except OSError as exc:
            raise read_error(self.name, exc) from exc
        # A text stream (sys.stdin rather than sys.stdin.buffer) already decoded the bytes;
        # encoding them back as UTF-8 is lossless.
        return data.encode("utf-8") if isinstance(data, str) else bytes(data)


def text_content(data: bytes, name: str, format_name: str) -> bytes:
    """``data`` without a UTF-8 byte-order mark; MeshFormatError unless it is UTF-8 text without
    NUL bytes.

    A text format read from a binary file (or random bytes) fails here with one clear line,
    instead of deep inside a number parser. The BOM some editors write would otherwise hide the
    keyword of the first line (a lost first vertex shifts every index).
    """
    if data.startswith(_BOM):
        data = data[len(_BOM) :]
    nul = data.find(b"\0")
    if nul >= 0:
        raise MeshFormatError(
            f"{name}: binary data (NUL byte on line {_line_at(data, nul)}) where {format_name} "
            f"text was expected; check the file and its extension"
        )
    if data.isascii():  # the common case, checked at C speed without decoding
        return data
    try:
        data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise MeshFormatError(
            f"{name}: line {_line_at(data, exc.start)} is not UTF-8 text (byte "
            f"0x{data[exc.start]:02x}); expected {format_name} text saved as UTF-8"
        ) from exc
    return data


def _line_at(data: bytes, offset: int) -> int:
    """1-based line number of byte ``offset``."""
    return data.count(b"\n", 0, offset) + 1
