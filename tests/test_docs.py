"""The documents stay true and readable: every command and every option is documented (as
sqlite-utils' docs tests do: a new option that nobody wrote down fails here, not in a user's
hands), the front doors keep their size, and DESIGN.md's module map names files that exist."""

from __future__ import annotations

import re

import pytest
from conftest import ROOT

from massprops.cli import cli

README = ROOT / "README.md"
DESIGN = ROOT / "DESIGN.md"
DOCS = ROOT / "docs"

README_MAX_BYTES = 12 * 1024  # the front door: what it is, the commands, one example each
DESIGN_MAX_BYTES = 20 * 1024  # the map: layers, modules, data flow, conventions

# A path in DESIGN.md's module map: backticked, relative to massprops/, a .py file or a folder.
MAP_PATH = re.compile(r"`([A-Za-z_][\w/]*(?:\.py|/))`")


def _documentation() -> str:
    """README.md and every page under docs/ (decision records included), as one text."""
    pages = [README, *sorted(DOCS.rglob("*.md"))]
    return "\n".join(page.read_text(encoding="utf-8") for page in pages)


@pytest.mark.parametrize("name", sorted(cli.commands))
def test_every_command_and_option_is_documented(name):
    text = _documentation()
    command = cli.commands[name]
    assert f"massprops {name}" in text
    missing = [opt for param in command.params for opt in param.opts
               if opt.startswith("--") and opt not in text and opt != "--help"]
    assert missing == []


@pytest.mark.parametrize("name", sorted(cli.commands))
def test_every_command_and_option_has_help(name):
    command = cli.commands[name]
    assert command.help
    assert all(param.help for param in command.params if hasattr(param, "help")
               and param.param_type_name == "option")


def test_every_command_has_an_example_in_the_readme():
    text = README.read_text(encoding="utf-8")
    missing = [name for name in sorted(cli.commands) if f"$ massprops {name} " not in text]
    assert missing == []


def test_readme_and_design_keep_their_size():
    assert README.stat().st_size <= README_MAX_BYTES
    assert DESIGN.stat().st_size <= DESIGN_MAX_BYTES


def test_ci_runs_exactly_the_readme_commands():
    """CI starts from a clean clone and runs the README's two commands as written, the first
    before the README's examples (.ci/smoke) and the test command last: nothing a user would not
    do, such as copying kernels or setting variables."""
    readme = README.read_text(encoding="utf-8")
    block = readme.split("```sh\n", 1)[1].split("```", 1)[0].splitlines()
    ci = [line for line in (ROOT / ".ci" / "run").read_text(encoding="utf-8").splitlines()
          if line.strip() and not line.startswith(("#", "set ", "cd "))]
    assert ci == [block[0], "bash .ci/smoke", block[1]]


def _anchors(page) -> set[str]:
    """GitHub's anchors of a page's headings: lower case, punctuation dropped, spaces -> '-'."""
    anchors, in_code = set(), False
    for line in page.read_text(encoding="utf-8").splitlines():
        in_code ^= line.startswith("```")
        if not in_code and re.match(r"#+ ", line):
            heading = re.sub(r"^#+ ", "", line).strip().lower()
            anchors.add(re.sub(r"[^\w\- ]", "", heading).replace(" ", "-"))
    return anchors


def test_links_between_documents_resolve():
    pages = [README, DESIGN, *sorted(DOCS.rglob("*.md"))]
    broken = []
    for page in pages:
        for target, anchor in re.findall(r"\]\(([^)#\s]*)(?:#([^)\s]*))?\)",
                                         page.read_text(encoding="utf-8")):
            if "://" in target:
                continue
            path = page.parent / target if target else page
            if not path.exists() or (anchor and path.is_file() and anchor not in _anchors(path)):
                broken.append(f"{page.relative_to(ROOT)} -> {target}#{anchor}")
    assert broken == []


def _module_map_paths() -> list[str]:
    """Backticked paths of DESIGN.md's "Module map" section, less rows still being written."""
    text = DESIGN.read_text(encoding="utf-8")
    section = text.split("## Module map", 1)[1].split("\n## ", 1)[0]
    return [path for line in section.splitlines() if "being written" not in line
            for path in MAP_PATH.findall(line)]


def test_module_map_is_not_empty():
    assert len(_module_map_paths()) > 50


def test_module_map_names_files_that_exist():
    missing = [path for path in _module_map_paths()
               if not (ROOT / "massprops" / path).exists()]
    assert missing == []


def test_every_module_is_in_the_module_map():
    named = set(_module_map_paths())
    modules = [p.relative_to(ROOT / "massprops").as_posix()
               for p in (ROOT / "massprops").rglob("*.py") if p.name != "__init__.py"]
    assert sorted(m for m in modules if m not in named) == []
