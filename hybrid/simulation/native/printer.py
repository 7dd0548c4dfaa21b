"""Printing expression IR as numba-compilable source.

:class:`NativePrinter` is :class:`hybrid.expr.printer.SourcePrinter` with
the spellings compiled code needs: states are ``x[i]``, parameter slots
``p[k]``, signals ``s_name`` locals; built-in functions call the helpers of
:mod:`~hybrid.simulation.native.mathlib` (``h_sqrt``...), which turn Python's
failures into NaN; ``/`` and ``**`` are helper calls too; library functions
are ``_lib_name``; ``min``, ``max`` and ``hypot`` of more than two arguments
nest; comparison chains become conjunctions. Only checked IR reaches it:
numbers become float literals, names come from the tables built here.

Examples
--------
>>> from hybrid.expr.parse import Scope, parse_expression
>>> e = parse_expression("max(0, v, h) / g + sqrt(h)**2", Scope({"h": "state", "v": "state", "g": "param"}))
>>> NativePrinter({"h": "x[0]", "v": "x[1]", "g": "p[0]"}).emit(e)[0]
'h_div(h_max(0.0, h_max(x[1], x[0])), p[0]) + h_sq(h_sqrt(x[0]))'
>>> c = parse_expression("0 <= h < 1", Scope({"h": "state"}), want="bool")
>>> NativePrinter({"h": "x[0]"}).emit(c)[0]
'0.0 <= x[0] and x[0] < 1.0'
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

from hybrid.expr import ir
from hybrid.expr.dependencies import evaluation_order
from hybrid.expr.functions import BUILTINS
from hybrid.expr.printer import PRECEDENCE, SourcePrinter
from hybrid.simulation.native.structure import LEVEL_SIDE

__all__ = ["NativePrinter", "body_lines"]

_ATOM = 9
_VARIADIC = {"min": "h_min", "max": "h_max", "hypot": "h_hypot"}


class NativePrinter(SourcePrinter):
    """Python source that numba compiles in nopython mode (see the module docstring)."""

    def __init__(self, names: Mapping[str, str]) -> None:
        super().__init__(names, [])

    def literal(self, value: float) -> str:
        if math.isfinite(value):
            text = repr(float(value))
            return f"({text})" if text.startswith("-") else text
        if math.isnan(value):
            return "_NAN"
        return "_INF" if value > 0 else "(-_INF)"

    def function(self, name: str) -> str:
        if name == LEVEL_SIDE:
            return "h_level_side"
        return f"h_{name}" if name in BUILTINS else f"_lib_{name}"

    def emit(self, node: ir.Expr) -> tuple[str, int]:
        if isinstance(node, ir.Call) and node.func in _VARIADIC and len(node.args) > 2:
            head, *rest = node.args
            inner = ir.Call(node.func, tuple(rest), node.col)
            return f"{_VARIADIC[node.func]}({self.emit(head)[0]}, {self.emit(inner)[0]})", _ATOM
        if isinstance(node, ir.Cmp):
            parts = [
                f"{self.wrap(a, PRECEDENCE['cmp'] + 1)} {op} {self.wrap(b, PRECEDENCE['cmp'] + 1)}"
                for op, a, b in zip(node.ops, node.operands, node.operands[1:], strict=False)
            ]
            if len(parts) == 1:
                return parts[0], PRECEDENCE["cmp"]
            return " and ".join(parts), PRECEDENCE["and"]
        return super().emit(node)

    def binary(self, node: ir.Bin) -> tuple[str, int]:
        if node.op == "/":
            return f"h_div({self.emit(node.left)[0]}, {self.emit(node.right)[0]})", _ATOM
        if node.op == "**":
            exponent = node.right
            base = self.emit(node.left)[0]
            if isinstance(exponent, ir.Num) and exponent.value == 2.0:
                return f"h_sq({base})", _ATOM
            if isinstance(exponent, ir.Num) and exponent.value == 3.0:
                return f"h_cube({base})", _ATOM
            return f"h_pow({base}, {self.emit(exponent)[0]})", _ATOM
        return super().binary(node)


def body_lines(
    exprs: Sequence[ir.Expr],
    signals: Mapping[str, ir.Expr],
    names: Mapping[str, str],
) -> tuple[list[str], list[str]]:
    """``(lines computing the signals the expressions need, the expressions' source)``."""
    used: set[str] = set()
    for e in exprs:
        used |= ir.names_in(e)
    printer = NativePrinter(names)
    lines = [
        f"{names[s]} = {printer.emit(signals[s])[0]}" for s in evaluation_order(used, signals)
    ]
    return lines, [printer.emit(e)[0] for e in exprs]
