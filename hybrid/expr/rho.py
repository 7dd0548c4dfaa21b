"""Guards as real-valued functions: ``rho <= 0`` exactly when the guard holds.

The rewrite (DESIGN.md): ``a <= b`` and ``a < b`` become ``a - b``;
``a >= b`` and ``a > b`` become ``b - a``; ``a == b`` becomes ``|a - b|``;
``a != b`` becomes ``-|a - b|``; ``and`` is ``max``, ``or`` is ``min``, ``not``
negates; ``true`` is -1 and ``false`` is +1. Away from ``rho = 0`` the sign of
rho decides the guard. On ``rho = 0`` the boolean form decides: a non-strict
comparison (``<=``, ``>=``, ``==``) holds on its boundary, a strict one
(``<``, ``>``, ``!=``) does not. The simulator uses rho for root finding and
the boolean form to decide a guard that sits exactly on its boundary.

Examples
--------
>>> from hybrid.expr.parse import Scope, parse_expression
>>> from hybrid.expr.printer import to_source
>>> g = parse_expression("h <= 0 and v < 0", Scope({"h": "state", "v": "state"}), want="bool")
>>> to_source(guard_to_rho(g), {"h": "h", "v": "v"})
'_max(h, v)'
"""

from __future__ import annotations

from hybrid.expr import ir

__all__ = ["guard_to_rho", "is_strict"]


def guard_to_rho(node: ir.Expr) -> ir.Expr:
    """The rho expression of a boolean guard or invariant."""
    if isinstance(node, ir.BoolConst):
        return ir.Num(-1.0 if node.value else 1.0, node.col)
    if isinstance(node, ir.Not):
        return _negate(guard_to_rho(node.operand))
    if isinstance(node, ir.BoolOp):
        parts = tuple(guard_to_rho(v) for v in node.values)
        return ir.Call("max" if node.op == "and" else "min", parts, node.col)
    if isinstance(node, ir.Cmp):
        pairs = [
            _comparison(op, node.operands[i], node.operands[i + 1], node.col)
            for i, op in enumerate(node.ops)
        ]
        return pairs[0] if len(pairs) == 1 else ir.Call("max", tuple(pairs), node.col)
    raise TypeError(f"not a condition: {node!r}")


def is_strict(node: ir.Expr) -> bool:
    """True if ``node`` is a single strict comparison (``<``, ``>``, ``!=``)."""
    return isinstance(node, ir.Cmp) and len(node.ops) == 1 and node.ops[0] in ("<", ">", "!=")


def _comparison(op: str, a: ir.Expr, b: ir.Expr, col: int) -> ir.Expr:
    if op in ("<", "<="):
        return _sub(a, b, col)
    if op in (">", ">="):
        return _sub(b, a, col)
    diff = ir.Call("abs", (_sub(a, b, col),), col)
    return diff if op == "==" else ir.Unary("-", diff, col)


def _sub(a: ir.Expr, b: ir.Expr, col: int) -> ir.Expr:
    if isinstance(b, ir.Num) and b.value == 0.0:
        return a
    if isinstance(a, ir.Num) and a.value == 0.0:
        return ir.Unary("-", b, col)
    return ir.Bin("-", a, b, col)


def _negate(node: ir.Expr) -> ir.Expr:
    if isinstance(node, ir.Unary):
        return node.operand
    if isinstance(node, ir.Num):
        return ir.Num(-node.value, node.col)
    return ir.Unary("-", node, node.col)
