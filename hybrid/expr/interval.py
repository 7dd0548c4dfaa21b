"""Interval arithmetic over the expression IR, for the static checks.

An :class:`Interval` is a closed range ``[lo, hi]`` of floats that holds every
value an expression can take when its variables range over a *box* (one
interval per name). Evaluation is sound: results are rounded outward whenever
floating point could have rounded inward, so the true range is always inside.
Infinite ends are allowed; an interval is never empty and never NaN.

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
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from fractions import Fraction

from hybrid.expr import ir

__all__ = [
    "ENTIRE",
    "Interval",
    "IntervalEvaluator",
    "can_fail",
    "can_hold",
    "evaluate",
]

INF = math.inf
_MAX = sys.float_info.max
_Err = int | None  # sign of (true value - rounded value); None: unknown


@dataclass(frozen=True, slots=True)
class Interval:
    """A closed interval ``[lo, hi]`` with ``lo <= hi`` (ends may be infinite).

    Examples
    --------
    >>> Interval(1.0, 2.0) + Interval(0.5, 0.5)
    Interval(lo=1.5, hi=2.5)
    >>> Interval(-1.0, 2.0) * Interval(-3.0, 1.0)
    Interval(lo=-6.0, hi=3.0)
    >>> Interval(1.0, 2.0).intersect(Interval(3.0, 4.0)) is None
    True
    """

    lo: float
    hi: float

    @staticmethod
    def point(value: float) -> Interval:
        """The interval holding one value."""
        return Interval(float(value), float(value))

    @property
    def is_point(self) -> bool:
        return self.lo == self.hi

    @property
    def is_entire(self) -> bool:
        return self.lo == -INF and self.hi == INF

    def contains(self, value: float) -> bool:
        return self.lo <= value <= self.hi

    def intersect(self, other: Interval) -> Interval | None:
        """The common part, or ``None`` if there is none."""
        lo, hi = max(self.lo, other.lo), min(self.hi, other.hi)
        return Interval(lo, hi) if lo <= hi else None

    def hull(self, other: Interval) -> Interval:
        """The smallest interval holding both."""
        return Interval(min(self.lo, other.lo), max(self.hi, other.hi))

    def __neg__(self) -> Interval:
        return Interval(-self.hi, -self.lo)

    def __add__(self, other: Interval) -> Interval:
        return _combine(_add, [(self.lo, other.lo)], [(self.hi, other.hi)])

    def __sub__(self, other: Interval) -> Interval:
        return self + (-other)

    def __mul__(self, other: Interval) -> Interval:
        corners = [(a, b) for a in (self.lo, self.hi) for b in (other.lo, other.hi)]
        return _combine(_mul, corners, corners)

    def __truediv__(self, other: Interval) -> Interval:
        if other.lo <= 0.0 <= other.hi:
            return ENTIRE
        corners = [(a, b) for a in (self.lo, self.hi) for b in (other.lo, other.hi)]
        return _combine(_div, corners, corners)

    def __repr__(self) -> str:
        return f"Interval(lo={self.lo!r}, hi={self.hi!r})"


ENTIRE = Interval(-INF, INF)
_TIME = Interval(0.0, INF)


# --- outward rounding ------------------------------------------------------------------


# Each operation returns (rounded value, sign of true - rounded): -1, 0, +1, or None when
# unknown. Error-free transformations (TwoSum, Dekker's TwoProduct) give the sign cheaply;
# far from 1 in magnitude, where they could overflow or underflow, exact rationals do.
_SPLIT = 134217729.0  # 2**27 + 1
_SAFE_BIG = 1e150
_SAFE_SMALL = 1e-140


def _sgn(x: float) -> int:
    return (x > 0) - (x < 0)


def _safe_range(*values: float) -> bool:
    return all(v == 0.0 or _SAFE_SMALL < abs(v) < _SAFE_BIG for v in values)


def _split(a: float) -> tuple[float, float]:
    c = _SPLIT * a
    hi = c - (c - a)
    return hi, a - hi


def _product_error(a: float, b: float, p: float) -> float:
    """``a * b - p`` exactly, for ``p = fl(a * b)`` (Dekker)."""
    ah, al = _split(a)
    bh, bl = _split(b)
    return ((ah * bh - p) + ah * bl + al * bh) + al * bl


def _rational_sign(exact: Fraction, value: float) -> int:
    rounded = Fraction(value)
    return (exact > rounded) - (exact < rounded)


def _add(a: float, b: float) -> tuple[float, _Err]:
    value = a + b
    if math.isnan(value) or not math.isfinite(value):
        return value, 0  # infinite ends are exact; overflow is handled by _down/_up
    bp = value - a
    ap = value - bp
    return value, _sgn((a - ap) + (b - bp))


def _mul(a: float, b: float) -> tuple[float, _Err]:
    if a == 0.0 or b == 0.0:
        return 0.0, 0
    value = a * b
    if not (math.isfinite(a) and math.isfinite(b)) or not math.isfinite(value):
        return value, 0
    if _safe_range(a, b, value):
        return value, _sgn(_product_error(a, b, value))
    return value, _rational_sign(Fraction(a) * Fraction(b), value)


def _div(a: float, b: float) -> tuple[float, _Err]:
    if a == 0.0:
        return 0.0, 0
    if math.isinf(a) and math.isinf(b):
        return math.nan, None
    if math.isinf(b):
        return 0.0, _sgn(a) * _sgn(b)
    if math.isinf(a):
        return math.copysign(INF, a) * math.copysign(1.0, b), 0
    value = a / b
    if not math.isfinite(value):
        return value, 0
    if _safe_range(a, b, value):
        p = value * b
        if _safe_range(p):
            remainder = (a - p) - _product_error(value, b, p)
            return value, _sgn(remainder) * _sgn(b)
    return value, _rational_sign(Fraction(a) / Fraction(b), value)


def _down(value: float, err: _Err) -> float:
    """A float at or below the true value (``value`` rounded, ``err`` the sign of the error)."""
    if math.isnan(value) or value == -INF:
        return -INF
    if value == INF:  # overflow: the largest float is still below the true value
        return _MAX
    if err is not None and err >= 0:
        return value
    return math.nextafter(value, -INF)


def _up(value: float, err: _Err) -> float:
    """A float at or above the true value."""
    if math.isnan(value) or value == INF:
        return INF
    if value == -INF:
        return -_MAX
    if err is not None and err <= 0:
        return value
    return math.nextafter(value, INF)


def _combine(
    op: Callable[[float, float], tuple[float, _Err]],
    low_pairs: list[tuple[float, float]],
    high_pairs: list[tuple[float, float]],
) -> Interval:
    lows = [op(a, b) for a, b in low_pairs]
    highs = lows if high_pairs is low_pairs else [op(a, b) for a, b in high_pairs]
    if any(math.isnan(v) for v, _ in lows) or any(math.isnan(v) for v, _ in highs):
        return ENTIRE
    lo = min(v for v, _ in lows)
    hi = max(v for v, _ in highs)
    return Interval(_down(lo, _worst(lows, lo, -1)), _up(hi, _worst(highs, hi, 1)))


def _worst(items: list[tuple[float, _Err]], value: float, direction: int) -> _Err:
    """The error sign to assume for ``value``: outward (``direction``) if any candidate is."""
    signs = [e for v, e in items if v == value]
    if any(e is None or e == direction for e in signs):
        return direction
    return 0 if all(e == 0 for e in signs) else -direction


def _widen(
    lo: float, hi: float, ulps: int = 2, *, lo_exact: bool = False, hi_exact: bool = False
) -> Interval:
    """Outward by a few ulps (library functions are correct to within one ulp)."""
    if math.isnan(lo) or math.isnan(hi):
        return ENTIRE
    for _ in range(ulps):
        if math.isfinite(lo) and not lo_exact:
            lo = math.nextafter(lo, -INF)
        if math.isfinite(hi) and not hi_exact:
            hi = math.nextafter(hi, INF)
    return Interval(lo, hi)


# Arguments at which a function's float result is exact (sin(0) = 0, exp(0) = 1, ...).
_EXACT_AT: dict[str, frozenset[float]] = {
    "sin": frozenset({0.0}),
    "cos": frozenset({0.0}),
    "tan": frozenset({0.0}),
    "asin": frozenset({0.0}),
    "acos": frozenset({1.0}),
    "atan": frozenset({0.0}),
    "sinh": frozenset({0.0}),
    "cosh": frozenset({0.0}),
    "tanh": frozenset({0.0}),
    "exp": frozenset({0.0}),
    "log": frozenset({1.0}),
    "log10": frozenset({1.0}),
}


# --- functions -------------------------------------------------------------------------


def _safe(fn: Callable[[float], float], x: float) -> float:
    """``fn(x)``; on overflow an infinity of the right sign, on a domain error NaN."""
    try:
        return fn(x)
    except OverflowError:
        return math.copysign(INF, x) if fn is math.sinh else INF
    except ValueError:
        return math.nan


def _monotone(
    name: str, fn: Callable[[float], float], x: Interval, *, increasing: bool = True
) -> Interval:
    """Range of a monotone ``fn``, widened except at arguments where it is exact."""
    a, b = _safe(fn, x.lo), _safe(fn, x.hi)
    exact = _EXACT_AT.get(name, frozenset())
    a_exact, b_exact = x.lo in exact, x.hi in exact
    if not increasing:
        a, b, a_exact, b_exact = b, a, b_exact, a_exact
    a_exact = a_exact or a == INF  # overflow: the largest float is already below
    b_exact = b_exact or b == -INF
    lo = -INF if math.isnan(a) else _MAX if a == INF else a
    hi = INF if math.isnan(b) else -_MAX if b == -INF else b
    return _widen(lo, hi, lo_exact=a_exact, hi_exact=b_exact)


def _periodic(fn: Callable[[float], float], x: Interval, peak: float, trough: float) -> Interval:
    """Range of ``sin`` or ``cos`` (maxima at ``peak + 2k pi``, minima at ``trough + 2k pi``)."""
    if not (math.isfinite(x.lo) and math.isfinite(x.hi)):
        return Interval(-1.0, 1.0)
    if x.hi - x.lo >= 2 * math.pi or max(abs(x.lo), abs(x.hi)) > 1e6:
        return Interval(-1.0, 1.0)
    ends = sorted([(fn(x.lo), x.lo == 0.0), (fn(x.hi), x.hi == 0.0)])
    (lo, lo_exact), (hi, hi_exact) = ends[0], ends[-1]
    if _holds_phase(x, peak):
        hi, hi_exact = 1.0, True
    if _holds_phase(x, trough):
        lo, lo_exact = -1.0, True
    result = _widen(lo, hi, ulps=4, lo_exact=lo_exact, hi_exact=hi_exact)
    return Interval(max(result.lo, -1.0), min(result.hi, 1.0))


def _holds_phase(x: Interval, base: float) -> bool:
    """Whether ``x`` may hold ``base + 2 k pi`` for an integer k (near misses count)."""
    period = 2 * math.pi
    k = math.ceil((x.lo - base) / period - 1e-9)
    return base + k * period <= x.hi + 1e-9


def _tan(x: Interval) -> Interval:
    if not (math.isfinite(x.lo) and math.isfinite(x.hi)) or x.hi - x.lo >= math.pi:
        return ENTIRE
    # poles at pi/2 + k pi
    k = math.ceil((x.lo - math.pi / 2) / math.pi - 1e-12)
    if math.pi / 2 + k * math.pi <= x.hi + 1e-12:
        return ENTIRE
    return _monotone("tan", math.tan, x)


def _clip_domain(x: Interval, lo: float, hi: float) -> Interval | None:
    return x.intersect(Interval(lo, hi))


def _sqrt(x: Interval) -> Interval:
    part = _clip_domain(x, 0.0, INF)
    if part is None:
        return ENTIRE
    lo, hi = math.sqrt(part.lo), math.sqrt(part.hi)
    lo = lo if Fraction(lo) ** 2 <= _frac(part.lo) else math.nextafter(lo, -INF)
    hi = hi if hi == INF or Fraction(hi) ** 2 >= _frac(part.hi) else math.nextafter(hi, INF)
    return Interval(max(lo, 0.0), hi)


def _frac(value: float) -> Fraction:
    return Fraction(value) if math.isfinite(value) else Fraction(_MAX)


def _log(fn: Callable[[float], float], x: Interval) -> Interval:
    part = _clip_domain(x, 0.0, INF)
    if part is None or part.hi == 0.0:
        return ENTIRE
    lo = -INF if part.lo == 0.0 else fn(part.lo)
    hi = fn(part.hi) if math.isfinite(part.hi) else INF
    return _widen(lo, hi, lo_exact=part.lo == 1.0, hi_exact=part.hi == 1.0)


def _abs(x: Interval) -> Interval:
    if x.lo >= 0.0:
        return x
    if x.hi <= 0.0:
        return -x
    return Interval(0.0, max(-x.lo, x.hi))


def _cosh(x: Interval) -> Interval:
    return _monotone("cosh", math.cosh, _abs(x))


def _floor(x: Interval) -> Interval:
    return Interval(*(float(math.floor(v)) if math.isfinite(v) else v for v in (x.lo, x.hi)))


def _ceil(x: Interval) -> Interval:
    return Interval(*(float(math.ceil(v)) if math.isfinite(v) else v for v in (x.lo, x.hi)))


def _pow(base: Interval, exponent: Interval) -> Interval:
    if exponent.is_point and float(exponent.lo).is_integer() and abs(exponent.lo) <= 1024:
        return _int_pow(base, int(exponent.lo))
    part = _clip_domain(base, 0.0, INF)
    if part is None:
        return ENTIRE
    values = []
    for b in (part.lo, part.hi):
        for e in (exponent.lo, exponent.hi):
            values.append(_real_pow(b, e))
    if any(math.isnan(v) for v in values):
        return ENTIRE
    return _widen(min(values), max(values))


def _real_pow(b: float, e: float) -> float:
    try:
        value = b**e
    except ZeroDivisionError:
        return INF
    except OverflowError:
        return INF
    return float(value) if isinstance(value, float | int) else math.nan


def _int_pow(base: Interval, n: int) -> Interval:
    if n == 0:
        return Interval(1.0, 1.0)
    if n < 0:
        return Interval(1.0, 1.0) / _int_pow(base, -n)
    if n % 2 == 0:
        mag = _abs(base)
        return _power_ends(mag.lo, mag.hi, n)
    return _power_ends(base.lo, base.hi, n)


def _power_ends(lo: float, hi: float, n: int) -> Interval:
    def one(x: float) -> tuple[float, _Err]:
        try:
            value = float(x**n)
        except OverflowError:
            return (math.copysign(INF, x) if n % 2 else INF), 0
        if math.isfinite(x) and math.isfinite(value) and n <= 64:
            return value, _rational_sign(Fraction(x) ** n, value)
        return value, None if math.isfinite(value) else 0

    a, b = one(lo), one(hi)
    return Interval(_down(*a), _up(*b))


def _minmax(args: list[Interval], pick_max: bool) -> Interval:
    if pick_max:
        return Interval(max(a.lo for a in args), max(a.hi for a in args))
    return Interval(min(a.lo for a in args), min(a.hi for a in args))


def _sign(x: Interval) -> Interval:
    def s(v: float) -> float:
        return (v > 0) - (v < 0) + 0.0

    return Interval(s(x.lo), s(x.hi))


def _hypot(args: list[Interval]) -> Interval:
    total = Interval(0.0, 0.0)
    for a in args:
        total = total + _int_pow(a, 2)
    return _sqrt(total)


def _atan2(y: Interval, x: Interval) -> Interval:
    if x.lo > 0.0:  # right half plane: atan(y / x), continuous and exact at the corners
        corners = [math.atan2(a, b) for a in (y.lo, y.hi) for b in (x.lo, x.hi)]
        return _widen(min(corners), max(corners))
    return Interval(-math.pi - 1e-15, math.pi + 1e-15)


_UNARY: dict[str, Callable[[Interval], Interval]] = {
    "sin": lambda x: _periodic(math.sin, x, math.pi / 2, -math.pi / 2),
    "cos": lambda x: _periodic(math.cos, x, 0.0, math.pi),
    "tan": _tan,
    "asin": lambda x: _domain(x, -1.0, 1.0, lambda p: _monotone("asin", math.asin, p)),
    "acos": lambda x: _domain(
        x, -1.0, 1.0, lambda p: _monotone("acos", math.acos, p, increasing=False)
    ),
    "atan": lambda x: _monotone("atan", math.atan, x),
    "sinh": lambda x: _monotone("sinh", math.sinh, x),
    "cosh": _cosh,
    "tanh": lambda x: _monotone("tanh", math.tanh, x),
    "exp": lambda x: _monotone("exp", math.exp, x),
    "log": lambda x: _log(math.log, x),
    "log10": lambda x: _log(math.log10, x),
    "sqrt": _sqrt,
    "abs": _abs,
    "floor": _floor,
    "ceil": _ceil,
    "sign": _sign,
}


def _domain(x: Interval, lo: float, hi: float, fn: Callable[[Interval], Interval]) -> Interval:
    part = _clip_domain(x, lo, hi)
    return ENTIRE if part is None else fn(part)


def _call(name: str, args: list[Interval]) -> Interval:
    if name in _UNARY and len(args) == 1:
        return _UNARY[name](args[0])
    if name == "min" and args:
        return _minmax(args, pick_max=False)
    if name == "max" and args:
        return _minmax(args, pick_max=True)
    if name == "clip" and len(args) == 3:
        x, lo, hi = args
        result = _minmax([_minmax([x, lo], pick_max=True), hi], pick_max=False)
        if x.lo < lo.hi:  # clip returns lo whenever x < lo, even when lo > hi
            result = result.hull(Interval(max(lo.lo, x.lo), lo.hi))
        return result
    if name == "hypot" and args:
        return _hypot(args)
    if name == "atan2" and len(args) == 2:
        return _atan2(args[0], args[1])
    return ENTIRE


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
                return _pow(left, right)
            return ENTIRE
        if isinstance(node, ir.Call):
            if node.func in self.opaque:
                return ENTIRE
            return _call(node.func, [self.number(a) for a in node.args])
        return ENTIRE

    def _var(self, node: ir.Var) -> Interval:
        if node.kind == ir.SIGNAL:
            cached = self._cache.get(node.name)
            if cached is None:
                definition = self.signals.get(node.name)
                cached = ENTIRE if definition is None else self.number(definition)
                self._cache[node.name] = cached
            return cached
        if node.kind == ir.TIME:
            return self.box.get("t", _TIME)
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
