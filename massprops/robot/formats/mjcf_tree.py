"""MJCF's file-level structure: ``<include>`` expanded in place, ``<replicate>``'s copies.

``<include file="...">`` (MuJoCo XML reference, "include"): the included file's top element is
dropped and its children take the include's place, at any depth, recursively; the result is one
model (its ``<default>``, ``<asset>`` and ``<compiler>`` count as if written there). A relative
``file`` is looked up first in the folder of the *main* model file (MuJoCo's documented rule),
then in the folder of the file that holds the ``<include>`` (MuJoCo 3+ accepts that too; checked
against mujoco 4.0: where both exist, the main file's folder wins). An absolute path is used as
it is. A file included twice along one chain is a loop and refused.

``<replicate count offset [euler]>``: ``count`` copies of its children, copy i (0-based) placed
by T^i where T is the translation ``offset`` after the rotation ``euler`` (compiler angle and
eulerseq), i.e. each copy is the previous one moved by T; every name inside gets the suffix
``sep`` + i written with as many digits as ``count - 1`` has (r00 ... r10 for 11 copies).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from massprops.errors import RobotModelError
from massprops.robot.formats.xmltree import Node, parse_xml

__all__ = ["expand_includes", "replicate_frames", "replicate_suffix"]

_MAX_DEPTH = 32  # include chains deeper than any real model: a guard against runaway recursion


def expand_includes(root: Node, main: Path, _chain: tuple[Path, ...] = ()) -> Node:
    """Splice every ``<include>`` under ``root`` (in place); returns ``root``.

    main : the main model file (relative include paths start at its folder).
    Raises RobotModelError naming the include's file and line for a missing file or a loop.
    """
    chain = _chain or ((root.file or main).resolve(),)
    for node in list(root.iter("include")):
        parent = node.parent
        if parent is None:
            continue
        where = node.file or main
        file = node.attrs.get("file", "")
        if not file:
            raise RobotModelError(f"{where}:{node.line}: <include> needs file=\"...\"")
        target = _locate(file, main, where)
        if target is None:
            raise RobotModelError(f"{where}:{node.line}: <include file={file!r}>: "
                                  f"{_not_found(file, main, where)}; fix the path")
        resolved = target.resolve()
        if resolved in chain or len(chain) > _MAX_DEPTH:
            raise RobotModelError(f"{where}:{node.line}: <include file={file!r}> includes "
                                  "itself (an include loop); remove one of them")
        sub, _ = parse_xml(target)
        expand_includes(sub, main, chain + (resolved,))
        at = parent.children.index(node)
        for child in sub.children:
            child.parent = parent
        parent.children[at:at + 1] = sub.children
    return root


def _not_found(file: str, main: Path, including: Path) -> str:
    """Where a missing include was looked for: the folders, absolute, each once."""
    if Path(file).is_absolute():
        return "no such file"
    first, second = (os.path.abspath(p.parent) for p in (main, including))
    if first == second:
        return f"no such file in {first} (the main model's folder)"
    return (f"no such file in {first} (the main model's folder) nor in {second} (the "
            "including file's folder)")


def _locate(file: str, main: Path, including: Path) -> Path | None:
    """Where ``file`` is: absolute, or in the main model's folder, else the including file's;
    None if nowhere (something there that is not a regular file: parse_xml refuses it)."""
    p = Path(file)
    if p.is_absolute():
        return p if p.exists() else None
    for folder in (main.parent, including.parent):
        if (folder / p).exists():
            return folder / p
    return None


def replicate_frames(count: int, rotation: np.ndarray, offset: np.ndarray):
    """The poses (A_i, t_i) of the ``count`` copies: T^0 = identity, T^i = T T^(i-1)."""
    a, t = np.eye(3), np.zeros(3)
    for _ in range(count):
        yield a, t
        a, t = rotation @ a, rotation @ t + offset


def replicate_suffix(count: int, index: int, sep: str) -> str:
    """The name suffix of copy ``index``: ``sep`` and the index zero-padded to the width of
    ``count - 1``."""
    return f"{sep}{index:0{len(str(max(count - 1, 0)))}d}"
