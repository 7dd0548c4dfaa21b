"""Values of SpaceEx trees: a reset applied to a condition, a constant expression's number.

Examples
--------
>>> from hybrid.interchange.safexml import SourceText
>>> tree = sx.parse(SourceText("m.xml", "2 * c ^ 2 - 1"))
>>> constant_value(tree, {"c": 3.0}), constant_value(tree, {})
(17.0, None)
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from hybrid.interchange import sxexpr as sx

__all__ = ["constant_value", "substitute"]


def substitute(node: sx.Node, values: Mapping[str, sx.Node]) -> sx.Node:
    """``node`` with each unprimed variable in ``values`` replaced (a reset applied to a condition)."""
    if isinstance(node, sx.Name):
        return values.get(node.name, node) if not node.primed else node
    if isinstance(node, sx.Neg):
        return sx.Neg(substitute(node.operand, values), node.position)
    if isinstance(node, sx.BinOp):
        return sx.BinOp(
            node.op, substitute(node.left, values), substitute(node.right, values), node.position
        )
    if isinstance(node, sx.Call):
        return sx.Call(node.func, tuple(substitute(a, values) for a in node.args), node.position)
    if isinstance(node, sx.Cmp):
        operands = tuple(substitute(o, values) for o in node.operands)
        return sx.Cmp(node.ops, operands, node.position, node.single)
    if isinstance(node, sx.And):
        return sx.And(tuple(substitute(i, values) for i in node.items), node.position)
    if isinstance(node, sx.Or):
        return sx.Or(tuple(substitute(i, values) for i in node.items), node.position)
    return node


def constant_value(node: sx.Node, values: Mapping[str, float]) -> float | None:
    """The number an arithmetic tree of numbers and known constants stands for, else ``None``."""
    if isinstance(node, sx.Num):
        return node.value
    if isinstance(node, sx.Name):
        return None if node.primed else values.get(node.name)
    if isinstance(node, sx.Neg):
        inner = constant_value(node.operand, values)
        return None if inner is None else -inner
    if isinstance(node, sx.BinOp):
        a = constant_value(node.left, values)
        b = constant_value(node.right, values)
        if a is None or b is None:
            return None
        try:
            result = _arith(node.op, a, b)
        except (ZeroDivisionError, OverflowError, ValueError):
            return None
        return result if math.isfinite(result) else None
    return None


def _arith(op: str, a: float, b: float) -> float:
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return a * b
    if op == "/":
        return a / b
    return float(math.pow(a, b))
