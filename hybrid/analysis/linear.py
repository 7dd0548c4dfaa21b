"""Affine forms of expressions, and exact satisfiability of linear constraints.

A comparison whose sides are affine in the variables (state, ``t``, inputs)
becomes one row of a linear program; :func:`lp_feasible` decides a
conjunction of such rows within the box bounds with
:func:`scipy.optimize.linprog` (HiGHS). Strict inequalities are decided with
a slack variable ``s``: maximise ``s`` subject to ``a.x + s <= b`` for every
strict row (rows scaled to unit largest coefficient); the strict system is
satisfiable iff the optimum exceeds :data:`STRICT_MARGIN`.

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
>>> lp_feasible(rows, lin.bounds(box))
False
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from hybrid.expr import ir
from hybrid.expr.functions import BUILTINS
from hybrid.expr.interval import ENTIRE, Interval
from hybrid.expr.ranges import IntervalEvaluator

__all__ = ["STRICT_MARGIN", "Affine", "Linearizer", "Row", "lp_feasible", "structural_key"]

STRICT_MARGIN = 1e-6
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
                definition = self.evaluator.signals.get(node.name)
                cached = self._opaque(node) if definition is None else self.affine(definition)
                self._signals[node.name] = cached
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


def lp_feasible(rows: Sequence[Row], bounds: Mapping[str, Interval]) -> bool:
    """Whether some point within ``bounds`` satisfies every row.

    Strict rows need a margin of :data:`STRICT_MARGIN` (rows scaled to unit
    largest coefficient). When the solver fails, the answer is ``True``
    (conservative: "may hold").

    Examples
    --------
    >>> x = Affine({"x": 1.0}, 0.0)
    >>> box = {"x": Interval(0.0, 1.0)}
    >>> lp_feasible([Row(x, "<=")], box), lp_feasible([Row(x, "<")], box)
    (True, False)
    """
    if any(not math.isfinite(c) for row in rows for c in row.form.coeffs.values()):
        return True  # a coefficient overflowed: no exact answer, lean to "may hold"
    variables = sorted({v for row in rows for v in row.form.coeffs})
    if not variables:
        return all(_constant_holds(row) for row in rows)
    index = {v: k for k, v in enumerate(variables)}
    strict = any(row.op == "<" for row in rows)
    width = len(variables) + (1 if strict else 0)
    a_ub: list[np.ndarray] = []
    b_ub: list[float] = []
    a_eq: list[np.ndarray] = []
    b_eq: list[float] = []
    for row in rows:
        if not row.form.coeffs:
            if not _constant_holds(row):
                return False
            continue
        scale = max(abs(c) for c in row.form.coeffs.values())
        line = np.zeros(width)
        for v, c in row.form.coeffs.items():
            line[index[v]] = c / scale
        rhs = -row.form.const / scale
        if not math.isfinite(rhs):
            return True
        if row.op == "==":
            a_eq.append(line)
            b_eq.append(rhs)
            continue
        if row.op == "<":
            line[-1] = 1.0
        a_ub.append(line)
        b_ub.append(rhs)
    lp_bounds: list[tuple[float | None, float | None]] = []
    for v in variables:
        interval = bounds.get(v, ENTIRE)
        lp_bounds.append(
            (
                interval.lo if math.isfinite(interval.lo) else None,
                interval.hi if math.isfinite(interval.hi) else None,
            )
        )
    objective = np.zeros(width)
    if strict:
        lp_bounds.append((0.0, 1.0))
        objective[-1] = -1.0
    from scipy.optimize import linprog  # imported on first use: it is slow to import

    try:
        result = linprog(
            objective,
            A_ub=np.array(a_ub) if a_ub else None,
            b_ub=np.array(b_ub) if b_ub else None,
            A_eq=np.array(a_eq) if a_eq else None,
            b_eq=np.array(b_eq) if b_eq else None,
            bounds=lp_bounds,
            method="highs",
        )
    except ValueError:  # the solver refused the problem (badly scaled); lean to "may hold"
        return True
    if result.status == 2:
        return False
    if result.status != 0:
        return True
    return not strict or -float(result.fun) > STRICT_MARGIN


def _constant_holds(row: Row) -> bool:
    k = row.form.const
    if row.op == "<=":
        return k <= 0.0
    if row.op == "<":
        return k < 0.0
    return k == 0.0
