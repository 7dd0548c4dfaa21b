"""Signals replaced by their definitions, for conditions the analysis reasons about."""

from __future__ import annotations

from collections.abc import Mapping

from hybrid.expr import ir

__all__ = ["INLINE_BUDGET", "inline_signals"]

INLINE_BUDGET = 400


def inline_signals(
    node: ir.Expr, signals: Mapping[str, ir.Expr], budget: int = INLINE_BUDGET
) -> ir.Expr | None:
    """``node`` with every signal replaced by its definition, or ``None``.

    ``None`` when the result would read inputs or vector signals (whose values
    another component or a library decides) or exceed ``budget`` nodes.

    Examples
    --------
    >>> from hybrid.expr.printer import to_source
    >>> s = {"g": ir.Bin("*", ir.Num(2.0), ir.Var("x", "state"))}
    >>> to_source(inline_signals(ir.Var("g", "signal"), s), {"x": "x"})
    '2.0 * x'
    """
    count = 0

    def go(n: ir.Expr) -> ir.Expr | None:
        nonlocal count
        count += 1
        if count > budget:
            return None
        if isinstance(n, ir.Var):
            if n.kind == ir.SIGNAL:
                definition = signals.get(n.name)
                return None if definition is None else go(definition)
            return None if n.kind == ir.INPUT else n
        if isinstance(n, ir.Index):
            return None
        kids = ir.children(n)
        if not kids:
            return n
        new = [go(k) for k in kids]
        if any(k is None for k in new):
            return None
        done = [k for k in new if k is not None]
        if isinstance(n, ir.Call):
            return ir.Call(n.func, tuple(done), n.col)
        if isinstance(n, ir.Unary):
            return ir.Unary(n.op, done[0], n.col)
        if isinstance(n, ir.Bin):
            return ir.Bin(n.op, done[0], done[1], n.col)
        if isinstance(n, ir.Cmp):
            return ir.Cmp(n.ops, tuple(done), n.col)
        if isinstance(n, ir.BoolOp):
            return ir.BoolOp(n.op, tuple(done), n.col)
        if isinstance(n, ir.Not):
            return ir.Not(done[0], n.col)
        return n  # pragma: no cover - leaves are handled above

    return go(node)
