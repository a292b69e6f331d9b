"""A small XML tree that remembers where each element stands in the file's bytes.

Built on the standard library's expat (no lxml): every `Node` keeps its line and column for
error messages and the byte span of the whole element for in-place write-back, so a writer can
replace one element's bytes and leave every other byte of the file as it was.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from xml.parsers import expat

from massprops.errors import RobotModelError
from massprops.files import read_input

__all__ = ["Node", "parse_xml", "parse_xml_bytes"]


@dataclass(eq=False)
class Node:
    """One element.

    tag : the qualified name as written (``drake:capsule`` keeps its prefix).
    attrs : attribute name -> value, as written (entities resolved).
    line, column : 1-based line, 0-based column of the ``<`` of its start tag.
    start : byte offset of that ``<``. head_end : byte offset just after the start tag's ``>``.
    end : byte offset just after the element (after ``</tag>``, or ``head_end`` for ``<tag/>``).
    text : the character data directly inside it, concatenated (children's text excluded).
    children : child elements in document order. parent : None for the root.
    file : the file it was read from (an MJCF ``<include>`` splices in another file's nodes;
        their lines and byte spans are that file's).
    """

    tag: str
    attrs: dict[str, str]
    line: int
    column: int
    start: int
    head_end: int = -1
    end: int = -1
    text: str = ""
    children: list[Node] = field(default_factory=list)
    parent: Node | None = None
    file: Path | None = None

    @property
    def self_closing(self) -> bool:
        return self.end == self.head_end

    def find(self, tag: str) -> Node | None:
        """The first child called ``tag``, or None."""
        return next((c for c in self.children if c.tag == tag), None)

    def findall(self, tag: str) -> list[Node]:
        return [c for c in self.children if c.tag == tag]

    def iter(self, tag: str | None = None):
        """This node and every descendant (depth first, document order), optionally by tag."""
        stack = [self]
        while stack:
            node = stack.pop()
            if tag is None or node.tag == tag:
                yield node
            stack.extend(reversed(node.children))


def parse_xml(path: str | os.PathLike) -> tuple[Node, bytes]:
    """Parse the XML file at ``path``: (root Node, the file's bytes).

    Raises MeshFileError if it cannot be read, RobotModelError (naming the file, line and
    column) if it is not well-formed XML.
    """
    p = Path(path)
    data = read_input(p, what="a robot description file")
    return _Builder(data, str(p)).run(), data


def parse_xml_bytes(data: bytes, name: str) -> Node:
    """Parse XML held in memory (e.g. xacro's output); messages and ``Node.file`` say ``name``."""
    return _Builder(data, name).run()


class _Builder:
    def __init__(self, data: bytes, name: str) -> None:
        self.data, self.name, self.path = data, name, Path(name)
        self.stack: list[Node] = []
        self.root: Node | None = None
        self.parser = expat.ParserCreate()
        self.parser.buffer_text = True
        self.parser.ordered_attributes = False
        self.parser.StartElementHandler = self._start
        self.parser.EndElementHandler = self._end
        self.parser.CharacterDataHandler = self._text

    def run(self) -> Node:
        self.data = _declaration_first(self.data)
        try:
            self.parser.Parse(self.data, True)
        except expat.ExpatError as exc:
            if self.root is not None and self.root.end >= 0:
                # bytes after the root element closed (stray text some exporters append):
                # the description itself is complete, as ROS's and pybullet's readers accept
                return self.root
            raise RobotModelError(
                f"{self.name}:{exc.lineno}: malformed XML at column {exc.offset}: "
                f"{expat.ErrorString(exc.code)}; fix the file (an XML validator shows the "
                "spot)") from exc
        if self.root is None:
            raise RobotModelError(f"{self.name}: no XML element found; expected a robot "
                                  "description")
        return self.root

    def _start(self, tag: str, attrs: dict[str, str]) -> None:
        p = self.parser
        start = p.CurrentByteIndex
        node = Node(tag, dict(attrs), p.CurrentLineNumber, p.CurrentColumnNumber, start,
                    file=self.path)
        node.head_end = _tag_end(self.data, start)
        if self.stack:
            node.parent = self.stack[-1]
            self.stack[-1].children.append(node)
        else:
            self.root = node
        self.stack.append(node)

    def _end(self, tag: str) -> None:
        node = self.stack.pop()
        at = self.parser.CurrentByteIndex
        # an empty-element tag <x/> is its own end (expat then reports the offset after it)
        empty = self.data[node.head_end - 2:node.head_end] == b"/>"
        node.end = node.head_end if empty else _tag_end(self.data, at)

    def _text(self, text: str) -> None:
        if self.stack:
            self.stack[-1].text += text


def _declaration_first(data: bytes) -> bytes:
    """The XML declaration moved over the blank lines some files put before it: expat refuses
    a declaration that is not the first thing in the file. It is blanked out (replaced by
    spaces, so every byte offset and line number stays) when only whitespace precedes it."""
    stripped = data.lstrip()
    if stripped is data or not stripped.startswith(b"<?xml"):
        return data
    end = stripped.find(b"?>")
    if end < 0:
        return data
    start = len(data) - len(stripped)
    return data[:start] + b" " * (end + 2) + data[start + end + 2:]


def _tag_end(data: bytes, at: int) -> int:
    """Offset just after the ``>`` closing the tag that starts at ``at`` (quotes skipped)."""
    quote = 0
    i = at
    n = len(data)
    while i < n:
        c = data[i]
        if quote:
            if c == quote:
                quote = 0
        elif c in (0x22, 0x27):  # " or '
            quote = c
        elif c == 0x3E:  # >
            return i + 1
        i += 1
    return n
