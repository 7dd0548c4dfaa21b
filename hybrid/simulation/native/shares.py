"""The kernel compiled in shares by several processes, when numba's cache misses it.

Compiling the kernel (:func:`~hybrid.simulation.native.kernel_text.kernel_module`)
costs about 14 s of one core, almost all of it numba's own typing and lowering
and LLVM, spread over the whole kernel (no function dominates, and no
optimisation level short of none saves much: measured in docs/performance.md).
Its pieces (:data:`~hybrid.simulation.native.kernel_types.PIECES`) are
independent compile units (they reach each other through function pointers),
so on a machine with more than one core they are compiled in parallel: this
process compiles its share, worker processes compile theirs into numba's disk
cache beside the generated module, and this process then loads those from the
cache, as a second process would. A worker that fails or is not possible
leaves its pieces to this process (compiled here, as without workers).

How many processes: ``$HYBRID_NATIVE_COMPILE_PROCESSES`` if set (``1``: all
in this process), else the CPUs this process may use, at most one per piece.
Which pieces each compiles (:func:`shares`): the split that finishes first,
counting what each function costs to compile (from its size,
:func:`function_costs`) once per process that needs it, a worker's start, and
what this process compiles besides (the model it was asked for,
:func:`compiling_beside`).

Examples
--------
>>> costs = {"a": 3.0, "b": 3.0, "c": 2.0, "h": 2.0}  # a and b both call h
>>> needs = {"a": ("h",), "b": ("h",), "c": ()}
>>> shares(costs, needs, 2, startup=1.0)
[['a', 'c'], ['b']]
>>> shares(costs, needs, 2, startup=1.0, beside=3.0)
[['a'], ['b', 'c']]
"""

from __future__ import annotations

import ast
import functools
import itertools
import json
import os
import subprocess
import sys
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from typing import Any

__all__ = [
    "PROCESSES_ENV",
    "SHARE_ENV",
    "compile_kernel",
    "compiling_beside",
    "function_costs",
    "maybe_cached",
    "piece_callees",
    "processes",
    "shares",
]

PROCESSES_ENV = "HYBRID_NATIVE_COMPILE_PROCESSES"
SHARE_ENV = "HYBRID_NATIVE_COMPILE_SHARE"
"""Set in a worker: the pieces it compiles (comma-separated); it compiles nothing else."""

SECONDS_PER_NODE = 0.0011
"""Seconds of one core to compile a kernel function, per node of its syntax tree (measured
function by function, numba 0.68: the fit's correlation 0.92; its callees linked in and
numba's first compile in a process besides)."""

WORKER_STARTUP_S = 1.0
"""What a worker spends before compiling (importing hybrid and numba), in the costs' unit."""

_BESIDE = [0.0]

WORKER_TIMEOUT_S = 900.0

_WORKER = """
import importlib.util, json, sys
path, name = sys.argv[1], sys.argv[2]
sys.path[:] = json.loads(sys.argv[3])  # this process's, so that hybrid is the same one
spec = importlib.util.spec_from_file_location(name, path)
module = importlib.util.module_from_spec(spec)
sys.modules[name] = module
spec.loader.exec_module(module)
from hybrid.frames import with_frame_room
with_frame_room(module.build)
"""


def processes(pieces: int) -> int:
    """How many processes compile ``pieces`` pieces (see the module docstring)."""
    configured = os.environ.get(PROCESSES_ENV, "").strip()
    if configured:
        try:
            wanted = int(configured)
        except ValueError:
            wanted = 1
    else:
        affinity = getattr(os, "sched_getaffinity", None)
        wanted = len(affinity(0)) if affinity is not None else (os.cpu_count() or 1)
    return max(1, min(wanted, pieces))


@functools.lru_cache(maxsize=2)
def _functions(code: str) -> tuple[ast.FunctionDef, ...]:
    """The functions ``code`` defines at its top level (parsed once for both readers below)."""
    return tuple(node for node in ast.parse(code).body if isinstance(node, ast.FunctionDef))


def piece_callees(
    code: str, names: Sequence[str], pieces: Sequence[str]
) -> dict[str, tuple[str, ...]]:
    """Each piece's callees among ``names``, transitively (a call of a parameter or local is not one)."""
    known = set(names)
    direct: dict[str, set[str]] = {}
    for node in _functions(code):
        params = {a.arg for a in node.args.args} | {
            n.id for n in ast.walk(node) if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)
        }
        direct[node.name] = {
            call.func.id
            for call in ast.walk(node)
            if isinstance(call, ast.Call) and isinstance(call.func, ast.Name)
            and call.func.id in known and call.func.id not in params
        }  # fmt: skip
    out = {}
    for piece in pieces:
        seen: set[str] = set()
        stack = list(direct.get(piece, ()))
        while stack:
            name = stack.pop()
            if name not in seen:
                seen.add(name)
                stack.extend(direct.get(name, ()))
        out[piece] = tuple(n for n in names if n in seen)
    return out


def maybe_cached(path: str, module: str, pieces: Sequence[str]) -> bool:
    """False if numba's cache surely lacks a piece (no file of it beside ``path``), else True.

    Saves a failed attempt at loading (typing the first piece until it calls a
    function not compiled yet) when compiling is certain; a worker never loads.
    """
    if os.environ.get(SHARE_ENV) is not None:
        return False
    try:
        files = os.listdir(os.path.join(os.path.dirname(path), "__pycache__"))
    except OSError:
        return False
    return all(any(f.startswith(f"{module}.{piece}-") for f in files) for piece in pieces)


def function_costs(code: str, names: Sequence[str]) -> dict[str, float]:
    """The estimated seconds to compile each function ``names`` of ``code`` (by its size)."""
    sizes = {node.name: sum(1 for _ in ast.walk(node)) for node in _functions(code)}
    return {name: round(SECONDS_PER_NODE * sizes.get(name, 0), 3) for name in names}


@contextmanager
def compiling_beside(seconds: float) -> Iterator[None]:
    """Within: a kernel compiled now is split knowing this process compiles ``seconds`` more."""
    _BESIDE[0] = seconds
    try:
        yield
    finally:
        _BESIDE[0] = 0.0


def shares(
    costs: Mapping[str, float],
    needs: Mapping[str, Iterable[str]],
    count: int,
    startup: float = WORKER_STARTUP_S,
    beside: float = 0.0,
) -> list[list[str]]:
    """The pieces (``needs``' keys) in at most ``count`` shares, this process's first.

    The split whose last share finishes first (then its next to last...): a
    share compiles its pieces and every function they call (``needs``) once,
    at ``costs`` each; this process's share starts at ``beside``, a worker's
    at ``startup``. Every split is tried (at most 5**5 here); of equal ones the
    first (this process's share first); a worker with nothing to compile is
    not started.
    """
    pieces = list(needs)
    closure = [frozenset((p, *needs[p])) for p in pieces]
    starts = [beside] + [startup] * (max(1, count) - 1)
    best: tuple[tuple[float, ...], tuple[int, ...]] | None = None
    for plan in itertools.product(range(len(starts)), repeat=len(pieces)):
        finishes = []
        for k, start in enumerate(starts):
            wanted = frozenset().union(*(c for c, owner in zip(closure, plan, strict=True) if owner == k))
            if wanted or k == 0:
                finishes.append(round(start + sum(costs.get(f, 0.0) for f in wanted), 9))
        key = tuple(sorted(finishes, reverse=True))
        if best is None or key < best[0]:
            best = (key, plan)
    assert best is not None
    out = [[p for p, owner in zip(pieces, best[1], strict=True) if owner == k] for k in range(len(starts))]
    return [out[0], *(share for share in out[1:] if share)]


def _compile(namespace: dict[str, Any], jit: Callable[[str], Any], names: Sequence[str],
             needs: Mapping[str, Iterable[str]], pieces: Iterable[str], done: set[str]) -> None:  # fmt: skip
    """Compile ``pieces`` and the functions they call, callees first (each once)."""
    wanted = set(pieces)
    for piece in pieces:
        wanted.update(needs[piece])
    for name in names:
        if name in wanted and name not in done:
            namespace[name] = jit(name)
            done.add(name)


def _spawn(path: str, module: str, share: Sequence[str]) -> subprocess.Popen[bytes] | None:
    if not sys.executable or getattr(sys, "frozen", False):  # no interpreter to start
        return None
    env = dict(os.environ)
    env[SHARE_ENV] = ",".join(share)
    search = [os.path.abspath(p) for p in sys.path if isinstance(p, str)]
    try:
        return subprocess.Popen(
            [sys.executable, "-c", _WORKER, path, module, json.dumps(search)],
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
    except OSError:
        return None


def _wait(worker: subprocess.Popen[bytes] | None) -> None:
    if worker is None:
        return
    try:
        worker.wait(timeout=WORKER_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        worker.kill()
        worker.wait()


def _stop(workers: list[subprocess.Popen[bytes] | None]) -> None:
    """Kill the workers (Ctrl-C): numba writes each cache file whole (a temporary file
    renamed), so a worker killed mid-compile leaves no entry a later process would load."""
    for worker in workers:
        if worker is not None and worker.poll() is None:
            worker.kill()
            worker.wait()


def compile_kernel(namespace: dict[str, Any], jit: Callable[[str], Any], names: Sequence[str],
                   pieces: Sequence[str], path: str, module: str,
                   costs: Mapping[str, float] | None = None) -> Callable[[], None]:  # fmt: skip
    """Compile the ``pieces`` of the generated module ``module`` (file ``path``) into ``namespace``.

    ``jit(name)`` compiles the function ``name`` of the module (or loads it
    from numba's cache); ``names`` lists them callees first. What each piece
    calls (:func:`piece_callees`) and, unless ``costs`` gives them, what each
    function costs to compile (:func:`function_costs`) are read from the
    module's code here, where they are needed. Returns ``finish``: this process's share is compiled now,
    the workers' pieces are there once ``finish()`` returns (meanwhile this
    process may compile something else: a model). In a worker
    (``$HYBRID_NATIVE_COMPILE_SHARE`` set) only that share is compiled.
    """
    with open(path, encoding="utf-8") as file:
        code = file.read()
    needs = piece_callees(code, names, pieces)
    done: set[str] = set()
    share = os.environ.get(SHARE_ENV)
    if share is not None:
        _compile(namespace, jit, names, needs, [p for p in share.split(",") if p in needs], done)
        return _nothing
    if costs is None:
        costs = function_costs(code, names)
    plan = shares(costs, needs, processes(len(needs)), beside=_BESIDE[0])
    workers = [_spawn(path, module, s) for s in plan[1:]]
    try:
        _compile(namespace, jit, names, needs, plan[0], done)
    except KeyboardInterrupt:
        _stop(workers)
        raise
    except BaseException:
        for worker in workers:
            _wait(worker)
        raise

    def finish() -> None:
        """Wait for the workers, then load their pieces (or compile those they did not)."""
        try:
            while workers:
                _wait(workers[-1])
                workers.pop()
        except KeyboardInterrupt:
            _stop(workers)
            raise
        for piece in (p for s in plan[1:] for p in s):
            if piece in done:
                continue
            try:
                namespace[piece] = jit(piece)  # from numba's cache (its callees are not needed)
            except Exception:  # the worker did not compile it: here, callees first
                _compile(namespace, jit, names, needs, [piece], done)
            done.add(piece)

    return finish


def _nothing() -> None:
    """Nothing left to compile."""
