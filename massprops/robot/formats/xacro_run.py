"""xacro: a ``.xacro`` description expanded by the ``xacro`` package (pure Python, on PyPI).

``expand_xacro(path, args)`` runs xacro on the file with ``args`` (``name:=value`` mappings, as
``xacro file name:=value`` takes them) and returns the expanded URDF's bytes. ``$(find PKG)``
resolves as ``package://PKG`` does (`uris`): an ancestor folder named PKG, ``--package-path``,
``ROS_PACKAGE_PATH``, so no ROS installation is needed. Line numbers of later errors refer to
the expanded text, which is why the parsed nodes carry the name ``FILE (expanded by xacro)``.
"""

from __future__ import annotations

import contextlib
import io
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

from massprops.errors import MassPropsError, RobotModelError, chain, setting_ref

__all__ = ["EXPANDED", "expand_xacro", "has_xacro", "is_xacro", "parse_xacro_arg"]

EXPANDED = " (expanded by xacro)"
"""Appended to the file name in messages about the expanded text (its line numbers)."""


def is_xacro(path: Path) -> bool:
    return path.suffix.lower() == ".xacro"


def has_xacro(root) -> bool:
    """Whether a parsed description (`xmltree.Node`) still holds xacro elements or ``${...}`` /
    ``$(...)`` expressions."""
    return any(node.tag.startswith("xacro:") or any("${" in a or "$(" in a
                                                    for a in node.attrs.values())
               for node in root.iter())


def expand_xacro(path: Path, args: Mapping[str, str] | None = None,
                 package_paths: Sequence[Path] = (), notes: list | None = None) -> bytes:
    """The URDF that xacro makes of ``path`` with ``args``, as UTF-8 bytes.

    xacro prints its warnings to stderr (a library never prints): they are captured and each
    one goes to ``notes`` as ``xacro: ...`` (its "when processing file" trail dropped).
    Raises MassPropsError (exit 1) with the install hint when xacro is missing, RobotModelError
    naming the file when xacro refuses it.
    """
    try:
        import xacro  # optional at import time: only .xacro inputs need it
        import xacro.substitution_args as substitution
    except ImportError as exc:
        raise MassPropsError(f"{path}: reading .xacro needs the xacro package: pip install "
                             "xacro") from exc
    printed = io.StringIO()
    with _find_packages(substitution, path, package_paths), \
            contextlib.redirect_stderr(printed), contextlib.redirect_stdout(printed):
        try:
            doc = xacro.process_file(str(path), mappings=dict(args or {}))
        except Exception as exc:  # xacro raises XacroException, its own and the XML parser's
            ours = _ours(exc)
            if ours is not None:  # our $(find) refused: its own line, its settings kept
                raise ours from exc
            text = " ".join(str(exc).split()) or type(exc).__name__
            raise RobotModelError(f"{path}: xacro failed: {text}; {_what_to_do(text, path)}"
                                  ) from exc
    if notes is not None:
        for line in _ANSI.sub("", printed.getvalue()).splitlines():
            line = line.strip()
            if line and not line.startswith(("when processing file", "in file:",
                                             "when instantiating", "instantiated from")):
                notes.append(f"xacro: {line.removeprefix('warning: ')}")
    return doc.toprettyxml(indent="  ", encoding="utf-8")


_ANSI = re.compile(r"\x1b\[[0-9;]*m")  # xacro colours its warnings
_NO_ARG = re.compile(r"Undefined substitution argument (\S+)")  # $(arg NAME) without a value
_NO_NAME = re.compile(r"name '(\w+)' is not defined")  # ${NAME}: Python's NameError, said
_PACKAGE_INCLUDE = re.compile(r"No such file or directory: \S*?package://([^/\s]+)/(\S+?)'?(?:\s|$)")


def _ours(exc: BaseException) -> MassPropsError | None:
    """The MassPropsError xacro wrapped while running our ``$(find)`` (its XacroException
    keeps it as ``exc`` and as the context), if any."""
    return next((e for e in chain(exc, "exc") if isinstance(e, MassPropsError)), None)


def _what_to_do(text: str, path: Path) -> str:
    """The fix for xacro's message ``text``: an argument ``$(arg NAME)`` takes its value from
    the caller (`xacro_arg`); a ``${name}`` is a property, which only the file (or one it
    includes) can define."""
    arg = _NO_ARG.search(text)
    if arg:
        return f"give its value with {setting_ref('xacro_arg')} {arg[1]}:=VALUE"
    uri = _PACKAGE_INCLUDE.search(text)
    if uri:  # xacro joins the URI to the folder as a relative path
        return (f"xacro:include takes a path, not a URI: write $(find {uri[1]})/{uri[2]} for "
                f"package://{uri[1]}/{uri[2]}")
    name = _NO_NAME.search(text)
    if name:
        return (f"the property {name[1]!r} is not defined in {path.name} nor in the files it "
                f"includes: define it there (<xacro:property name=\"{name[1]}\" value=\"...\"/>)"
                " or fix the expression")
    return "fix the file"


def parse_xacro_arg(text: str) -> tuple[str, str]:
    """(NAME, VALUE) of one ``NAME:=VALUE`` argument, as ``xacro FILE NAME:=VALUE`` takes it;
    ValueError saying what was expected."""
    name, sep, value = text.partition(":=")
    if not sep or not name.strip():
        raise ValueError(f"expected NAME:=VALUE, got {text!r}")
    return name.strip(), value


@contextlib.contextmanager
def _find_packages(module, path: Path, package_paths: Sequence[Path]):
    """``$(find PKG)`` through massprops' package search while xacro runs (restored after)."""
    from massprops.robot.formats.uris import resolve_uri  # the only user of the search here

    def find(package: str) -> str:
        folder, problem = resolve_uri(f"package://{package}/", path.parent, path, package_paths)
        if problem:
            raise RobotModelError(f"{path}: $(find {package}): {problem}")
        return str(folder).rstrip("/")

    saved, saved_eval = module._eval_find, module._eval_dict.get("find")
    module._eval_find = module._eval_dict["find"] = find
    try:
        yield
    finally:
        module._eval_find = saved
        module._eval_dict["find"] = saved_eval
