"""The kernel compiled in shares by several processes, when numba's cache misses it.

Compiling the kernel (:func:`~hybrid.simulation.native.source.kernel_module`)
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

Examples
--------
>>> shares({"a": 4.0, "b": 3.5, "c": 3.0, "d": 2.0, "e": 1.5}, 2, startup=1.0)
[['a', 'c'], ['b', 'd', 'e']]
>>> shares({"a": 4.0, "b": 3.5}, 1)
[['a', 'b']]
"""

from __future__ import annotations

import ast
import json
import os
import subprocess
import sys
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

__all__ = [
    "PIECE_COSTS",
    "PROCESSES_ENV",
    "SHARE_ENV",
    "compile_kernel",
    "maybe_cached",
    "piece_callees",
    "processes",
    "shares",
]

PROCESSES_ENV = "HYBRID_NATIVE_COMPILE_PROCESSES"
SHARE_ENV = "HYBRID_NATIVE_COMPILE_SHARE"
"""Set in a worker: the pieces it compiles (comma-separated); it compiles nothing else."""

PIECE_COSTS = {
    "flow_stay": 4.0,
    "first_event": 3.5,
    "run_one": 3.0,
    "decide": 2.2,
    "rk45_step": 1.5,
}
"""Seconds of one core to compile each piece with the functions it calls (measured, numba 0.68)."""

WORKER_STARTUP_S = 1.2
"""What a worker spends before compiling (importing hybrid and numba), in the costs' unit."""

WORKER_TIMEOUT_S = 900.0

_WORKER = """
import importlib.util, json, sys
path, name = sys.argv[1], sys.argv[2]
sys.path[:] = json.loads(sys.argv[3])  # this process's, so that hybrid is the same one
spec = importlib.util.spec_from_file_location(name, path)
module = importlib.util.module_from_spec(spec)
sys.modules[name] = module
spec.loader.exec_module(module)
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


def piece_callees(
    code: str, names: Sequence[str], pieces: Sequence[str]
) -> dict[str, tuple[str, ...]]:
    """Each piece's callees among ``names``, transitively (a call of a parameter or local is not one)."""
    known = set(names)
    direct: dict[str, set[str]] = {}
    for node in ast.parse(code).body:
        if isinstance(node, ast.FunctionDef):
            params = {a.arg for a in node.args.args} | {
                n.id
                for n in ast.walk(node)
                if isinstance(n, ast.Name) and isinstance(n.ctx, ast.Store)
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


def shares(
    costs: Mapping[str, float], count: int, startup: float = WORKER_STARTUP_S
) -> list[list[str]]:
    """The pieces split into ``count`` shares of about equal cost, this process's first.

    Largest first, each to the share that would finish first; a worker's share
    starts at ``startup`` (this process's at 0).
    """
    loads = [0.0] + [startup] * (count - 1)
    out: list[list[str]] = [[] for _ in range(count)]
    for name in sorted(costs, key=lambda n: -costs[n]):
        k = min(range(count), key=lambda i: loads[i])
        out[k].append(name)
        loads[k] += costs[name]
    return [share for share in out if share] or [[]]


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


def compile_kernel(namespace: dict[str, Any], jit: Callable[[str], Any], names: Sequence[str],
                   costs: Mapping[str, float], needs: Mapping[str, Iterable[str]], path: str,
                   module: str) -> Callable[[], None]:  # fmt: skip
    """Compile the pieces of the generated module ``module`` (file ``path``) into ``namespace``.

    ``jit(name)`` compiles the function ``name`` of the module (or loads it
    from numba's cache); ``names`` lists them callees first; ``needs[piece]``
    names the functions a piece calls; ``costs`` holds each piece's estimated
    compile time. Returns ``finish``: this process's share is compiled now,
    the workers' pieces are there once ``finish()`` returns (meanwhile this
    process may compile something else: a model). In a worker
    (``$HYBRID_NATIVE_COMPILE_SHARE`` set) only that share is compiled.
    """
    done: set[str] = set()
    share = os.environ.get(SHARE_ENV)
    if share is not None:
        _compile(namespace, jit, names, needs, [p for p in share.split(",") if p in costs], done)
        return _nothing
    plan = shares(costs, processes(len(costs)))
    workers = [_spawn(path, module, s) for s in plan[1:]]
    try:
        _compile(namespace, jit, names, needs, plan[0], done)
    except BaseException:
        for worker in workers:
            _wait(worker)
        raise

    def finish() -> None:
        """Wait for the workers, then load their pieces (or compile those they did not)."""
        while workers:
            _wait(workers.pop())
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
