"""Ranges of the built-in functions and of ``**`` over intervals: one cohesive table.

Each function maps argument intervals to an interval holding every value it
takes there, rounded outward; outside a function's domain only the part of
the argument inside it counts, and no part gives the whole line.

Examples
--------
>>> call_range("sqrt", [Interval(-4.0, 4.0)])
Interval(lo=0.0, hi=2.0)
>>> call_range("sin", [Interval(0.0, 10.0)])
Interval(lo=-1.0, hi=1.0)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from fractions import Fraction

from hybrid.expr.interval import (
    ENTIRE,
    INF,
    LARGEST,
    Interval,
    RoundingError,
    rational_sign,
    round_down,
    round_up,
    widen,
)

__all__ = ["call_range", "power_range"]


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
    lo = -INF if math.isnan(a) else LARGEST if a == INF else a
    hi = INF if math.isnan(b) else -LARGEST if b == -INF else b
    return widen(lo, hi, lo_exact=a_exact, hi_exact=b_exact)


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
    result = widen(lo, hi, ulps=4, lo_exact=lo_exact, hi_exact=hi_exact)
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
    return Fraction(value) if math.isfinite(value) else Fraction(LARGEST)


def _log(fn: Callable[[float], float], x: Interval) -> Interval:
    part = _clip_domain(x, 0.0, INF)
    if part is None or part.hi == 0.0:
        return ENTIRE
    lo = -INF if part.lo == 0.0 else fn(part.lo)
    hi = fn(part.hi) if math.isfinite(part.hi) else INF
    return widen(lo, hi, lo_exact=part.lo == 1.0, hi_exact=part.hi == 1.0)


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


def power_range(base: Interval, exponent: Interval) -> Interval:
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
    return widen(min(values), max(values))


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
    def one(x: float) -> tuple[float, RoundingError]:
        try:
            value = float(x**n)
        except OverflowError:
            return (math.copysign(INF, x) if n % 2 else INF), 0
        if math.isfinite(x) and math.isfinite(value) and n <= 64:
            return value, rational_sign(Fraction(x) ** n, value)
        return value, None if math.isfinite(value) else 0

    a, b = one(lo), one(hi)
    return Interval(round_down(*a), round_up(*b))


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
        return widen(min(corners), max(corners))
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


def call_range(name: str, args: list[Interval]) -> Interval:
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
