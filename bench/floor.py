"""The floor: a minimal hand-written numba loop every compiled row is measured against.

Dormand–Prince 5(4) with scipy's tableau (``RK45.A``, ``B``, ``C``, ``E``,
``P``), its step control (``SAFETY`` 0.9, factors in [0.2, 10], no growth
right after a rejection) and its initial step; the compiled backend's event
rule (each accepted step sampled on its interpolant at
``max(4, ceil(h / s))`` points, ``s = (t_end - t_start) / 1000``; the first
sample at or below zero located by Brent's method, ``4 eps`` absolute and
relative, an exact 0 counting as below; a watch that starts at or below zero
armed once a sample is above it); a warm start after a jump (the last full
step's size); the end at ``max_jumps`` as hybrid's (the run flows on after
its last jump to the next event, locates and records it, and ends there
without taking it: ``max_jumps`` jumps, ``max_jumps + 1`` stays). The
right-hand side, watch and reset of the bouncing ball and of the thermostat
are written by hand, so the loop calls no function pointer
and nothing is generated: what a model written once in numba costs, points and
jumps recorded in preallocated arrays.

:func:`single` runs one model once (a Python call into the loop);
:func:`ensemble` runs many initial temperatures of the thermostat on every
core (``prange``). Both are compiled on first use (``cache=True``).
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray
from scipy.integrate._ivp.rk import RK45

__all__ = ["BALL", "THERMOSTAT", "ensemble", "single"]

_A = np.ascontiguousarray(RK45.A, dtype=np.float64)
_B = np.ascontiguousarray(RK45.B, dtype=np.float64)
_C = np.ascontiguousarray(RK45.C, dtype=np.float64)
_E = np.ascontiguousarray(RK45.E, dtype=np.float64)
_P = np.ascontiguousarray(RK45.P, dtype=np.float64)

BALL = 0
"""The bouncing ball: ``h' = v, v' = -g``; at ``h <= 0``: ``h := 0, v := -e v``. ``p = (g, e)``."""
THERMOSTAT = 1
"""The thermostat: ``p = (a, T_out, T_heat, T_low, T_high)``, mode 0 off, 1 on."""

_JIT = {"cache": True, "nogil": True, "error_model": "numpy", "fastmath": False}


@numba.njit(**_JIT)
def _rhs(kind: int, m: int, y: Any, p: Any, out: Any) -> None:
    if kind == BALL:
        out[0] = y[1]
        out[1] = -p[0]
    elif m == 0:
        out[0] = -p[0] * (y[0] - p[1])
    else:
        out[0] = p[0] * (p[2] - y[0])


@numba.njit(**_JIT)
def _watch(kind: int, m: int, y: Any, p: Any) -> float:
    """The guard's margin: it holds at or below zero."""
    if kind == BALL:
        return y[0]
    if m == 0:
        return y[0] - p[3]
    return p[4] - y[0]


@numba.njit(**_JIT)
def _reset(kind: int, m: int, y: Any, p: Any) -> int:
    if kind == BALL:
        y[0] = 0.0
        y[1] = -p[1] * y[1]
        return 0
    return 1 - m


@numba.njit(**_JIT)
def _dense(t: float, t_old: float, h: float, y_old: Any, q: Any, out: Any) -> None:
    """scipy's ``RkDenseOutput``: ``y_old + h Q (x, x^2, x^3, x^4)``."""
    x = (t - t_old) / h
    x2 = x * x
    x3 = x2 * x
    x4 = x3 * x
    for i in range(y_old.size):
        out[i] = y_old[i] + h * (q[i, 0] * x + q[i, 1] * x2 + q[i, 2] * x3 + q[i, 3] * x4)


@numba.njit(**_JIT)
def _at(kind: int, m: int, t: float, t_old: float, h: float, y_old: Any, q: Any, p: Any,
        tmp: Any) -> float:  # fmt: skip
    _dense(t, t_old, h, y_old, q, tmp)
    w = _watch(kind, m, tmp, p)
    return -5e-324 if w == 0.0 else w


@numba.njit(**_JIT)
def _brent(kind: int, m: int, xa: float, xb: float, fa: float, fb: float, t_old: float, h: float,
           y_old: Any, q: Any, p: Any, tmp: Any) -> float:  # fmt: skip
    """scipy's ``brentq`` (its C code) on the interpolant, ``xtol = rtol = 4 eps``."""
    xtol = rtol = 4.0 * np.finfo(np.float64).eps
    xpre, xcur, fpre, fcur = xa, xb, fa, fb
    xblk = fblk = spre = scur = 0.0
    for _ in range(100):
        if fpre != 0.0 and fcur != 0.0 and (fpre > 0.0) != (fcur > 0.0):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2.0
        sbis = (xblk - xcur) / 2.0
        if fcur == 0.0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2.0 * abs(stry) < min(abs(spre), 3.0 * abs(sbis) - delta):
                spre, scur = scur, stry
            else:
                spre, scur = sbis, sbis
        else:
            spre, scur = sbis, sbis
        xpre, fpre = xcur, fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0.0 else -delta
        fcur = _at(kind, m, xcur, t_old, h, y_old, q, p, tmp)
    return xcur


@numba.njit(**_JIT)
def _norm(v: Any) -> float:
    s = 0.0
    for i in range(v.size):
        s += v[i] * v[i]
    return math.sqrt(s / v.size)


@numba.njit(**_JIT)
def _initial_step(kind: int, m: int, t0: float, y0: Any, f0: Any, t_end: float, p: Any,
                  rtol: float, atol: float, y1: Any, f1: Any, sc: Any) -> float:  # fmt: skip
    """scipy's ``select_initial_step`` for order 4."""
    interval = t_end - t0
    if interval == 0.0:
        return 0.0
    for i in range(y0.size):
        sc[i] = y0[i] / (atol + abs(y0[i]) * rtol)
    d0 = _norm(sc)
    for i in range(y0.size):
        sc[i] = f0[i] / (atol + abs(y0[i]) * rtol)
    d1 = _norm(sc)
    h0 = 1e-6 if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    h0 = min(h0, interval)
    for i in range(y0.size):
        y1[i] = y0[i] + h0 * f0[i]
    _rhs(kind, m, y1, p, f1)
    for i in range(y0.size):
        sc[i] = (f1[i] - f0[i]) / (atol + abs(y0[i]) * rtol)
    d2 = _norm(sc) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 5.0)
    return min(100.0 * h0, h1, interval)


@numba.njit(**_JIT)
def _simulate(kind: int, p: Any, x0: Any, m0: int, t_start: float, t_end: float, rtol: float,
              atol: float, max_jumps: int, pts: Any, jps: Any, A: Any, B: Any, C: Any, E: Any,
              P: Any) -> tuple[int, int]:  # fmt: skip
    """One run: points ``(t, x...)`` into ``pts``, jumps ``(t, before..., after...)`` into ``jps``.

    Returns the numbers of points and jumps recorded (a full ``pts`` ends the run).
    After ``max_jumps`` jumps the run ends at the next event, its point the last.
    """
    d = x0.size
    y = x0.copy()
    f = np.empty(d)
    y_new = np.empty(d)
    tmp = np.empty(d)
    sc = np.empty(d)
    K = np.empty((7, d))
    q = np.empty((d, 4))
    spacing = (t_end - t_start) / 1000.0
    m = m0
    t = t_start
    warm = 0.0
    n_pts = n_jps = 0
    pts[0, 0] = t
    pts[0, 1 : 1 + d] = y
    n_pts = 1
    while True:  # one stay
        _rhs(kind, m, y, p, f)
        if warm > 0.0:
            h_abs = min(warm, t_end - t)
        else:
            h_abs = _initial_step(kind, m, t, y, f, t_end, p, rtol, atol, y_new, tmp, sc)
        w_prev = _watch(kind, m, y, p)
        t_prev = t
        armed = w_prev > 0.0
        while True:  # one step
            rejected = False
            while True:
                min_step = 10.0 * abs(np.nextafter(t, np.inf) - t)
                if h_abs < min_step:
                    return n_pts, n_jps  # the step size collapsed
                h = h_abs
                t_new = t + h
                if t_new - t_end > 0.0:
                    t_new = t_end
                h = t_new - t
                h_abs = abs(h)
                for i in range(d):
                    K[0, i] = f[i]
                for s in range(1, 6):
                    for i in range(d):
                        dy = 0.0
                        for r in range(s):
                            dy += A[s, r] * K[r, i]
                        tmp[i] = y[i] + h * dy
                    _rhs(kind, m, tmp, p, K[s])
                for i in range(d):
                    acc = 0.0
                    for r in range(6):
                        acc += B[r] * K[r, i]
                    y_new[i] = y[i] + h * acc
                _rhs(kind, m, y_new, p, K[6])
                err = 0.0
                for i in range(d):
                    e = 0.0
                    for r in range(7):
                        e += K[r, i] * E[r]
                    scale = atol + max(abs(y[i]), abs(y_new[i])) * rtol
                    err += (e * h / scale) ** 2
                err = math.sqrt(err / d)
                if err < 1.0:
                    factor = 10.0 if err == 0.0 else min(10.0, 0.9 * err ** (-1.0 / 5.0))
                    if rejected:
                        factor = min(1.0, factor)
                    h_abs *= factor
                    break
                h_abs *= max(0.2, 0.9 * err ** (-1.0 / 5.0))
                rejected = True
            for i in range(d):  # the interpolant's coefficients, Q = K^T P
                for c in range(4):
                    acc = 0.0
                    for r in range(7):
                        acc += K[r, i] * P[r, c]
                    q[i, c] = acc
            samples = max(4, math.ceil(h / spacing))
            event = -1.0
            for k in range(1, samples + 1):
                tk = t + k * h / samples if k < samples else t_new
                if k < samples:
                    _dense(tk, t, h, y, q, tmp)
                    w = _watch(kind, m, tmp, p)
                else:
                    w = _watch(kind, m, y_new, p)
                if armed and w <= 0.0:
                    wz = -5e-324 if w == 0.0 else w
                    event = _brent(kind, m, t_prev, tk, w_prev, wz, t, h, y, q, p, tmp)
                    break
                if w > 0.0:
                    armed = True
                t_prev, w_prev = tk, w
            if event >= 0.0:
                _dense(event, t, h, y, q, y_new)
                if n_pts == pts.shape[0]:
                    return n_pts, n_jps
                pts[n_pts, 0] = event
                pts[n_pts, 1 : 1 + d] = y_new
                n_pts += 1
                if n_jps >= max_jumps:  # hybrid's max_jumps: located, not taken
                    return n_pts, n_jps
                jps[n_jps, 0] = event
                jps[n_jps, 1 : 1 + d] = y_new
                m = _reset(kind, m, y_new, p)
                jps[n_jps, 1 + d : 1 + 2 * d] = y_new
                n_jps += 1
                for i in range(d):
                    y[i] = y_new[i]
                t = event
                break
            if n_pts == pts.shape[0]:
                return n_pts, n_jps
            pts[n_pts, 0] = t_new
            pts[n_pts, 1 : 1 + d] = y_new
            n_pts += 1
            if t_new >= t_end:
                return n_pts, n_jps
            warm = h
            for i in range(d):
                y[i] = y_new[i]
                f[i] = K[6, i]
            t = t_new


def single(kind: int, p: NDArray[np.float64], x0: NDArray[np.float64], t_end: float,
           max_jumps: int, rtol: float = 1e-10, atol: float = 1e-12,
           points: int = 4096) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # fmt: skip
    """One run: ``(points, jumps)``, rows ``(t, x...)`` and ``(t, before..., after...)``.

    Examples
    --------
    >>> import numpy as np
    >>> pts, jps = single(THERMOSTAT, np.array([0.1, 10.0, 30.0, 18.0, 22.0]),
    ...                   np.array([20.0]), t_end=1e4, max_jumps=2)
    >>> round(float(jps[0, 0]), 9) == round(10 * np.log(10 / 8), 9)
    True
    """
    d = x0.size
    pts = np.empty((points, 1 + d))
    jps = np.empty((max_jumps, 1 + 2 * d))
    n, j = _simulate(
        kind, p, x0, 0, 0.0, t_end, rtol, atol, max_jumps, pts, jps, _A, _B, _C, _E, _P
    )
    return pts[:n], jps[:j]


@numba.njit(parallel=True, **_JIT)
def _many(p: Any, x0s: Any, t_end: float, rtol: float, atol: float, max_jumps: int,
          points: int, A: Any, B: Any, C: Any, E: Any, P: Any) -> tuple[Any, Any]:  # fmt: skip
    n = x0s.shape[0]
    times = np.full((n, max_jumps), np.nan)
    counts = np.zeros(n, dtype=np.int64)
    for r in numba.prange(n):
        pts = np.empty((points, 2))
        jps = np.empty((max_jumps, 3))
        _, j = _simulate(THERMOSTAT, p, x0s[r], 0, 0.0, t_end, rtol, atol, max_jumps,
                         pts, jps, A, B, C, E, P)  # fmt: skip
        counts[r] = j
        for k in range(j):
            times[r, k] = jps[k, 0]
    return times, counts


def ensemble(p: NDArray[np.float64], starts: NDArray[np.float64], t_end: float, max_jumps: int,
             rtol: float = 1e-10, atol: float = 1e-12,
             points: int = 4096) -> tuple[NDArray[np.float64], NDArray[np.int64]]:  # fmt: skip
    """Thermostat runs from each initial temperature in ``starts`` (every core).

    Returns the jump times (one row per run, NaN past its last jump) and the jump counts.
    """
    x0s = np.ascontiguousarray(starts, dtype=np.float64).reshape(-1, 1)
    times, counts = _many(p, x0s, t_end, rtol, atol, max_jumps, points, _A, _B, _C, _E, _P)
    return times, counts
