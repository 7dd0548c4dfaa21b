"""Kernel source: the built-in functions of the expression language, with Python's failures.

The reference engine runs expressions as Python, where ``sqrt(-1)``,
``log(0)``, ``1 / 0``, an overflowing ``exp`` or ``**`` raise, and the
simulator turns the raise into a named failure (:mod:`hybrid.expr.codegen`).
Compiled code does not raise; here every such case gives NaN instead, and NaN
propagates through every helper (``min``, ``max``, ``sign``, ``clip`` too), so
a failure anywhere in an arithmetic expression makes its value NaN, which the
compiled loop reads as the failure. The rule, for calls, ``/`` and ``**``: a
non-finite result from finite arguments is a failure (Python's
``ValueError``/``OverflowError``/``ZeroDivisionError``).

This module is copied into every generated model module (everything below
the ``kernel`` marker); it imports no numba and runs as plain Python too.

Examples
--------
>>> h_sqrt(-1.0), h_div(1.0, 0.0), h_log(0.0), h_min(1.0, float("nan"))
(nan, nan, nan, nan)
>>> h_pow(2.0, 10.0), h_clip(5.0, 0.0, 1.0), h_sign(-3.0)
(1024.0, 1.0, -1.0)
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "h_abs",
    "h_acos",
    "h_asin",
    "h_atan",
    "h_atan2",
    "h_ceil",
    "h_checked",
    "h_clip",
    "h_cos",
    "h_cosh",
    "h_cube",
    "h_div",
    "h_exp",
    "h_floor",
    "h_hypot",
    "h_level_side",
    "h_log",
    "h_log10",
    "h_max",
    "h_min",
    "h_pow",
    "h_sign",
    "h_sin",
    "h_sinh",
    "h_sq",
    "h_sqrt",
    "h_tan",
    "h_tanh",
]

# --- kernel ---


def h_checked(r: float, a: float) -> float:
    """``r`` unless it is non-finite while the argument ``a`` is finite (then NaN)."""
    if math.isfinite(r) or not math.isfinite(a):
        return r
    return math.nan


def h_div(a: float, b: float) -> float:
    if b == 0.0:
        return math.nan
    return a / b


def h_pow(a: float, b: float) -> float:
    r = math.pow(a, b)
    if math.isfinite(r) or not (math.isfinite(a) and math.isfinite(b)):
        return r
    return math.nan


def h_sq(a: float) -> float:
    return h_checked(a * a, a)


def h_cube(a: float) -> float:
    return h_checked(a * a * a, a)


def h_sin(a: float) -> float:
    return h_checked(math.sin(a), a)


def h_cos(a: float) -> float:
    return h_checked(math.cos(a), a)


def h_tan(a: float) -> float:
    return h_checked(math.tan(a), a)


def h_asin(a: float) -> float:
    if a > 1.0 or a < -1.0:
        return math.nan
    return math.asin(a)


def h_acos(a: float) -> float:
    if a > 1.0 or a < -1.0:
        return math.nan
    return math.acos(a)


def h_atan(a: float) -> float:
    return math.atan(a)


def h_atan2(a: float, b: float) -> float:
    return math.atan2(a, b)


def h_sinh(a: float) -> float:
    return h_checked(math.sinh(a), a)


def h_cosh(a: float) -> float:
    return h_checked(math.cosh(a), a)


def h_tanh(a: float) -> float:
    return math.tanh(a)


def h_exp(a: float) -> float:
    return h_checked(math.exp(a), a)


def h_log(a: float) -> float:
    if a <= 0.0:
        return math.nan
    return math.log(a)


def h_log10(a: float) -> float:
    if a <= 0.0:
        return math.nan
    return math.log10(a)


def h_sqrt(a: float) -> float:
    if a < 0.0:
        return math.nan
    return math.sqrt(a)


def h_abs(a: float) -> float:
    return abs(a)


def h_min(a: float, b: float) -> float:
    if a != a or b != b:
        return math.nan
    return b if b < a else a


def h_max(a: float, b: float) -> float:
    if a != a or b != b:
        return math.nan
    return b if b > a else a


def h_floor(a: float) -> float:
    return float(np.floor(a))


def h_ceil(a: float) -> float:
    return float(np.ceil(a))


def h_level_side(s: float, d: float) -> float:
    """An oriented level atom's rho: ``s * d`` (``s`` = 1 or -1, the side it was on), ``|d|`` on it (0)."""
    if s != 0.0:
        return s * d
    return abs(d)


def h_sign(a: float) -> float:
    if a > 0.0:
        return 1.0
    if a < 0.0:
        return -1.0
    if a != a:
        return math.nan
    return 0.0


def h_clip(a: float, lo: float, hi: float) -> float:
    if a != a or lo != lo or hi != hi:
        return math.nan
    if a < lo:
        return lo
    if a > hi:
        return hi
    return a


def h_hypot(a: float, b: float) -> float:
    return math.hypot(a, b)
