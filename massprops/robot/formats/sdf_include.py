"""SDFormat ``<include>``: another model's file spliced in where it is included.

``<include><uri>model://NAME</uri> [<name>] [<pose>]</include>`` (sdformat.org, 1.4-1.11): the
URI is resolved as `uris.resolve_uri` says (``model://`` in ``--package-path``,
``GZ_SIM_RESOURCE_PATH``, ``SDF_PATH``, ...; a plain path relative to the including file). A
folder is a model folder: its ``model.config`` names the SDF file (``<sdf>`` elements; the one
with the highest ``version`` wins), else ``model.sdf``. The included file's first ``<model>``
takes the include's place, renamed by ``<name>``; ``merge="true"`` (SDF 1.9) puts its children
into the enclosing model instead. The pose does not matter here: inertials are in link frames.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import cast

from massprops.errors import RobotModelError, setting_ref
from massprops.robot.formats.uris import resolve_uri
from massprops.robot.formats.xmltree import Node, parse_xml

__all__ = ["expand_sdf_includes"]

_MAX_DEPTH = 32  # deeper than any real model: a guard against include loops


def expand_sdf_includes(root: Node, path: Path, package_paths: Sequence[Path],
                        _depth: int = 0) -> None:
    """Splice every ``<include>`` under ``root`` in place (recursively)."""
    for node in list(root.iter("include")):
        parent = node.parent
        if parent is None:
            continue
        where = node.file or path
        uri_el = node.find("uri")
        uri = "" if uri_el is None else uri_el.text.strip()
        if not uri:
            raise RobotModelError(f"{where}:{node.line}: <include> needs a <uri>")
        if _depth > _MAX_DEPTH:
            raise RobotModelError(f"{where}:{node.line}: <include> {uri!r} nests more than "
                                  f"{_MAX_DEPTH} deep (an include loop?)")
        target, problem = resolve_uri(uri, where.parent, where, package_paths)
        if problem:
            raise RobotModelError(f"{where}:{node.line}: <include>: {problem}")
        file = _model_file(cast(Path, target), where, node, uri)  # no problem: a path
        sub, _ = parse_xml(file)
        expand_sdf_includes(sub, file, package_paths, _depth + 1)
        model = next(sub.iter("model"), None)
        if model is None:
            raise RobotModelError(f"{file}: no <model> to include (from {where}:{node.line})")
        name_el = node.find("name")
        if name_el is not None and name_el.text.strip():
            model.attrs = {**model.attrs, "name": name_el.text.strip()}
        merge = node.attrs.get("merge", "false").strip().lower() in ("true", "1")
        new = [c for c in model.children if c.tag != "pose"] if merge else [model]
        at = parent.children.index(node)
        for child in new:
            child.parent = parent
        parent.children[at:at + 1] = new


def _model_file(target: Path, where: Path, node: Node, uri: str) -> Path:
    if target.exists() and not target.is_dir():  # a file (parse_xml refuses a special one)
        return target
    if not target.is_dir():
        raise RobotModelError(f"{where}:{node.line}: <include> {uri!r}: {target} does not "
                              f"exist; fix the URI or give {setting_ref('package_path')}")
    config = target / "model.config"
    if config.is_file():
        croot, _ = parse_xml(config)
        entries = [(c.attrs.get("version", "0"), c.text.strip()) for c in croot.iter("sdf")
                   if c.text.strip()]
        if entries:
            best = max(entries, key=lambda e: tuple(int(x) for x in e[0].split(".")
                                                    if x.isdigit()))
            return target / best[1]
    if (target / "model.sdf").is_file():
        return target / "model.sdf"
    raise RobotModelError(f"{where}:{node.line}: <include> {uri!r}: {target} has no "
                          "model.config naming its SDF file and no model.sdf")
