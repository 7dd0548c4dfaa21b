"""Expressions that are sums of number-times-variable terms, read as one matrix product.

The linear models of the field come as flows written out term by term: ARCH-COMP's
Building has 48 state variables and 1,176 terms such as ``0.0137 * u1 - 606.16 * x1
+ 34.67 * x2 ...``. Compiled to Python, each term is an operation of the
interpreter, and a call of Building's flow cost 340 µs. Read as ``M x + N u + c``,
the same call is one matrix product.

Only the plain shape is read: sums and differences of numbers, parameters, state
variables, inputs, and products of a number (or parameter) with one of them.
Anything else (a signal, time, a division, a product of two variables, a
function) is not read, and the expression is compiled term by term as before.
The matrix product sums the same products in another order, so the result agrees
with the term-by-term one to rounding (a few units in the last place).

Examples
--------
>>> from hybrid.expr import ir
>>> x, y = ir.Var("x", ir.STATE), ir.Var("y", ir.STATE)
>>> row = ir.Bin("-", ir.Bin("*", ir.Num(2.0), x), ir.Bin("*", y, ir.Var("k", ir.PARAM)))
>>> form = matrix_form([row, x], ("x", "y"), {"k": 3.0}, ())
>>> form.states.tolist(), form.const.tolist(), form.terms
([[2.0, -3.0], [1.0, 0.0]], [0.0, 0.0], 3)
>>> matrix_form([ir.Bin("*", x, y)], ("x", "y"), {}, ()) is None
True
"""

from __future__ import annotations

import math
from collections.abc import Container, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from hybrid.expr import ir

__all__ = ["MatrixForm", "matrix_form"]


@dataclass(frozen=True)
class MatrixForm:
    """``outputs = states @ x + by_input @ (inputs...) + const``; ``terms`` products were read."""

    states: NDArray[np.float64]
    inputs: tuple[str, ...]
    by_input: NDArray[np.float64]
    const: NDArray[np.float64]
    terms: int


def matrix_form(
    exprs: Sequence[ir.Expr],
    states: Sequence[str],
    params: Mapping[str, float],
    inputs: Container[str],
) -> MatrixForm | None:
    """The matrix form of ``exprs`` over ``states`` and the ``inputs`` they read, or None.

    ``params`` gives each parameter's value (a parameter is a number here).
    """
    column = {name: i for i, name in enumerate(states)}
    rows: list[tuple[dict[str, float], float]] = []
    terms = 0
    for expr in exprs:
        read = _row(expr, column, params, inputs)
        if read is None:
            return None
        coeffs, offset, count = read
        rows.append((coeffs, offset))
        terms += count
    used = tuple(sorted({name for coeffs, _ in rows for name in coeffs if name not in column}))
    where = {name: k for k, name in enumerate(used)}
    matrix = np.zeros((len(rows), len(states)))
    by_input = np.zeros((len(rows), len(used)))
    const = np.zeros(len(rows))
    for i, (coeffs, c) in enumerate(rows):
        const[i] = c
        for name, value in coeffs.items():
            if name in column:
                matrix[i, column[name]] = value
            else:
                by_input[i, where[name]] = value
    return MatrixForm(matrix, used, by_input, const, terms)


def _row(
    expr: ir.Expr,
    column: Mapping[str, int],
    params: Mapping[str, float],
    inputs: Container[str],
) -> tuple[dict[str, float], float, int] | None:
    """``(coefficient of each variable, constant, products read)`` of one expression, or None."""
    coeffs: dict[str, float] = {}
    const = 0.0
    count = 0
    stack: list[tuple[ir.Expr, float]] = [(expr, 1.0)]  # no recursion: a row may be long
    while stack:
        node, sign = stack.pop()
        if isinstance(node, ir.Bin) and node.op in ("+", "-"):
            stack.append((node.left, sign))
            stack.append((node.right, sign if node.op == "+" else -sign))
        elif isinstance(node, ir.Unary) and node.op == "-":
            stack.append((node.operand, -sign))
        elif (number := _number(node, params)) is not None:
            const += sign * number
        elif _variable(node, column, inputs):
            assert isinstance(node, ir.Var)
            coeffs[node.name] = coeffs.get(node.name, 0.0) + sign
            count += 1
        elif isinstance(node, ir.Bin) and node.op == "*":
            pair = _scaled(node.left, node.right, column, params, inputs)
            if pair is None:
                pair = _scaled(node.right, node.left, column, params, inputs)
            if pair is None:
                return None
            name, factor = pair
            coeffs[name] = coeffs.get(name, 0.0) + sign * factor
            count += 1
        else:
            return None
    if not (math.isfinite(const) and all(math.isfinite(v) for v in coeffs.values())):
        return None
    return coeffs, const, count


def _number(node: ir.Expr, params: Mapping[str, float]) -> float | None:
    if isinstance(node, ir.Num) and not isinstance(node.value, bool):
        return float(node.value)
    if isinstance(node, ir.Var) and node.kind == ir.PARAM and node.name in params:
        return float(params[node.name])
    return None


def _variable(node: ir.Expr, column: Mapping[str, int], inputs: Container[str]) -> bool:
    return isinstance(node, ir.Var) and (
        (node.kind == ir.STATE and node.name in column)
        or (node.kind == ir.INPUT and node.name in inputs)
    )


def _scaled(
    number: ir.Expr,
    variable: ir.Expr,
    column: Mapping[str, int],
    params: Mapping[str, float],
    inputs: Container[str],
) -> tuple[str, float] | None:
    """``(variable, factor)`` if ``number * variable`` is a number times one variable."""
    factor = _number(number, params)
    if factor is None or not _variable(variable, column, inputs):
        return None
    assert isinstance(variable, ir.Var)
    return variable.name, factor
