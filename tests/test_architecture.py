"""The layers of docs/architecture.md hold: no import circle, no import that runs upward.

The imports of every module under ``hybrid/`` are read with ``ast`` (inside
functions too; the ones under ``if TYPE_CHECKING:`` count for the layers but
not for circles, since they never run). A module may import from its own
package and from lower layers only; packages on one layer are independent of
each other.
"""

from __future__ import annotations

import ast
import functools
import warnings
from pathlib import Path

import networkx as nx
import pytest
from support import REPO

PACKAGE = REPO / "hybrid"

LAYERS: tuple[frozenset[str], ...] = (
    frozenset({"errors", "version", "lazy", "allocation", "progress", "held", "frames",
               "interrupted"}),
    frozenset({"expr", "files", "keywords"}),
    frozenset({"model"}),
    frozenset({"binding"}),
    frozenset({"compose"}),
    frozenset({"modes", "reader"}),
    frozenset({"simulation", "analysis"}),
    frozenset({"reach"}),
    frozenset({"campaigns", "interchange", "export"}),
    frozenset({"cli"}),
    frozenset({"__init__", "__main__"}),
)
"""Units of ``hybrid/`` (top-level modules and packages), lowest layer first."""

SOFT_MAX_LINES = 800
"""Modules are cut by topic, not by size; one above this is worth a look (a warning)."""
MAX_LINES = 1500
"""Above this a module is more than one topic, whatever it says (a failure)."""


def _module_name(path: Path, root: Path = REPO) -> str:
    parts = path.relative_to(root).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _unit(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "__init__"


def _rank(unit: str) -> int:
    for rank, units in enumerate(LAYERS):
        if unit in units:
            return rank
    raise AssertionError(f"hybrid/{unit} is in no layer: add it to LAYERS and docs/architecture.md")


def _is_type_checking(node: ast.If) -> bool:
    test = node.test
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


@functools.cache
def _tree(path: Path) -> ast.Module:
    """The syntax tree of ``path``, parsed once per process (three rules read every module)."""
    return ast.parse(path.read_text(encoding="utf-8"))


_BLOCKS = (ast.stmt, ast.excepthandler, ast.match_case)
"""The nodes an import statement can be inside: statements and their blocks, no expression."""


def _imports(path: Path, package: Path = PACKAGE) -> list[tuple[str, bool]]:
    """``(imported hybrid module, runs at import or call time)`` for every import in ``path``."""
    tree = _tree(path)
    found: list[tuple[str, bool]] = []

    def visit(node: ast.AST, runtime: bool) -> None:
        if isinstance(node, ast.If) and _is_type_checking(node):
            for child in node.body:
                visit(child, False)
            for child in node.orelse:
                visit(child, runtime)
            return
        if isinstance(node, ast.Import):
            found.extend((a.name, runtime) for a in node.names if a.name.startswith("hybrid"))
        elif (
            isinstance(node, ast.ImportFrom)
            and node.level == 0
            and (node.module or "").startswith("hybrid")
        ):
            module = node.module or ""
            for alias in node.names:
                candidate = f"{module}.{alias.name}"
                where = package.parent / Path(*candidate.split("."))
                is_module = where.with_suffix(".py").exists() or (where / "__init__.py").exists()
                found.append((candidate if is_module else module, runtime))
        for child in ast.iter_child_nodes(node):
            if isinstance(child, _BLOCKS):
                visit(child, runtime)

    visit(tree, True)
    return found


def _spliced(path: Path) -> list[str]:
    """Modules whose text ``path`` copies into generated code (its textual dependencies).

    The generated kernel and model modules are made of the code below the
    ``# --- kernel ---`` line of other modules (``kernel_text.kernel_source``): a
    tuple of their names given to ``kernel_source(...)``, or ``KERNEL_MODULES``.
    """
    tree = _tree(path)
    names: list[str] = []
    for node in ast.walk(tree):
        value: ast.AST | None = None
        if isinstance(node, ast.Call) and getattr(node.func, "id", "") == "kernel_source":
            value = node.args[0] if node.args else None
        elif isinstance(node, ast.Assign) and any(
            getattr(t, "id", "") == "KERNEL_MODULES" for t in node.targets
        ):
            value = node.value
        if isinstance(value, ast.Tuple):
            names += [e.value for e in value.elts if isinstance(e, ast.Constant)]
    package = _module_name(path.parent / "__init__.py", PACKAGE.parent)
    return [f"{package}.{name}" for name in names]


@functools.cache
def _graph(package: Path = PACKAGE) -> tuple[nx.DiGraph, list[tuple[str, str, bool]]]:
    """The import graph of ``package`` and its edges (made once per process: read, not changed)."""
    graph = nx.DiGraph()
    edges: list[tuple[str, str, bool]] = []
    for path in sorted(package.rglob("*.py")):
        source = _module_name(path, package.parent)
        graph.add_node(source)
        textual = [(m, True) for m in _spliced(path)] if package == PACKAGE else []
        for target, runtime in _imports(path, package) + textual:
            edges.append((source, target, runtime))
            if runtime and target != source:
                graph.add_edge(source, target)
    return graph, edges


def _circles(package: Path) -> list[list[str]]:
    return list(nx.simple_cycles(_graph(package)[0]))


def _upward(package: Path) -> list[str]:
    found = []
    for source, target, _ in _graph(package)[1]:
        a, b = _unit(source), _unit(target)
        if a != b and _rank(b) >= _rank(a):
            found.append(f"{source} -> {target}")
    return found


def test_no_import_circle() -> None:
    circles = _circles(PACKAGE)
    assert not circles, f"import circles: {circles[:5]}"


def test_no_upward_import() -> None:
    upward = _upward(PACKAGE)
    assert not upward, "imports that run upward or sideways:\n" + "\n".join(upward)


def test_the_walker_sees_imports_in_functions_and_type_checking_blocks() -> None:
    main = _imports(PACKAGE / "cli" / "main.py")
    assert ("hybrid.cli.check", True) in main  # imported inside main()
    init = _imports(PACKAGE / "analysis" / "__init__.py")
    assert ("hybrid.analysis.api", False) in init  # under TYPE_CHECKING: never runs


def test_the_rules_catch_a_circle_and_an_upward_import(tmp_path: Path) -> None:
    fake = tmp_path / "hybrid"
    (fake / "simulation").mkdir(parents=True)
    (fake / "__init__.py").write_text("")
    (fake / "simulation" / "__init__.py").write_text("")
    (fake / "model.py").write_text("def f():\n    from hybrid.simulation.engine import run\n")
    (fake / "simulation" / "engine.py").write_text("from hybrid.model import Automaton\n")
    assert _circles(fake) == [["hybrid.model", "hybrid.simulation.engine"]] or _circles(fake) == [
        ["hybrid.simulation.engine", "hybrid.model"]
    ]
    assert _upward(fake) == ["hybrid.model -> hybrid.simulation.engine"]


@pytest.mark.parametrize(
    "path", sorted(PACKAGE.rglob("*.py")), ids=lambda p: str(p.relative_to(REPO))
)
def test_a_long_module_is_worth_a_look(path: Path) -> None:
    text = path.read_text(encoding="utf-8")
    lines = text.count("\n")
    assert lines <= MAX_LINES, f"{path.relative_to(REPO)} has {lines} lines: split it by topic"
    docstring = ast.get_docstring(ast.parse(text)) or ""
    if lines > SOFT_MAX_LINES and "one cohesive table" not in docstring:
        warnings.warn(
            f"{path.relative_to(REPO)} has {lines} lines: is it still one topic?", stacklevel=1
        )


def test_the_kernels_textual_dependencies_are_seen_and_import_nothing() -> None:
    from hybrid.simulation.native.kernel_text import KERNEL_MODULES, MARKER

    native = PACKAGE / "simulation" / "native"
    assert _spliced(native / "kernel_text.py") == [
        f"hybrid.simulation.native.{m}" for m in KERNEL_MODULES
    ]
    assert "hybrid.simulation.native.mathlib" in _spliced(native / "source.py")
    graph = _graph()[0]
    assert graph.has_edge("hybrid.simulation.native.source", "hybrid.simulation.native.mathlib")
    spliced = {m for path in native.glob("*.py") for m in _spliced(path)}
    for module in sorted(spliced):
        text = (PACKAGE.parent / Path(*module.split("."))).with_suffix(".py").read_text()
        assert MARKER in text, f"{module} is spliced but has no {MARKER!r} line"
        below = ast.parse(text.split(MARKER, 1)[1])
        imports = [n for n in ast.walk(below) if isinstance(n, ast.Import | ast.ImportFrom)]
        assert not imports, f"{module}: the code below its marker is copied; it may import nothing"
