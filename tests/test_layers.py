"""The house's layers (DESIGN.md, "Layers"): every massprops module imports only from its own
layer or the ones below, the import graph has no cycle (imports inside functions included: a
deferred import hides a cycle, it does not remove it), only the CLI imports click or rich, and
every import of a massprops module inside a function says why in a comment."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent / "massprops"

LAYERS = (
    ("massprops.errors", "massprops.tolerances", "massprops.rotation", "massprops.inertia",
     "massprops.parallel", "massprops.files"),
    ("massprops.mesh",),
    ("massprops.io", "massprops.repair"),
    ("massprops.inspection", "massprops.cad"),
    ("massprops.robot", "massprops.batch"),
    ("massprops.dynamics", "massprops.sweep", "massprops.torques"),
    ("massprops.cli", "massprops.__main__", "massprops.api", "massprops"),
)
"""Lowest first. ``massprops`` itself (the front door) and the CLI sit on top."""


def _layer(module: str) -> int:
    best, depth = None, -1
    for level, prefixes in enumerate(LAYERS):
        for prefix in prefixes:
            if (module == prefix or module.startswith(prefix + ".")) and prefix.count(".") > depth:
                best, depth = level, prefix.count(".")
    assert best is not None, f"{module} belongs to no layer: add it to LAYERS and DESIGN.md"
    return best


def _modules() -> dict[str, Path]:
    out = {}
    for path in sorted(ROOT.rglob("*.py")):
        parts = path.relative_to(ROOT.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = path
    return out


MODULES = _modules()


class _Imports(ast.NodeVisitor):
    """Each import of the module: (target module, line, inside a function)."""

    def __init__(self, name: str, is_package: bool) -> None:
        self.package = name if is_package else name.rpartition(".")[0]
        self.found: list[tuple[str, int, bool]] = []
        self.depth = 0

    def _function(self, node: ast.AST) -> None:
        self.depth += 1
        self.generic_visit(node)
        self.depth -= 1

    visit_FunctionDef = visit_AsyncFunctionDef = visit_Lambda = _function

    def visit_Import(self, node: ast.Import) -> None:
        for alias in node.names:
            self.found.append((alias.name, node.lineno, self.depth > 0))

    def visit_ImportFrom(self, node: ast.ImportFrom) -> None:
        base = node.module or ""
        if node.level:
            parts = self.package.split(".")
            base = ".".join(parts[: len(parts) - node.level + 1] + ([base] if base else []))
        for alias in node.names:  # `from pkg import submodule` imports the submodule
            sub = f"{base}.{alias.name}"
            self.found.append((sub if sub in MODULES else base, node.lineno, self.depth > 0))


def _imports(name: str) -> list[tuple[str, int, bool]]:
    path = MODULES[name]
    visitor = _Imports(name, path.name == "__init__.py")
    visitor.visit(ast.parse(path.read_text(encoding="utf-8")))
    return visitor.found


GRAPH = {name: _imports(name) for name in MODULES}


def _resolve(target: str) -> str | None:
    """The massprops module an import loads (a name inside a module: that module)."""
    while target and target not in MODULES:
        target = target.rpartition(".")[0]
    return target or None


@pytest.mark.parametrize("name", sorted(MODULES))
def test_imports_go_down(name):
    mine = _layer(name)
    for target, line, _ in GRAPH[name]:
        if not target.startswith("massprops"):
            continue
        module = _resolve(target)
        if module is None or name.startswith(module + ".") or module == name:
            continue  # a package's own __init__ is loaded first anyway
        assert _layer(module) <= mine, (
            f"{MODULES[name]}:{line}: {name} (layer {mine}) imports {module} "
            f"(layer {_layer(module)}): a lower layer may not depend on a higher one")


def test_no_import_cycles():
    edges = {name: set() for name in MODULES}
    for name, found in GRAPH.items():
        for target, _, _ in found:
            module = _resolve(target) if target.startswith("massprops") else None
            if module and module != name and not name.startswith(module + "."):
                edges[name].add(module)
    index, low, stack, on_stack, cycles = {}, {}, [], set(), []
    counter = iter(range(10**9))

    def connect(v):  # Tarjan's strongly connected components
        index[v] = low[v] = next(counter)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(edges[v]):
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            group = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                group.append(w)
                if w == v:
                    break
            if len(group) > 1:
                cycles.append(sorted(group))

    for v in sorted(edges):
        if v not in index:
            connect(v)
    assert not cycles, f"import cycles: {cycles}"


@pytest.mark.parametrize("name", sorted(MODULES))
def test_only_the_cli_renders(name):
    if _layer(name) == len(LAYERS) - 1:
        return
    for target, line, _ in GRAPH[name]:
        top = target.partition(".")[0]
        assert top not in ("click", "rich"), (
            f"{MODULES[name]}:{line}: {top} is imported outside the CLI; the library returns "
            f"values and raises, the CLI renders")


@pytest.mark.parametrize("name", sorted(MODULES))
def test_deferred_imports_say_why(name):
    lines = MODULES[name].read_text(encoding="utf-8").splitlines()
    for target, line, deferred in GRAPH[name]:
        if not (deferred and target.startswith("massprops")):
            continue
        above = line - 2  # one comment may head a block of imports, above it or on its first
        said = "#" in lines[line - 1]
        while above >= 0 and _part_of_imports(lines[above]) and not said:
            said = "#" in lines[above]
            above -= 1
        said = said or (above >= 0 and lines[above].strip().startswith("#"))
        assert said, (
            f"{MODULES[name]}:{line}: an import of {target} inside a function needs a short "
            f"comment on or above it saying why it is deferred")


def _part_of_imports(line: str) -> bool:
    text = line.strip()
    return (not text or text.startswith(("from ", "import ")) or text == ")"
            or (text.endswith(",") and text.replace(",", "").replace(" as ", "").isidentifier()))


@pytest.mark.parametrize("name", sorted(MODULES))
def test_numba_only_where_kernels_are_made(name):
    """numba's decorators and cache live in dynamics.compiled; a kernel module takes them from
    there (a bare ``njit(cache=True)`` would cache outside massprops' folder)."""
    if name.startswith("massprops.dynamics.compiled"):
        return
    for target, line, _ in GRAPH[name]:
        assert target.partition(".")[0] != "numba", (
            f"{MODULES[name]}:{line}: numba imported outside massprops.dynamics.compiled; take "
            f"the decorators from massprops.dynamics.compiled.jit")
