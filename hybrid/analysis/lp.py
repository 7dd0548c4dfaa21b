"""Exact satisfiability of a conjunction of linear rows over a box.

:func:`lp_feasible` decides the rows of :mod:`hybrid.analysis.linear` with
:func:`scipy.optimize.linprog` (HiGHS). Strict inequalities are decided
exactly, with a slack variable ``s``: maximise ``s`` subject to
``a.x + s <= b`` for every strict row (rows scaled to unit largest
coefficient); the strict system is satisfiable iff the optimum is positive.
No margin is added anywhere, and a verdict "infeasible" is given only when
the solver's dual multipliers, checked in exact rational arithmetic, prove
it (a Farkas/Motzkin certificate): the floating-point solver proposes, exact
arithmetic disposes. Anything else answers "may hold".
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from fractions import Fraction
from typing import Any

import numpy as np

from hybrid.analysis.linear import Row
from hybrid.expr.interval import ENTIRE, Interval

__all__ = ["lp_feasible"]

_TIME = Interval(0.0, math.inf)


def lp_feasible(rows: Sequence[Row], bounds: Mapping[str, Interval]) -> bool:
    """Whether some point within ``bounds`` may satisfy every row (``False`` is a proof).

    Strictness is exact: the strict rows are decided with a slack variable
    ``s`` (maximise ``s`` subject to ``a.x + s <= b`` on every strict row), and
    the system counts as unsatisfiable only when an infeasibility certificate
    (nonnegative row multipliers from the solver's duals) checks out in exact
    rational arithmetic (:func:`_certified`). Whenever the solver fails or the
    certificate does not check, the answer is ``True`` ("may hold").

    Examples
    --------
    >>> from hybrid.analysis.linear import Affine
    >>> x = Affine({"x": 1.0}, 0.0)
    >>> box = {"x": Interval(0.0, 1.0)}
    >>> lp_feasible([Row(x, "<=")], box), lp_feasible([Row(x, "<")], box)
    (True, False)
    >>> d = Affine({"x": 1.0, "y": -1.0}, 0.0)          # x - y
    >>> near = [Row(d.scaled(-1.0), "<"), Row(d - Affine({}, 1e-7), "<")]
    >>> lp_feasible(near, {"x": Interval(0.0, 1.0), "y": Interval(0.0, 1.0)})  # 0 < x - y < 1e-7
    True
    """
    if any(not math.isfinite(c) for row in rows for c in row.form.coeffs.values()):
        return True  # a coefficient overflowed: no exact answer, lean to "may hold"
    live: list[Row] = []
    for row in rows:
        if not row.form.coeffs:
            if not _constant_holds(row):
                return False
            continue
        if not math.isfinite(row.form.const):
            return True
        live.append(row)
    if not live:
        return True
    problem = _Problem(live, bounds)
    if problem.empty_box:
        return False
    try:
        if not problem.closed_feasible():
            return False
        return not problem.strict or problem.strictly_feasible()
    except ValueError:  # the solver refused the problem (badly scaled); lean to "may hold"
        return True


class _Problem:
    """One conjunction of rows over a box, in floating point for the solver and exactly."""

    def __init__(self, rows: Sequence[Row], bounds: Mapping[str, Interval]) -> None:
        self.variables = sorted({v for row in rows for v in row.form.coeffs})
        index = {v: k for k, v in enumerate(self.variables)}
        n = len(self.variables)
        self.ub: list[tuple[np.ndarray, float, bool]] = []  # (row, rhs, strict), scaled
        self.eq: list[tuple[np.ndarray, float]] = []
        self.exact_ub: list[tuple[list[Fraction], Fraction, bool]] = []
        self.exact_eq: list[tuple[list[Fraction], Fraction]] = []
        for row in rows:
            scale = max(abs(c) for c in row.form.coeffs.values())
            exact_scale = Fraction(scale)
            line = np.zeros(n)
            exact = [Fraction(0)] * n
            for v, c in row.form.coeffs.items():
                exact[index[v]] = Fraction(c) / exact_scale
                line[index[v]] = float(exact[index[v]])
            exact_rhs = -Fraction(row.form.const) / exact_scale
            if row.op == "==":
                self.eq.append((line, float(exact_rhs)))
                self.exact_eq.append((exact, exact_rhs))
            else:
                self.ub.append((line, float(exact_rhs), row.op == "<"))
                self.exact_ub.append((exact, exact_rhs, row.op == "<"))
        self.strict = any(s for _, _, s in self.ub)
        self.box: list[tuple[float, float]] = []
        self.empty_box = False
        for v in self.variables:
            interval = bounds.get(v, _TIME if v == "t" else ENTIRE)
            if interval.lo > interval.hi:
                self.empty_box = True
            self.box.append((interval.lo, interval.hi))

    def _lp_bounds(self) -> list[tuple[float | None, float | None]]:
        return [
            (lo if math.isfinite(lo) else None, hi if math.isfinite(hi) else None)
            for lo, hi in self.box
        ]

    def closed_feasible(self) -> bool:
        """Whether the rows, strict ones taken as non-strict, may hold (elastic phase one)."""
        n = len(self.variables)
        m_ub, m_eq = len(self.ub), len(self.eq)
        width = n + m_ub + 2 * m_eq  # x, one slack per inequality, two per equality
        objective = np.zeros(width)
        objective[n:] = 1.0
        a_ub = np.zeros((m_ub, width))
        b_ub = np.zeros(m_ub)
        for k, (line, rhs, _) in enumerate(self.ub):
            a_ub[k, :n] = line
            a_ub[k, n + k] = -1.0
            b_ub[k] = rhs
        a_eq = np.zeros((m_eq, width))
        b_eq = np.zeros(m_eq)
        for j, (line, rhs) in enumerate(self.eq):
            a_eq[j, :n] = line
            a_eq[j, n + m_ub + 2 * j] = -1.0
            a_eq[j, n + m_ub + 2 * j + 1] = 1.0
            b_eq[j] = rhs
        bounds = self._lp_bounds() + [(0.0, None)] * (width - n)
        result = _linprog(objective, a_ub, b_ub, a_eq, b_eq, bounds)
        if result is None or result.status != 0 or float(result.fun) <= 0.0:
            return True
        return not self._certified(result, strict_needed=False)

    def strictly_feasible(self) -> bool:
        """Whether the strict rows may hold with a positive slack (maximise the slack)."""
        n = len(self.variables)
        width = n + 1
        objective = np.zeros(width)
        objective[n] = -1.0
        a_ub = np.zeros((len(self.ub), width))
        b_ub = np.zeros(len(self.ub))
        for k, (line, rhs, strict) in enumerate(self.ub):
            a_ub[k, :n] = line
            a_ub[k, n] = 1.0 if strict else 0.0
            b_ub[k] = rhs
        a_eq = np.zeros((len(self.eq), width))
        b_eq = np.zeros(len(self.eq))
        for j, (line, rhs) in enumerate(self.eq):
            a_eq[j, :n] = line
            b_eq[j] = rhs
        bounds = [*self._lp_bounds(), (0.0, 1.0)]
        result = _linprog(objective, a_ub, b_ub, a_eq, b_eq, bounds)
        if result is None or result.status != 0 or -float(result.fun) > 0.0:
            return True
        return not self._certified(result, strict_needed=True)

    def _certified(self, result: Any, *, strict_needed: bool) -> bool:
        """Whether the solver's duals, checked exactly, prove the rows cannot all hold.

        Multipliers ``y >= 0`` (inequalities) and ``w`` (equalities) give
        ``r.x <= c`` (``<`` when a strict row has ``y > 0``) for every point
        satisfying the rows, with ``r = sum y a``, ``c = sum y b``; if the
        least value of ``r.x`` over the box exceeds ``c`` (or equals it, the
        combination being strict) no point satisfies the rows.
        """
        ineq = getattr(result, "ineqlin", None)
        eqs = getattr(result, "eqlin", None)
        y_raw = (
            [] if ineq is None or ineq.marginals is None else [-float(v) for v in ineq.marginals]
        )
        w_raw = [] if eqs is None or eqs.marginals is None else [-float(v) for v in eqs.marginals]
        if len(y_raw) != len(self.ub) or len(w_raw) != len(self.eq):
            return False
        for denominator in (None, 10**6, 10**3):
            y = [_rational(max(v, 0.0), denominator) for v in y_raw]
            w = [_rational(v, denominator) for v in w_raw]
            if self._checks(y, w, strict_needed):
                return True
        return False

    def _checks(self, y: list[Fraction], w: list[Fraction], strict_needed: bool) -> bool:
        n = len(self.variables)
        r = [Fraction(0)] * n
        c = Fraction(0)
        strict = False
        for yk, (line, rhs, is_strict) in zip(y, self.exact_ub, strict=True):
            if yk == 0:
                continue
            strict = strict or is_strict
            c += yk * rhs
            for i, a in enumerate(line):
                if a:
                    r[i] += yk * a
        for wj, (line, rhs) in zip(w, self.exact_eq, strict=True):
            if wj == 0:
                continue
            c += wj * rhs
            for i, a in enumerate(line):
                if a:
                    r[i] += wj * a
        if strict_needed and not strict:
            return False
        least = Fraction(0)
        for ri, (lo, hi) in zip(r, self.box, strict=True):
            if ri == 0:
                continue
            end = lo if ri > 0 else hi
            if not math.isfinite(end):
                return False
            least += ri * Fraction(end)
        return least > c or (strict and least == c)


def _rational(value: float, denominator: int | None) -> Fraction:
    exact = Fraction(value)
    return exact if denominator is None else exact.limit_denominator(denominator)


def _linprog(
    objective: np.ndarray,
    a_ub: np.ndarray,
    b_ub: np.ndarray,
    a_eq: np.ndarray,
    b_eq: np.ndarray,
    bounds: list[tuple[float | None, float | None]],
) -> Any:
    from scipy.optimize import linprog  # imported on first use: it is slow to import

    return linprog(
        objective,
        A_ub=a_ub if a_ub.size else None,
        b_ub=b_ub if a_ub.size else None,
        A_eq=a_eq if a_eq.size else None,
        b_eq=b_eq if a_eq.size else None,
        bounds=bounds,
        method="highs",
    )


def _constant_holds(row: Row) -> bool:
    k = row.form.const
    if row.op == "<=":
        return k <= 0.0
    if row.op == "<":
        return k < 0.0
    return k == 0.0
