"""``--write OUT``: the description with computed inertials, every other byte unchanged.

Edits are byte splices on the file as read: an existing ``<inertial>`` element's span is
replaced by the new element; a link without one gets it inserted right after its start tag, on a
line of its own with the indentation of the link's first child (or the link's plus one step).
Comments, attribute order, quoting, blank lines and line endings elsewhere stay as they were.
The element text is ASCII, so it splices into UTF-8 (and any ASCII-compatible encoding) as is.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from massprops.errors import RobotModelError
from massprops.io.atomic import OutputKind, atomic_write_bytes
from massprops.robot.formats.xmltree import Node
from massprops.robot.write.elements import WRITERS

if TYPE_CHECKING:
    from massprops.robot.inertials.combine import LinkMass

__all__ = ["description_output", "edited_bytes", "write_description"]


def edited_bytes(data: bytes, fmt: str,
                 edits: Sequence[tuple[Node, Node | None, LinkMass]]) -> bytes:
    """``data`` with each (link node, inertial node or None, LinkMass) edit applied."""
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):
        raise RobotModelError("UTF-16 descriptions cannot be edited in place; convert the file "
                              "to UTF-8")
    newline = "\r\n" if b"\r\n" in data else "\n"
    splices = []
    for link, inertial, props in edits:
        base = _indent_of(data, link.start) or ""
        child = next((c for c in link.children), None)
        inner = _indent_of(data, child.start) if child is not None else None
        if inner is None or not inner.startswith(base) or inner == base:
            inner = base + "  "
        step = inner[len(base):]
        text = WRITERS[fmt](props.mass, props.center_of_mass, props.inertia, indent=step,
                            newline=newline)
        if inertial is not None:
            own = _indent_of(data, inertial.start)
            text = text.replace(newline, newline + (own if own is not None else inner))
            splices.append((inertial.start, inertial.end, text))
        else:
            if link.self_closing:
                raise RobotModelError(f"line {link.line}: <{link.tag}/> has no body to hold an "
                                      "inertial")
            text = newline + inner + text.replace(newline, newline + inner)
            splices.append((link.head_end, link.head_end, text))
    out = bytearray(data)
    for start, end, text in sorted(splices, key=lambda s: s[0], reverse=True):
        out[start:end] = text.encode("ascii")
    return bytes(out)


_WRITES_AS = {".xacro": ".urdf"}
"""A description whose edited file has another extension than its own: xacro's expansion."""


def description_output(source: str | os.PathLike) -> OutputKind:
    """The output rule's `OutputKind` for ``--write`` of the description at ``source``: its own
    format, so its own extension (a .xacro file writes its expansion, a .urdf)."""
    own = Path(os.fspath(source)).suffix.lower()
    return OutputKind("the edited description", (_WRITES_AS.get(own, own),), "write")


def write_description(data: bytes, out: str | os.PathLike, *, source: Path,
                      force: bool = False) -> None:
    """Write ``data`` to ``out`` atomically under the output rule (`description_output`): never
    over ``source`` (the description read), nor over an existing file without ``force``."""
    atomic_write_bytes(Path(out), data, force=force, protect=[source],
                       kind=description_output(source))


def _indent_of(data: bytes, at: int) -> str | None:
    """The whitespace from the start of the line to ``at``, or None if the line has other text
    before it."""
    line_start = data.rfind(b"\n", 0, at) + 1
    head = data[line_start:at]
    return head.decode("ascii") if head.strip() == b"" and head.isascii() else None
