"""No error message names an option the command does not have: every string of the library that
a command can reach (its CLI module and every massprops module it imports, at any depth,
function-level imports included; not docstrings, option declarations or help texts) goes
through the CLI's message boundary (`fit_message`, as `say_error`/`say_warning` apply it for
that command), and what comes out may name only options of that command or of the top-level
group, unless listed below with the reason the string cannot reach that command's user."""

from __future__ import annotations

import ast
import re
from pathlib import Path

import click
import pytest

from massprops.cli import cli
from massprops.cli.common import SCENE_COMMANDS, flag
from massprops.cli.messages import fit_message

PACKAGE = Path(__file__).resolve().parent.parent / "massprops"
OPTION = re.compile(r"(?<![\w-])--([a-z][a-z0-9-]*)")

UNREACHABLE = {
    # (module, option): why a command that imports the module never shows that string
    ("massprops.io.dispatch", "input-format"): "only for a stream ('-'), which only inspect and "
                                               "align read",
    ("massprops.io.atomic", "force"): "only when writing a file; inspect writes none",
    ("massprops.cli.common", "density"): "check_mass_options, called by inspect and align only",
    ("massprops.cli.common", "mass"): "check_mass_options, called by inspect and align only",
    ("massprops.robot.write.elements", "principal"): "inspect --format mjcf --principal only",
    ("massprops.robot.write.elements", "format"): "inspect --format mjcf --principal only",
    ("massprops.dynamics.compiled.build", "only"): "the build script's own usage line",
}
"""Other commands' options that a shared module names in a branch this command never takes."""


def _module_file(name: str) -> Path | None:
    rel = Path(*name.split(".")[1:])
    if not rel.parts:
        return PACKAGE / "__init__.py"
    for p in (PACKAGE / rel.with_suffix(".py"), PACKAGE / rel / "__init__.py"):
        if p.is_file():
            return p
    return None


def _imports(name: str, tree: ast.AST) -> set[str]:
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.update(a.name for a in node.names if a.name.startswith("massprops"))
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0 and \
                node.module.startswith("massprops"):
            out.add(node.module)
            out.update(f"{node.module}.{a.name}" for a in node.names)
    return {m for m in out if _module_file(m) is not None}


def _strings(tree: ast.AST) -> list[str]:
    """Every string constant that is not a docstring, a help text or an option's name."""
    docs = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            body = node.body
            if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
                docs.add(id(body[0].value))
        # a bare string statement documents the assignment above it (this project's style)
        if isinstance(node, ast.Expr) and isinstance(node.value, ast.Constant):
            docs.add(id(node.value))
        if isinstance(node, ast.keyword) and node.arg == "help":
            docs.update(id(n) for n in ast.walk(node.value))
    refs = [flag(n.args[0].value) for n in ast.walk(tree)  # errors.setting_ref("name")
            if isinstance(n, ast.Call) and getattr(n.func, "id", None) == "setting_ref"
            and n.args and isinstance(n.args[0], ast.Constant)]
    return refs + [n.value for n in ast.walk(tree) if isinstance(n, ast.Constant)
                   and isinstance(n.value, str) and id(n) not in docs
                   and not re.fullmatch(r"--[a-z0-9-]+", n.value)]


def _reach(start: str) -> dict[str, ast.AST]:
    seen: dict[str, ast.AST] = {}
    todo = [start]
    while todo:
        name = todo.pop()
        if name in seen:
            continue
        tree = ast.parse(_module_file(name).read_text())
        seen[name] = tree
        # a command module's import of massprops.cli.app is the group, not other commands
        todo.extend(m for m in _imports(name, tree)
                    if not (m.startswith("massprops.cli.") and m not in (
                        "massprops.cli.common",) and m != start))
    return seen


def _options(command: click.Command) -> set[str]:
    names = set()
    for param in [*command.params, *cli.params]:
        for opt in getattr(param, "opts", []) + getattr(param, "secondary_opts", []):
            if opt.startswith("--"):
                names.add(opt[2:])
    return names


@pytest.mark.slow
def test_every_option_named_in_a_message_exists_on_the_command():
    bad = []
    for name, command in cli.commands.items():
        options = _options(command)
        for module, tree in _reach(command.callback.__module__).items():
            for text in _strings(tree):
                shown = fit_message(text, options, scene=name in SCENE_COMMANDS)
                for opt in OPTION.findall(shown):
                    if opt not in options and (module, opt) not in UNREACHABLE:
                        bad.append(f"{name}: {module}: --{opt} in {shown[:70]!r}")
    assert not bad, "\n".join(sorted(set(bad)))


def test_fit_message_drops_or_translates_missing_options():
    assert fit_message("rescale the mesh (--unit)", {"json"}) == "rescale the mesh"
    assert fit_message("raise time.step (or --step)", {"json"}) == "raise time.step"
    assert fit_message("use --fill-holes to cap them", {"json"}, scene=True) == \
        "use the body key fill_holes: true to cap them"
    assert fit_message("use --fill-holes to cap them", {"fill-holes"}) == \
        "use --fill-holes to cap them"
