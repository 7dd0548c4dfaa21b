"""Interval arithmetic over the expression IR, for the static checks.

An :class:`Interval` is a closed range ``[lo, hi]`` of floats that holds every
value an expression can take when its variables range over a *box* (one
interval per name). Evaluation is sound: results are rounded outward whenever
floating point could have rounded inward, so the true range is always inside.
Infinite ends are allowed; an interval is never empty and never NaN.

Arithmetic results are rounded outward with error-free transformations
(TwoSum, Dekker's TwoProduct) or exact rationals; :mod:`hybrid.expr.ranges`
evaluates whole expressions with it.

Examples
--------
>>> Interval(0.1, 0.1) + Interval(0.2, 0.2)   # 0.1 + 0.2 rounds up to 0.30000000000000004
Interval(lo=0.3, hi=0.30000000000000004)
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable
from dataclasses import dataclass
from fractions import Fraction

__all__ = [
    "ENTIRE",
    "INF",
    "LARGEST",
    "TIME",
    "Interval",
    "RoundingError",
    "rational_sign",
    "round_down",
    "round_up",
    "widen",
]

INF = math.inf
LARGEST = sys.float_info.max
RoundingError = int | None  # sign of (true value - rounded value); None: unknown


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
TIME = Interval(0.0, INF)


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


def rational_sign(exact: Fraction, value: float) -> int:
    rounded = Fraction(value)
    return (exact > rounded) - (exact < rounded)


def _add(a: float, b: float) -> tuple[float, RoundingError]:
    value = a + b
    if math.isnan(value) or not math.isfinite(value):
        return value, 0  # infinite ends are exact; overflow is handled by round_down/round_up
    bp = value - a
    ap = value - bp
    return value, _sgn((a - ap) + (b - bp))


def _mul(a: float, b: float) -> tuple[float, RoundingError]:
    if a == 0.0 or b == 0.0:
        return 0.0, 0
    value = a * b
    if not (math.isfinite(a) and math.isfinite(b)) or not math.isfinite(value):
        return value, 0
    if _safe_range(a, b, value):
        return value, _sgn(_product_error(a, b, value))
    return value, rational_sign(Fraction(a) * Fraction(b), value)


def _div(a: float, b: float) -> tuple[float, RoundingError]:
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
    return value, rational_sign(Fraction(a) / Fraction(b), value)


def round_down(value: float, err: RoundingError) -> float:
    """A float at or below the true value (``value`` rounded, ``err`` the sign of the error)."""
    if math.isnan(value) or value == -INF:
        return -INF
    if value == INF:  # overflow: the largest float is still below the true value
        return LARGEST
    if err is not None and err >= 0:
        return value
    return math.nextafter(value, -INF)


def round_up(value: float, err: RoundingError) -> float:
    """A float at or above the true value."""
    if math.isnan(value) or value == INF:
        return INF
    if value == -INF:
        return -LARGEST
    if err is not None and err <= 0:
        return value
    return math.nextafter(value, INF)


def _combine(
    op: Callable[[float, float], tuple[float, RoundingError]],
    low_pairs: list[tuple[float, float]],
    high_pairs: list[tuple[float, float]],
) -> Interval:
    lows = [op(a, b) for a, b in low_pairs]
    highs = lows if high_pairs is low_pairs else [op(a, b) for a, b in high_pairs]
    if any(math.isnan(v) for v, _ in lows) or any(math.isnan(v) for v, _ in highs):
        return ENTIRE
    lo = min(v for v, _ in lows)
    hi = max(v for v, _ in highs)
    return Interval(round_down(lo, _worst(lows, lo, -1)), round_up(hi, _worst(highs, hi, 1)))


def _worst(items: list[tuple[float, RoundingError]], value: float, direction: int) -> RoundingError:
    """The error sign to assume for ``value``: outward (``direction``) if any candidate is."""
    signs = [e for v, e in items if v == value]
    if any(e is None or e == direction for e in signs):
        return direction
    return 0 if all(e == 0 for e in signs) else -direction


def widen(
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
