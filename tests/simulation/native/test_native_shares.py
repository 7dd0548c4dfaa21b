"""The kernel compiled in shares by several processes (a cache miss), and what each piece needs."""

from __future__ import annotations

import ast
import importlib.util
import subprocess
import sys
import textwrap
from pathlib import Path
from types import ModuleType

import pytest

from hybrid.simulation.native import shares as sh
from hybrid.simulation.native.kernel_text import KERNEL_MODULES, kernel_module, kernel_source
from hybrid.simulation.native.kernel_types import PIECES

pytest.importorskip("numba")

# a generated module in miniature: two pieces calling one helper, compiled as the kernel is
MODULE = textwrap.dedent(
    """
    from numba import njit
    from hybrid.simulation.native.shares import compile_kernel, maybe_cached

    def helper(x):
        return x + 1.0

    def first(x):
        return helper(x) * 2.0

    def second(x):
        return helper(x) * 3.0

    _NAMES = ("helper", "first", "second")
    _PLAIN = {name: globals()[name] for name in _NAMES}

    def _jit(name):
        return njit("float64(float64)", cache=True)(_PLAIN[name])

    def finish_compiling():
        pass

    def build():
        global finish_compiling, HERE_BEFORE_FINISH
        try:
            if not maybe_cached(__file__, __name__, ("first", "second")):
                raise LookupError
            for name in ("first", "second"):
                globals()[name] = _jit(name)
        except Exception:
            finish_compiling = compile_kernel(globals(), _jit, _NAMES, ("first", "second"),
                                              __file__, __name__, {"first": 2.0, "second": 1.0})
        HERE_BEFORE_FINISH = [name for name in ("first", "second")
                              if hasattr(globals()[name], "py_func")]
        finish_compiling()
    """
)


def _load(path: Path, name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    try:
        spec.loader.exec_module(module)
        module.build()
    finally:
        del sys.modules[name]
    return module


def _hits(dispatcher: object) -> int:
    return sum(dispatcher.stats.cache_hits.values())  # type: ignore[attr-defined]


def test_shares_finish_first_counting_shared_callees_once() -> None:
    # by hand (a, b: 3 s each, both call h: 2 s; c: 2 s; a worker starts at 1 s):
    # {a, b} | {c}: 8 s; {a, c} | {b}: 7 | 6; {a} | {b, c}: 5 | 8; all here: 10
    costs = {"a": 3.0, "b": 3.0, "c": 2.0, "h": 2.0}
    needs = {"a": ("h",), "b": ("h",), "c": ()}
    assert sh.shares(costs, needs, 2, startup=1.0) == [["a", "c"], ["b"]]
    # with a 3 s model here besides: {a} | {b, c}: 8 | 8; {a, c} | {b}: 10 | 6; {} | all: 3 | 11
    assert sh.shares(costs, needs, 2, startup=1.0, beside=3.0) == [["a"], ["b", "c"]]
    assert sh.shares(costs, needs, 1) == [["a", "b", "c"]]
    # a 30 s model here: the workers take every piece, split as two would split them alone
    # ({a, c} | {b}: 8 | 6 before {a, b} | {c}: 9 | 3)
    assert sh.shares(costs, needs, 3, startup=1.0, beside=30.0) == [[], ["a", "c"], ["b"]]
    # a worker with nothing to do is not started
    assert sh.shares({"a": 1.0}, {"a": ()}, 4, startup=1.0) == [["a"]]


def test_function_costs_follow_the_size_of_the_code() -> None:
    code = "def small(x):\n    return x\n\ndef large(x):\n    y = x + 1\n    return y * y + x\n"
    costs = sh.function_costs(code, ["small", "large"])
    assert 0 < costs["small"] < costs["large"]


def test_processes_follow_the_environment(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(sh.PROCESSES_ENV, "3")
    assert sh.processes(5) == 3
    assert sh.processes(2) == 2  # at most one per piece
    monkeypatch.setenv(sh.PROCESSES_ENV, "1")
    assert sh.processes(5) == 1
    monkeypatch.setenv(sh.PROCESSES_ENV, "many")
    assert sh.processes(5) == 1


def test_each_piece_needs_exactly_the_kernel_functions_it_calls() -> None:
    """Every kernel function is a piece or called by one; no piece is called directly by another."""
    _code, names = kernel_source(KERNEL_MODULES[:-1])
    pieces = [name for name, _ in PIECES]
    # what compile_kernel reads: the generated module's code, with its own helpers in it
    needs = sh.piece_callees(kernel_module().source, names, pieces)
    assert sorted(needs) == sorted(pieces)
    assert set(names) == set(pieces) | {n for callees in needs.values() for n in callees}
    assert not any(set(callees) & set(pieces) for callees in needs.values())
    # by hand: the step calls remember_flow_failure and min_step_at; run_one calls decide
    # through a pointer
    assert needs["rk45_step"] == ("remember_flow_failure", "min_step_at")
    assert "enabled_at_entry" in needs["decide"] and "enabled_at_entry" not in needs["run_one"]


def test_the_kernels_functions_are_found_without_parsing_as_by_parsing() -> None:
    for modules in (KERNEL_MODULES[:-1], ("ensemble",), ("mathlib",)):
        code, names = kernel_source(modules)
        parsed = [n.name for n in ast.parse(code).body if isinstance(n, ast.FunctionDef)]
        assert names == parsed and names


def test_a_worker_compiles_its_share_and_this_process_loads_it(tmp_path: Path) -> None:
    path = tmp_path / "hybrid_native_shares_probe.py"
    path.write_text(MODULE, encoding="utf-8")
    code = (
        "import importlib.util, sys\n"
        f"spec = importlib.util.spec_from_file_location('hybrid_native_shares_probe', {str(path)!r})\n"
        "m = importlib.util.module_from_spec(spec); sys.modules[spec.name] = m\n"
        "spec.loader.exec_module(m)\n"
        "m.build()\n"
        "print(m.first(1.0), m.second(1.0), sum(m.first.stats.cache_hits.values()),"
        " sum(m.second.stats.cache_hits.values()), *m.HERE_BEFORE_FINISH)\n"
    )
    env = {**__import__("os").environ, sh.PROCESSES_ENV: "2"}
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env,
                          timeout=300, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    # "first" (the larger share) compiled here, "second" by the worker and loaded from the cache
    # once finish_compiling() is called (before: still the Python function)
    assert done.stdout.split() == ["4.0", "6.0", "0", "1", "first"]
    assert sh.maybe_cached(str(path), "hybrid_native_shares_probe", ("first", "second"))
    again = _load(path, "hybrid_native_shares_probe")  # a second process's path: both from the cache
    assert (again.first(2.0), again.second(2.0)) == (6.0, 9.0)
    assert (_hits(again.first), _hits(again.second)) == (1, 1)


def test_without_workers_this_process_compiles_every_piece(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    path = tmp_path / "hybrid_native_shares_alone.py"
    path.write_text(MODULE, encoding="utf-8")
    monkeypatch.setenv(sh.PROCESSES_ENV, "2")
    monkeypatch.setattr(sh.sys, "executable", "")  # no interpreter to start: no worker
    assert not sh.maybe_cached(str(path), "hybrid_native_shares_alone", ("first", "second"))
    module = _load(path, "hybrid_native_shares_alone")
    assert (module.first(1.0), module.second(1.0)) == (4.0, 6.0)
    assert (_hits(module.first), _hits(module.second)) == (0, 0)


def test_every_kernel_function_is_defined_after_the_kernel_functions_it_calls() -> None:
    # compiled in this order, each eagerly with its signature: a callee defined later is an
    # untyped global when its caller compiles (a first compile in one process failed so)
    code, names = kernel_source(KERNEL_MODULES)
    kernel = set(names)
    defined: set[str] = set()
    for node in ast.parse(code).body:
        if not isinstance(node, ast.FunctionDef):
            continue
        calls = {c.func.id for c in ast.walk(node)
                 if isinstance(c, ast.Call) and isinstance(c.func, ast.Name)}  # fmt: skip
        later = sorted((calls & kernel) - defined - {node.name})
        assert not later, f"{node.name} calls {later}, defined after it"
        defined.add(node.name)
