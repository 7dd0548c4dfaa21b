"""Printing expression IR: as a user writes it, or as Python source for generated code.

One precedence table and one walk serve both; :class:`SourcePrinter` only
changes how leaves and calls are spelled (local names, ``_fn`` calls, float
literals, ``math.pow``).

Examples
--------
>>> from hybrid.expr.parse import Scope, parse_expression
>>> e = parse_expression("-e*v + max(0, v)**2", Scope({"e": "param", "v": "state"}))
>>> expression_text(e)
'-e * v + max(0, v) ** 2'
>>> to_source(e, {"e": "p_e", "v": "x_v"})
'-p_e * x_v + _max(0.0, x_v) ** 2'
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from hybrid.expr import ir

__all__ = ["PRECEDENCE", "SourcePrinter", "TextPrinter", "expression_text", "to_source"]

PRECEDENCE = {
    "or": 1,
    "and": 2,
    "not": 3,
    "cmp": 4,
    "+": 5,
    "-": 5,
    "*": 6,
    "/": 6,
    "neg": 7,
    "**": 8,
}
"""Binding strength of each operator (Python's); atoms bind at 9."""
_ATOM = 9


class TextPrinter:
    """Prints an expression as a user would write it in a spec."""

    def emit(self, node: ir.Expr) -> tuple[str, int]:
        """``(text, precedence)`` of ``node``."""
        if isinstance(node, ir.Num):
            return self.number(node.value)
        if isinstance(node, ir.BoolConst):
            return self.boolean(node.value), _ATOM
        if isinstance(node, ir.Var):
            return self.name(node), _ATOM
        if isinstance(node, ir.Index):
            return f"{self.vector(node.name)}[{node.index}]", _ATOM
        if isinstance(node, ir.Call):
            args = ", ".join(self.emit(a)[0] for a in node.args)
            return f"{self.function(node.func)}({args})", _ATOM
        if isinstance(node, ir.Unary):
            return f"-{self.wrap(node.operand, PRECEDENCE['neg'] + 1)}", PRECEDENCE["neg"]
        if isinstance(node, ir.Bin):
            return self.binary(node)
        if isinstance(node, ir.Cmp):
            parts = [self.wrap(node.operands[0], PRECEDENCE["cmp"] + 1)]
            for op, operand in zip(node.ops, node.operands[1:], strict=True):
                parts.append(f"{op} {self.wrap(operand, PRECEDENCE['cmp'] + 1)}")
            return " ".join(parts), PRECEDENCE["cmp"]
        if isinstance(node, ir.BoolOp):
            p = PRECEDENCE[node.op]
            return f" {node.op} ".join(self.wrap(v, p + 1) for v in node.values), p
        if isinstance(node, ir.Not):
            return f"not {self.wrap(node.operand, PRECEDENCE['not'])}", PRECEDENCE["not"]
        raise TypeError(f"unknown IR node {node!r}")

    def wrap(self, node: ir.Expr, min_prec: int) -> str:
        text, prec = self.emit(node)
        return f"({text})" if prec < min_prec else text

    # --- spelling, overridden for generated source ------------------------------------

    def number(self, value: float) -> tuple[str, int]:
        if math.isfinite(value) and value == int(value) and abs(value) < 1e15:
            text = str(int(value))
        else:
            text = repr(value)
        return (text, PRECEDENCE["neg"]) if text.startswith("-") else (text, _ATOM)

    def boolean(self, value: bool) -> str:
        return "true" if value else "false"

    def name(self, node: ir.Var) -> str:
        return node.name

    def vector(self, name: str) -> str:
        return name

    def function(self, name: str) -> str:
        return name

    def binary(self, node: ir.Bin) -> tuple[str, int]:
        p = PRECEDENCE[node.op]
        if node.op == "**":  # right-associative
            return f"{self.wrap(node.left, p + 1)} ** {self.wrap(node.right, p)}", p
        return f"{self.wrap(node.left, p)} {node.op} {self.wrap(node.right, p + 1)}", p


class SourcePrinter(TextPrinter):
    """Prints Python source: names mapped to locals, calls to ``_name`` globals.

    Non-finite numbers become entries of a constant table ``_K`` (appended to
    ``consts``); ``**`` is ``math.pow`` (which raises on overflow) except for
    the squares and cubes that Python computes exactly.
    """

    def __init__(self, names: Mapping[str, str], consts: list[float] | None = None) -> None:
        self.names = names
        self.consts = consts if consts is not None else []

    def number(self, value: float) -> tuple[str, int]:
        return self.literal(value), _ATOM

    def literal(self, value: float) -> str:
        """A float literal (a ``_K`` entry for inf and nan)."""
        if math.isfinite(value):
            text = repr(float(value))
            return f"({text})" if text.startswith("-") else text
        self.consts.append(value)
        return f"_K[{len(self.consts) - 1}]"

    def boolean(self, value: bool) -> str:
        return "True" if value else "False"

    def name(self, node: ir.Var) -> str:
        return "t" if node.kind == ir.TIME else self.names[node.name]

    def vector(self, name: str) -> str:
        return self.names[name]

    def function(self, name: str) -> str:
        return f"_{name}"

    def binary(self, node: ir.Bin) -> tuple[str, int]:
        if node.op == "**":
            exponent = node.right
            if isinstance(exponent, ir.Num) and exponent.value in (2.0, 3.0):
                base = self.wrap(node.left, _ATOM)
                return f"{base} ** {int(exponent.value)}", PRECEDENCE["**"]
            return f"_pow({self.emit(node.left)[0]}, {self.emit(node.right)[0]})", _ATOM
        return super().binary(node)


def expression_text(node: ir.Expr) -> str:
    """An expression as a user would write it."""
    return TextPrinter().emit(node)[0]


def to_source(node: ir.Expr, names: Mapping[str, str], consts: list[float] | None = None) -> str:
    """Python source for ``node``; ``names`` maps each variable to its local name."""
    return SourcePrinter(names, consts).emit(node)[0]
