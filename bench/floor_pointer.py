"""The floor with its model behind a function pointer: what the compiled backend's design costs.

The compiled backend's loop is compiled once per machine and calls the model
through a function pointer (``model(op, index, t, x*, p*, out*) -> float``,
:mod:`hybrid.simulation.native.kernel_types`), so that a new model costs the
compile of its own functions only (about 0.5 s), not of the loop (about 12 s).
The floor (:mod:`bench.floor`) has the model written into the loop. This is the
floor's own code, function for function (the same Python functions, compiled
again with other globals), with the right-hand side, the watch and the reset
called the backend's way: through one function of that signature, at an
address the run is given. The ratio of the two says how much of the compiled
backend's distance to the floor the pointer costs by itself.

:func:`single` runs one model once, as :func:`bench.floor.single` does, with the
same results (the same arithmetic in the same order).

Examples
--------
>>> import numpy as np
>>> from bench import floor
>>> p, x0 = np.array([9.81, 0.95]), np.array([10.0, 0.0])
>>> mine, theirs = single(floor.BALL, p, x0, 100.0, 5), floor.single(floor.BALL, p, x0, 100.0, 5)
>>> bool(np.array_equal(mine[1], theirs[1]))
True
"""

from __future__ import annotations

import types
from functools import cache
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from bench import floor
from hybrid.simulation.native.kernel_types import model_signature
from hybrid.simulation.native.pointers import addresses, at, function_at

__all__ = ["single"]

_JIT = {**floor._JIT, "cache": False}  # the same code as the floor's: not in its cache entries
MODEL_FN_T = numba.types.FunctionType(model_signature())
RHS, WATCH, RESET = 0, 1, 2


def _model(kind: int) -> Any:
    """The model of ``kind`` (:data:`bench.floor.BALL` or ``THERMOSTAT``) as the backend calls one:
    the floor's own right-hand side, watch and reset, over the arrays at the pointers."""
    d, n_p = (2, 2) if kind == floor.BALL else (1, 5)  # states, parameters
    rhs, watch, reset = floor._rhs, floor._watch, floor._reset
    carray = numba.carray

    def model(op: int, m: int, t: float, x: Any, p: Any, out: Any) -> float:
        y, q = carray(x, d), carray(p, n_p)
        if op == RHS:
            rhs(kind, m, y, q, carray(out, d))
            return 0.0
        if op == WATCH:
            value: float = watch(kind, m, y, q)
            return value
        return float(reset(kind, m, y, q))  # the state in place, the mode returned

    return numba.njit(model_signature(), **_JIT)(model)


def _rhs(fns: Any, m: int, y: Any, p: Any, out: Any) -> None:
    fns(RHS, m, 0.0, at(y, 0), at(p, 0), at(out, 0))


def _watch(fns: Any, m: int, y: Any, p: Any) -> float:
    value: float = fns(WATCH, m, 0.0, at(y, 0), at(p, 0), at(y, 0))
    return value


def _reset(fns: Any, m: int, y: Any, p: Any) -> int:
    return int(fns(RESET, m, 0.0, at(y, 0), at(p, 0), at(y, 0)))


def _again(fn: Any, bound: dict[str, Any]) -> Any:
    """The floor's function ``fn`` compiled again, the names in ``bound`` rebound."""
    py = fn.py_func
    scope = {**py.__globals__, **bound}
    again = types.FunctionType(py.__code__, scope, py.__name__, py.__defaults__, py.__closure__)
    return numba.njit(**_JIT)(again)


@cache
def _loop() -> Any:
    """The floor's ``_simulate`` over the pointer's model (compiled on first use)."""
    bound: dict[str, Any] = {
        "_rhs": numba.njit(**_JIT)(_rhs),
        "_watch": numba.njit(**_JIT)(_watch),
        "_reset": numba.njit(**_JIT)(_reset),
    }
    bound["_at"] = _again(floor._at, bound)
    bound["_brent"] = _again(floor._brent, bound)
    bound["_initial_step"] = _again(floor._initial_step, bound)
    simulate = _again(floor._simulate, bound)

    def run(fp: Any, p: Any, x0: Any, m0: int, t_start: float, t_end: float, rtol: float,
            atol: float, max_jumps: int, pts: Any, jps: Any, A: Any, B: Any, C: Any, E: Any,
            P: Any) -> tuple[int, int]:  # fmt: skip
        fns = function_at(fp[0], fp[1], MODEL_FN_T)
        found: tuple[int, int] = simulate(
            fns, p, x0, m0, t_start, t_end, rtol, atol, max_jumps, pts, jps, A, B, C, E, P
        )
        return found

    return numba.njit(**_JIT)(run)


@cache
def _addresses(kind: int) -> NDArray[np.int64]:
    return np.array(addresses(_model(kind)), dtype=np.int64)


def single(kind: int, p: NDArray[np.float64], x0: NDArray[np.float64], t_end: float,
           max_jumps: int, rtol: float = 1e-10, atol: float = 1e-12,
           points: int = 4096) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # fmt: skip
    """One run as :func:`bench.floor.single`, the model called through its address."""
    d = x0.size
    pts = np.empty((points, 1 + d))
    jps = np.empty((max_jumps, 1 + 2 * d))
    n, j = _loop()(
        _addresses(kind), p, x0, 0, 0.0, t_end, rtol, atol, max_jumps, pts, jps,
        floor._A, floor._B, floor._C, floor._E, floor._P,
    )  # fmt: skip
    return pts[:n], jps[:j]
