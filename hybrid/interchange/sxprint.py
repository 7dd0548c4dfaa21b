"""Our expression IR printed in the SpaceEx language (for ``hybrid export spaceex``).

``**`` becomes ``^``, ``and`` ``&``, ``or`` ``|``; ``not`` is pushed into the
comparisons it covers (``not x < 1`` is ``x >= 1``); the functions SpaceEx
tools read (``sin cos tan exp log sqrt`` and their kin) are kept. What has no
SpaceEx counterpart (``!=``, ``abs``, ``min``, ``max``, ``clip``, ``floor``,
vector signals, library functions) is refused with :class:`Unsupported`,
naming the construct.

Examples
--------
>>> from hybrid.expr.parse import Scope, parse_expression
>>> scope = Scope({"x": "state", "v": "state", "g": "param"})
>>> spaceex_text(parse_expression("x <= 0 and not v >= 0 or x ** 2 > g", scope, want="bool"))
'x <= 0 & v < 0 | x ^ 2 > g'
"""

from __future__ import annotations

from dataclasses import replace

from hybrid.expr import ir
from hybrid.expr.printer import PRECEDENCE, TextPrinter

__all__ = ["SPACEEX_FUNCTIONS", "Unsupported", "negate", "spaceex_text"]

SPACEEX_FUNCTIONS = frozenset(
    ["sin", "cos", "tan", "asin", "acos", "atan", "sinh", "cosh", "tanh", "exp", "log", "sqrt"]
)
"""Our functions written as they are in SpaceEx files."""

_FLIP = {"<": ">=", "<=": ">", ">": "<=", ">=": "<", "==": "!=", "!=": "=="}


class Unsupported(Exception):
    """A construct with no SpaceEx counterpart (the message names it)."""


def negate(node: ir.Expr) -> ir.Expr:
    """``not node`` with the negation pushed down to the comparisons."""
    if isinstance(node, ir.Not):
        return node.operand
    if isinstance(node, ir.BoolConst):
        return ir.BoolConst(not node.value)
    if isinstance(node, ir.BoolOp):
        return ir.BoolOp("or" if node.op == "and" else "and", tuple(negate(v) for v in node.values))
    if isinstance(node, ir.Cmp):
        if len(node.ops) == 1:
            return replace(node, ops=(_FLIP[node.ops[0]],))
        pairs = tuple(
            ir.Cmp((op,), (a, b))
            for op, a, b in zip(node.ops, node.operands, node.operands[1:], strict=False)
        )
        return negate(ir.BoolOp("and", pairs))
    raise Unsupported(f"cannot negate {type(node).__name__}")


def _push_not(node: ir.Expr) -> ir.Expr:
    if isinstance(node, ir.Not):
        return _push_not(negate(_push_not(node.operand)))
    if isinstance(node, ir.BoolOp):
        return replace(node, values=tuple(_push_not(v) for v in node.values))
    return node


class _SpaceExPrinter(TextPrinter):
    def emit(self, node: ir.Expr) -> tuple[str, int]:
        if isinstance(node, ir.BoolOp):
            p = PRECEDENCE[node.op]
            joiner = " & " if node.op == "and" else " | "
            return joiner.join(self.wrap(v, p + 1) for v in node.values), p
        if isinstance(node, ir.Not):
            raise Unsupported("'not' of a condition that is not a comparison")
        if isinstance(node, ir.Index):
            raise Unsupported(f"vector signal '{node.name}[{node.index}]'")
        if isinstance(node, ir.Call) and node.func not in SPACEEX_FUNCTIONS:
            raise Unsupported(f"function '{node.func}'")
        if isinstance(node, ir.Cmp) and "!=" in node.ops:
            raise Unsupported("'!=' (SpaceEx sets are closed: write two guards with < and >)")
        return super().emit(node)

    def binary(self, node: ir.Bin) -> tuple[str, int]:
        p = PRECEDENCE[node.op]
        if node.op == "**":
            return f"{self.wrap(node.left, p + 1)} ^ {self.wrap(node.right, p)}", p
        return super().binary(node)


def spaceex_text(node: ir.Expr) -> str:
    """``node`` in SpaceEx syntax; raises :class:`Unsupported` for what SpaceEx lacks."""
    return _SpaceExPrinter().emit(_push_not(node))[0]
