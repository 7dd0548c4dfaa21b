"""Whatever a library function raises is a failure of the evaluation, not an escape.

A table lookup past its end raises IndexError, a library may raise its own
exception class: each makes the compiled function return NaN and record the
failure (the run then ends ``nonfinite`` naming the call), as a domain error
does. Before, only ArithmeticError, ValueError and TypeError were caught, and
these escaped ``hybrid.simulate`` as a traceback.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from hybrid.expr.codegen import CodeContext, compile_function
from hybrid.expr.functions import Function
from hybrid.expr.parse import Scope, parse_expression


class LibraryTrouble(Exception):
    """A library's own exception class."""


def _lookup(x: float) -> float:
    return (10.0, 20.0, 30.0)[int(x)]  # an IndexError from 3 on


def _picky(x: float) -> float:
    if x > 1.0:
        raise LibraryTrouble(f"picky at x={x}")
    return 2.0 * x


FUNCTIONS = {
    "lookup": Function("lookup", _lookup, 1, 1, builtin=False),
    "picky": Function("picky", _picky, 1, 1, builtin=False),
}
SCOPE = Scope({"a": "state"}, FUNCTIONS)


@pytest.mark.parametrize(
    ("call", "good", "bad", "error"),
    [("lookup(a)", (2.0, 30.0), 3.0, IndexError), ("picky(a)", (0.5, 1.0), 1.5, LibraryTrouble)],
)
def test_a_library_exception_is_a_recorded_failure(
    call: str, good: tuple[float, float], bad: float, error: type[Exception]
) -> None:
    ctx = CodeContext(states=("a",), functions=FUNCTIONS)
    flow = compile_function("flow", [parse_expression(call, SCOPE)], ctx)
    a, value = good
    assert flow(0.0, np.array([a])) == [value]
    assert ctx.failure.error is None
    result = flow(0.0, np.array([bad]))
    assert all(math.isnan(v) for v in result)
    assert isinstance(ctx.failure.error, error)


def test_an_interrupt_is_not_a_failure() -> None:
    def _stop(x: float) -> float:
        raise KeyboardInterrupt

    functions = {"stop": Function("stop", _stop, 1, 1, builtin=False)}
    ctx = CodeContext(states=("a",), functions=functions)
    flow = compile_function("flow", [parse_expression("stop(a)", Scope({"a": "state"}, functions))], ctx)
    with pytest.raises(KeyboardInterrupt):
        flow(0.0, np.array([1.0]))
