"""Ranges of expressions over boxes: interval evaluation of the IR for the static checks.

An expression's range over a *box* (one :class:`~hybrid.expr.interval.Interval`
per name) holds every value it can take there; evaluation is sound (see
:mod:`hybrid.expr.interval` for the outward rounding).

Conventions:

- ``0 * inf`` is taken as ``0`` (the usual rule for extended intervals);
- division by an interval containing 0 gives the whole line;
- functions outside their domain (``sqrt`` of negatives, ``log`` of
  non-positives) are evaluated on the part of the argument inside the domain;
  if no part is, the result is the whole line (unknown);
- ``sin``/``cos`` are exact up to rounding on short arguments, ``[-1, 1]`` on
  long ones; monotone functions map the ends;
- registered library functions and vector signals (``name[k]``) are unknown:
  the whole line.

Conditions are judged three-valued by :meth:`IntervalEvaluator.truth`: can the
condition be true somewhere in the box, and can it be false somewhere?
Comparisons keep their strictness (``x < 0`` cannot hold on ``[0, 5]``).

Examples
--------
>>> from hybrid.expr.parse import Scope, parse_expression
>>> scope = Scope({"x": "state", "y": "state"})
>>> box = {"x": Interval(-1.0, 2.0), "y": Interval(0.0, 3.0)}
>>> evaluate(parse_expression("x*y + 1", scope), box)
Interval(lo=-2.0, hi=7.0)
>>> can_hold(parse_expression("x > 2", scope, want="bool"), box)
False
>>> can_hold(parse_expression("x >= 2 and y < 1", scope, want="bool"), box)
True
"""

from __future__ import annotations

import math
from collections.abc import Mapping

from hybrid.expr import ir
from hybrid.expr.dependencies import evaluation_order
from hybrid.expr.function_ranges import call_range, power_range
from hybrid.expr.interval import (
    ENTIRE,
    TIME,
    Interval,
)

__all__ = ["IntervalEvaluator", "can_fail", "can_hold", "evaluate"]


# --- the evaluator ---------------------------------------------------------------------


class IntervalEvaluator:
    """Evaluates IR over a box of intervals.

    Parameters
    ----------
    box
        Interval of each state variable (and optionally of ``t`` and inputs);
        a name not in the box ranges over the whole line (``t`` over ``[0, inf)``).
    signals
        Definitions of the scalar signals in force; each is evaluated once per
        evaluator and cached. Signals not defined here (vector signals) are unknown.
    opaque
        Names of functions to treat as unknown (functions registered by libraries,
        which may shadow a built-in name).

    Examples
    --------
    >>> from hybrid.expr import ir
    >>> ev = IntervalEvaluator({"x": Interval(0.0, 1.0)}, {"s": ir.Var("x", "state")})
    >>> ev.number(ir.Bin("+", ir.Var("s", "signal"), ir.Num(1.0)))
    Interval(lo=1.0, hi=2.0)
    """

    def __init__(
        self,
        box: Mapping[str, Interval],
        signals: Mapping[str, ir.Expr] | None = None,
        *,
        opaque: frozenset[str] = frozenset(),
    ) -> None:
        self.box = box
        self.signals = signals or {}
        self.opaque = opaque
        self._cache: dict[str, Interval] = {}

    def number(self, node: ir.Expr) -> Interval:
        """The range of a numeric expression."""
        if isinstance(node, ir.Num):
            return Interval.point(node.value) if math.isfinite(node.value) else ENTIRE
        if isinstance(node, ir.Var):
            return self._var(node)
        if isinstance(node, ir.Index):
            return ENTIRE
        if isinstance(node, ir.Unary):
            return -self.number(node.operand)
        if isinstance(node, ir.Bin):
            left, right = self.number(node.left), self.number(node.right)
            if node.op == "+":
                return left + right
            if node.op == "-":
                return left - right
            if node.op == "*":
                return left * right
            if node.op == "/":
                return left / right
            if node.op == "**":
                return power_range(left, right)
            return ENTIRE
        if isinstance(node, ir.Call):
            if node.func in self.opaque:
                return ENTIRE
            return call_range(node.func, [self.number(a) for a in node.args])
        return ENTIRE

    def _var(self, node: ir.Var) -> Interval:
        if node.kind == ir.SIGNAL:
            cached = self._cache.get(node.name)
            if cached is None:
                if node.name not in self.signals:
                    return ENTIRE
                # the signals it reads first, each after those it reads: a chain of
                # definitions is evaluated in order, never as deep as it is long
                for name in evaluation_order((node.name,), self.signals, self._cache):
                    self._cache[name] = self.number(self.signals[name])
                cached = self._cache[node.name]
            return cached
        if node.kind == ir.TIME:
            return self.box.get("t", TIME)
        return self.box.get(node.name, ENTIRE)

    def truth(self, node: ir.Expr) -> tuple[bool, bool]:
        """``(can be true, can be false)`` of a condition over the box."""
        if isinstance(node, ir.BoolConst):
            return node.value, not node.value
        if isinstance(node, ir.Not):
            t, f = self.truth(node.operand)
            return f, t
        if isinstance(node, ir.BoolOp):
            parts = [self.truth(v) for v in node.values]
            if node.op == "and":
                return all(t for t, _ in parts), any(f for _, f in parts)
            return any(t for t, _ in parts), all(f for _, f in parts)
        if isinstance(node, ir.Cmp):
            values = [self.number(o) for o in node.operands]
            parts = [_compare(op, values[i], values[i + 1]) for i, op in enumerate(node.ops)]
            return all(t for t, _ in parts), any(f for _, f in parts)
        return True, True


def _compare(op: str, a: Interval, b: Interval) -> tuple[bool, bool]:
    """``(can a op b hold, can it fail)`` for some a in ``a``, b in ``b``."""
    if op == "<=":
        return a.lo <= b.hi, a.hi > b.lo
    if op == "<":
        return a.lo < b.hi, a.hi >= b.lo
    if op == ">=":
        return b.lo <= a.hi, b.hi > a.lo
    if op == ">":
        return b.lo < a.hi, b.hi >= a.lo
    meet = a.intersect(b) is not None
    same_point = a.is_point and b.is_point and a.lo == b.lo
    if op == "==":
        return meet, not same_point
    return not same_point, meet  # "!="


def evaluate(
    node: ir.Expr,
    box: Mapping[str, Interval],
    signals: Mapping[str, ir.Expr] | None = None,
) -> Interval:
    """The range of ``node`` over ``box`` (see :class:`IntervalEvaluator`)."""
    return IntervalEvaluator(box, signals).number(node)


def can_hold(
    cond: ir.Expr,
    box: Mapping[str, Interval],
    signals: Mapping[str, ir.Expr] | None = None,
) -> bool:
    """Whether ``cond`` may be true somewhere in ``box`` (``False`` is a proof it never is)."""
    return IntervalEvaluator(box, signals).truth(cond)[0]


def can_fail(
    cond: ir.Expr,
    box: Mapping[str, Interval],
    signals: Mapping[str, ir.Expr] | None = None,
) -> bool:
    """Whether ``cond`` may be false somewhere in ``box``."""
    return IntervalEvaluator(box, signals).truth(cond)[1]
