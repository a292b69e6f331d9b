"""Reading numbers out of XML attributes and text, with one-line errors that name the spot."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import overload

import numpy as np

from massprops.errors import RobotModelError
from massprops.robot.formats.xmltree import Node

__all__ = ["Values"]


class Values:
    """Number readers for one file; every error names ``path:line: <tag attr>``."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def error(self, node: Node, problem: str) -> RobotModelError:
        where = node.file if node.file is not None else self.path
        return RobotModelError(f"{where}:{node.line}: <{node.tag}>: {problem}")

    def numbers(self, node: Node, text: str, what: str, count: int | tuple[int, ...],
                example: str) -> np.ndarray:
        """The whitespace-separated numbers in ``text`` (finite), as many as ``count`` allows."""
        counts = (count,) if isinstance(count, int) else count
        try:
            values = [float(t) for t in text.split()]
        except ValueError:
            values = None
        if values is None or len(values) not in counts or not all(map(math.isfinite, values)):
            want = " or ".join(str(c) for c in counts)
            raise self.error(node, f"{what}: expected {want} finite number(s), got {text!r}; "
                                   f"write e.g. {example}")
        return np.array(values, dtype=np.float64)

    # with a default the readers never return None: the overloads let mypy see that
    @overload
    def attr(self, node: Node, name: str, count: int | tuple[int, ...], default: None = None,
             example: str | None = None) -> np.ndarray | None: ...

    @overload
    def attr(self, node: Node, name: str, count: int | tuple[int, ...],
             default: Sequence[float], example: str | None = None) -> np.ndarray: ...

    def attr(self, node: Node, name: str, count: int | tuple[int, ...], default=None,
             example: str | None = None) -> np.ndarray | None:
        """Attribute ``name`` as numbers; ``default`` (returned as an array) when absent."""
        if name not in node.attrs:
            return None if default is None else np.array(default, dtype=np.float64)
        n = count if isinstance(count, int) else count[0]
        return self.numbers(node, node.attrs[name], f"{name}=", count,
                            example or f'{name}="{" ".join(["0"] * n)}"')

    @overload
    def number(self, node: Node, name: str, default: None = None) -> float | None: ...

    @overload
    def number(self, node: Node, name: str, default: float) -> float: ...

    def number(self, node: Node, name: str, default: float | None = None) -> float | None:
        v = self.attr(node, name, 1, None if default is None else [default],
                      example=f'{name}="1.0"')
        return None if v is None else float(v[0])

    def text(self, node: Node, count: int | tuple[int, ...], example: str) -> np.ndarray:
        """The numbers in the element's text (SDF style: ``<size>1 2 3</size>``)."""
        return self.numbers(node, node.text, "its text", count, example)

    @overload
    def child_text(self, node: Node, tag: str, count: int | tuple[int, ...],
                   default: None = None, example: str = "") -> np.ndarray | None: ...

    @overload
    def child_text(self, node: Node, tag: str, count: int | tuple[int, ...],
                   default: Sequence[float], example: str = "") -> np.ndarray: ...

    def child_text(self, node: Node, tag: str, count: int | tuple[int, ...], default=None,
                   example: str = "") -> np.ndarray | None:
        child = node.find(tag)
        if child is None:
            return None if default is None else np.array(default, dtype=np.float64)
        return self.text(child, count, example or f"<{tag}>1</{tag}>")

    def positive(self, node: Node, what: str, value: float, allow_zero: bool = False) -> float:
        ok = value >= 0 if allow_zero else value > 0
        if not ok:
            raise self.error(node, f"{what} must be {'>= 0' if allow_zero else 'positive'}, "
                                   f"got {value!r}")
        return value
