"""Affine forms of expressions, and exact satisfiability of linear constraints.

A comparison whose sides are affine in the variables (state, ``t``, inputs)
becomes one row of a linear program; :func:`hybrid.analysis.lp.lp_feasible`
decides a conjunction of such rows within the box bounds, strictness exactly.

A sub-expression that is not affine (``x*y``, ``sin(x)``, a vector signal) is
replaced by an auxiliary variable bounded by its interval over the box, and the
same sub-expression always gets the same variable. The result is an
over-approximation: a verdict "infeasible" is a proof.

Examples
--------
>>> from hybrid.expr.parse import Scope, parse_expression
>>> from hybrid.expr.interval import Interval
>>> from hybrid.expr.ranges import IntervalEvaluator
>>> scope = Scope({"x": "state", "y": "state"})
>>> box = {"x": Interval(0.0, 10.0), "y": Interval(0.0, 10.0)}
>>> lin = Linearizer(IntervalEvaluator(box))
>>> rows = lin.atom(parse_expression("x + y >= 12", scope, want="bool"))
>>> rows += lin.atom(parse_expression("x - y > 9", scope, want="bool"))
>>> from hybrid.analysis.lp import lp_feasible
>>> lp_feasible(rows, lin.bounds(box))
False
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

from hybrid.expr import ir
from hybrid.expr.dependencies import evaluation_order
from hybrid.expr.functions import BUILTINS
from hybrid.expr.interval import Interval
from hybrid.expr.ranges import IntervalEvaluator

__all__ = ["Affine", "Linearizer", "Row", "structural_key"]

_TIME = Interval(0.0, math.inf)


@dataclass(frozen=True)
class Affine:
    """``sum(coeffs[v] * v) + const``.

    Examples
    --------
    >>> (Affine({"x": 2.0}, 1.0) - Affine({"x": 2.0, "y": 1.0}, 0.0)).coeffs
    {'y': -1.0}
    """

    coeffs: Mapping[str, float] = field(default_factory=dict)
    const: float = 0.0

    @property
    def is_constant(self) -> bool:
        return not self.coeffs

    def scaled(self, k: float) -> Affine:
        if k == 0.0:
            return Affine({}, 0.0)
        return Affine({v: c * k for v, c in self.coeffs.items()}, self.const * k)

    def __add__(self, other: Affine) -> Affine:
        coeffs = dict(self.coeffs)
        for v, c in other.coeffs.items():
            total = coeffs.get(v, 0.0) + c
            if total == 0.0:
                coeffs.pop(v, None)
            else:
                coeffs[v] = total
        return Affine(coeffs, self.const + other.const)

    def __sub__(self, other: Affine) -> Affine:
        return self + other.scaled(-1.0)


@dataclass(frozen=True)
class Row:
    """One linear constraint ``form op 0`` with ``op`` in ``<=``, ``<``, ``==``."""

    form: Affine
    op: str


def structural_key(node: ir.Expr) -> tuple[object, ...]:
    """A hashable key of ``node`` that ignores source columns.

    Examples
    --------
    >>> structural_key(ir.Var("x", "state", 3)) == structural_key(ir.Var("x", "state", 9))
    True
    """
    if isinstance(node, ir.Num):
        return ("num", node.value)
    if isinstance(node, ir.BoolConst):
        return ("bool", node.value)
    if isinstance(node, ir.Var):
        return ("var", node.name, node.kind)
    if isinstance(node, ir.Index):
        return ("index", node.name, node.index)
    if isinstance(node, ir.Call):
        return ("call", node.func, *(structural_key(a) for a in node.args))
    if isinstance(node, ir.Unary):
        return ("unary", node.op, structural_key(node.operand))
    if isinstance(node, ir.Bin):
        return ("bin", node.op, structural_key(node.left), structural_key(node.right))
    if isinstance(node, ir.Cmp):
        return ("cmp", node.ops, *(structural_key(o) for o in node.operands))
    if isinstance(node, ir.BoolOp):
        return ("boolop", node.op, *(structural_key(v) for v in node.values))
    return ("not", structural_key(node.operand))


class Linearizer:
    """Turns comparisons into :class:`Row` s, inventing bounded variables for non-affine terms.

    Variables are state names, ``t`` and input names; auxiliary ones are named
    ``#0``, ``#1``, ... and bounded by the interval of the term they stand for.
    Signal definitions are read from the evaluator (and linearised once each).
    """

    def __init__(self, evaluator: IntervalEvaluator) -> None:
        self.evaluator = evaluator
        self.aux: dict[tuple[object, ...], tuple[str, Interval]] = {}
        self._signals: dict[str, Affine] = {}

    def affine(self, node: ir.Expr) -> Affine:
        """The affine form of a numeric expression (exact where it is affine)."""
        if isinstance(node, ir.Num):
            return Affine({}, node.value) if math.isfinite(node.value) else self._opaque(node)
        if isinstance(node, ir.Var):
            return self._var(node)
        if isinstance(node, ir.Unary):
            return self.affine(node.operand).scaled(-1.0)
        if isinstance(node, ir.Bin):
            return self._bin(node)
        if isinstance(node, ir.Call):
            return self._call(node)
        return self._opaque(node)

    def atom(self, cmp: ir.Expr) -> list[Row]:
        """Rows for a comparison (chains give one row per link, ``!=`` none: not convex)."""
        if not isinstance(cmp, ir.Cmp):
            return []
        rows: list[Row] = []
        forms = [self.affine(o) for o in cmp.operands]
        for i, op in enumerate(cmp.ops):
            a, b = forms[i], forms[i + 1]
            if op in ("<", "<="):
                rows.append(Row(a - b, op))
            elif op in (">", ">="):
                rows.append(Row(b - a, "<" if op == ">" else "<="))
            elif op == "==":
                rows.append(Row(a - b, "=="))
        return rows

    def bounds(self, box: Mapping[str, Interval]) -> dict[str, Interval]:
        """Bounds of every variable met so far: the box, ``t >= 0``, the auxiliaries."""
        result = dict(box)
        result.setdefault("t", _TIME)
        for name, interval in self.aux.values():
            result[name] = interval
        return result

    def _var(self, node: ir.Var) -> Affine:
        if node.kind == ir.SIGNAL:
            cached = self._signals.get(node.name)
            if cached is None:
                definitions = self.evaluator.signals
                if node.name not in definitions:
                    cached = self._signals[node.name] = self._opaque(node)
                    return cached
                # the signals it reads first, each after those it reads (as the
                # evaluator does): a chain is linearised in order, not recursively
                for name in evaluation_order((node.name,), definitions, self._signals):
                    self._signals[name] = self.affine(definitions[name])
                cached = self._signals[node.name]
            return cached
        if node.kind == ir.TIME:
            return Affine({"t": 1.0}, 0.0)
        if node.kind in (ir.STATE, ir.INPUT):
            return Affine({node.name: 1.0}, 0.0)
        return self._opaque(node)

    def _bin(self, node: ir.Bin) -> Affine:
        left, right = self.affine(node.left), self.affine(node.right)
        if node.op == "+":
            return left + right
        if node.op == "-":
            return left - right
        if node.op == "*":
            if left.is_constant:
                return right.scaled(left.const)
            if right.is_constant:
                return left.scaled(right.const)
        elif node.op == "/":
            if right.is_constant and right.const != 0.0:
                return left.scaled(1.0 / right.const)
        elif node.op == "**" and left.is_constant and right.is_constant:
            value = _power(left.const, right.const)
            if value is not None:
                return Affine({}, value)
        elif node.op == "**" and right.is_constant and right.const in (0.0, 1.0):
            return left if right.const == 1.0 else Affine({}, 1.0)  # x ** 1, x ** 0 (0 ** 0 is 1)
        return self._opaque(node)

    def _call(self, node: ir.Call) -> Affine:
        func = BUILTINS.get(node.func)
        if func is not None and node.func not in self.evaluator.opaque:
            args = [self.affine(a) for a in node.args]
            if all(a.is_constant for a in args):
                try:
                    value = float(func.fn(*(a.const for a in args)))
                except (ArithmeticError, ValueError, TypeError):
                    value = math.nan
                if math.isfinite(value):
                    return Affine({}, value)
        return self._opaque(node)

    def _opaque(self, node: ir.Expr) -> Affine:
        key = structural_key(node)
        found = self.aux.get(key)
        if found is None:
            found = (f"#{len(self.aux)}", self.evaluator.number(node))
            self.aux[key] = found
        name, interval = found
        if interval.is_point and math.isfinite(interval.lo):
            return Affine({}, interval.lo)
        return Affine({name: 1.0}, 0.0)


def _power(base: float, exponent: float) -> float | None:
    try:
        value = base**exponent
    except (ArithmeticError, ValueError):
        return None
    if isinstance(value, complex):
        return None
    value = float(value)
    return value if math.isfinite(value) else None
