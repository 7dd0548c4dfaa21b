"""Rewrites of IR trees.

Examples
--------
>>> from hybrid.expr import ir
>>> bind_parameters(ir.Bin("*", ir.Var("g", "param"), ir.Var("h", "state")), {"g": 2.0})
Bin(op='*', left=Num(value=2.0, col=0), right=Var(name='h', kind='state', col=0), col=0)
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace

from hybrid.expr import ir

__all__ = ["bind_parameters"]


def bind_parameters(node: ir.Expr, values: Mapping[str, float]) -> ir.Expr:
    """Replace every parameter by its value (expression depth is capped, so recursion is safe)."""
    if isinstance(node, ir.Var):
        if node.kind == ir.PARAM:
            return ir.Num(float(values[node.name]), node.col)
        return node
    if isinstance(node, ir.Call):
        return replace(node, args=tuple(bind_parameters(a, values) for a in node.args))
    if isinstance(node, ir.Unary | ir.Not):
        return replace(node, operand=bind_parameters(node.operand, values))
    if isinstance(node, ir.Bin):
        return replace(
            node, left=bind_parameters(node.left, values), right=bind_parameters(node.right, values)
        )
    if isinstance(node, ir.Cmp):
        return replace(node, operands=tuple(bind_parameters(a, values) for a in node.operands))
    if isinstance(node, ir.BoolOp):
        return replace(node, values=tuple(bind_parameters(a, values) for a in node.values))
    return node
