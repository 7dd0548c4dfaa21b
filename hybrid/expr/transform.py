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

__all__ = ["bind_parameters", "rename_names"]


def bind_parameters(node: ir.Expr, values: Mapping[str, float]) -> ir.Expr:
    """Replace every parameter by its value (expression depth is capped, so recursion is safe).

    A sub-expression that reads no parameter is returned as it is, the same object:
    models that differ in parameter values share it, and whatever is remembered of it
    (:func:`hybrid.expr.ir.names_in`) is found again.

    >>> x = ir.Bin("*", ir.Var("x", "state"), ir.Num(2.0))
    >>> bound = bind_parameters(ir.Bin("+", x, ir.Var("g", "param")), {"g": 9.81})
    >>> bound.right, bound.left is x
    (Num(value=9.81, col=0), True)
    """
    if isinstance(node, ir.Var):
        if node.kind == ir.PARAM:
            return ir.Num(float(values[node.name]), node.col)
        return node
    if isinstance(node, ir.Call):
        args = tuple(bind_parameters(a, values) for a in node.args)
        return node if _same(args, node.args) else replace(node, args=args)
    if isinstance(node, ir.Unary | ir.Not):
        operand = bind_parameters(node.operand, values)
        return node if operand is node.operand else replace(node, operand=operand)
    if isinstance(node, ir.Bin):
        left, right = bind_parameters(node.left, values), bind_parameters(node.right, values)
        if left is node.left and right is node.right:
            return node
        return replace(node, left=left, right=right)
    if isinstance(node, ir.Cmp):
        operands = tuple(bind_parameters(a, values) for a in node.operands)
        return node if _same(operands, node.operands) else replace(node, operands=operands)
    if isinstance(node, ir.BoolOp):
        items = tuple(bind_parameters(a, values) for a in node.values)
        return node if _same(items, node.values) else replace(node, values=items)
    return node


def _same(new: tuple[ir.Expr, ...], old: tuple[ir.Expr, ...]) -> bool:
    return all(a is b for a, b in zip(new, old, strict=True))


_RENAMED_KINDS = (ir.STATE, ir.SIGNAL, ir.INPUT)


def rename_names(node: ir.Expr, mapping: Mapping[str, str]) -> ir.Expr:
    """Rename state variables, signals and inputs (all at once: a swap is a swap).

    Examples
    --------
    >>> x, y = ir.Var("x", "state"), ir.Var("y", "input")
    >>> rename_names(ir.Bin("-", x, y), {"x": "y", "y": "x"})
    Bin(op='-', left=Var(name='y', kind='state', col=0), right=Var(name='x', kind='input', col=0), col=0)
    """
    if isinstance(node, ir.Var):
        if node.kind in _RENAMED_KINDS and node.name in mapping:
            return replace(node, name=mapping[node.name])
        return node
    if isinstance(node, ir.Index):
        return replace(node, name=mapping.get(node.name, node.name))
    if isinstance(node, ir.Call):
        return replace(node, args=tuple(rename_names(a, mapping) for a in node.args))
    if isinstance(node, ir.Unary | ir.Not):
        return replace(node, operand=rename_names(node.operand, mapping))
    if isinstance(node, ir.Bin):
        return replace(
            node, left=rename_names(node.left, mapping), right=rename_names(node.right, mapping)
        )
    if isinstance(node, ir.Cmp):
        return replace(node, operands=tuple(rename_names(a, mapping) for a in node.operands))
    if isinstance(node, ir.BoolOp):
        return replace(node, values=tuple(rename_names(a, mapping) for a in node.values))
    return node
