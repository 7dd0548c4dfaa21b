"""Kernel source: the search of one accepted step for the first event, as :mod:`hybrid.simulation.crossing`.

The rule (docs/semantics.md, "First crossings inside a step"), function by function:

- :func:`parts` is ``crossing.parts``: a step of length ``h`` is cut into
  ``max(4, ceil(h / spacing))`` equal parts, ``spacing = (t_end - t_start) / 1000``;
- :func:`first_event` is ``crossing.first_event`` (both its paths): the watch
  at each sample in time order (the interpolant inside the step, the
  integrator's own state at its end), arming after each sample, the first
  sample at or below 0 a crossing, and before it a dip of the sampled values
  examined by :func:`dip`;
- :func:`locate` is ``crossing._locate``: ``brentq`` (scipy's C code, tolerances
  ``4 eps``, 100 iterations; a NaN, a bad bracket or no convergence keeps the
  safe end) on "at or below 0", an exact 0 counting as below (:data:`BELOW`),
  so a watch that comes down to 0 and stays there is located where it arrives;
- :func:`dip` is ``crossing._dip``: the parabola test, then the watch minimised
  between the neighbours by :func:`fminbound` (scipy's
  ``_minimize_scalar_bounded``, line for line); a minimum below 0 is a
  crossing, one of exactly 0 a touch located as a crossing, one above 0 within
  the band a touch at the minimum;
- :func:`curve_at` is ``StepCurve.at`` (exactly the step's ends at ``t0``, ``t1``).

Constants: ``SAMPLES_PER_STEP`` and ``HORIZON_SAMPLES`` are ``crossing``'s (a
test checks that they are equal).

Copied into the kernel module (below the ``kernel`` marker).
"""

from __future__ import annotations

import math

from hybrid.simulation.native.boundary import band
from hybrid.simulation.native.buffers import (
    S_B0,
    S_GEN,
    T_MODE_INV,
    T_MODE_TR,
    W_D,
    W_FAILI,
    W_INVARMED,
    W_Q,
    W_SCAL,
    W_TERMS,
    W_TRARMED,
    W_XS,
    W_Y,
    W_YNEW,
)
from hybrid.simulation.native.events import (
    arm_at,
    pending,
    watch_at,
    watch_min,
    watch_terms,
    watch_value,
)
from hybrid.simulation.native.integrator import dense_eval
from hybrid.simulation.native.kernel_types import Array, Fns, Ints

__all__ = [
    "BELOW",
    "EV_CROSSING",
    "EV_FAILED",
    "EV_NONE",
    "EV_TOUCH",
    "HORIZON_SAMPLES",
    "SAMPLES_PER_STEP",
    "curve_at",
    "dip",
    "first_event",
    "fminbound",
    "locate",
    "parts",
    "sample",
    "watch_on_curve",
]

# --- kernel ---

SAMPLES_PER_STEP = 4
HORIZON_SAMPLES = 1000
EPS = 2.220446049250313e-16
TOL = 4.0 * EPS
EV_NONE, EV_CROSSING, EV_TOUCH, EV_FAILED = 0, 1, 2, 3
BELOW = -5e-324
"""What a watch value of exactly 0 counts as while the first instant at or below 0 is bracketed."""


def parts(h: float, spacing: float) -> int:
    """How many equal parts a step of length ``h`` is cut into."""
    if not h < spacing * SAMPLES_PER_STEP:
        return max(SAMPLES_PER_STEP, math.ceil(h / spacing))
    return SAMPLES_PER_STEP


def curve_at(t: float, t0: float, t1: float, wf: Array, wi: Ints) -> None:
    """The state at ``t`` on the step ``[t0, t1]`` into ``xs`` (its ends exactly)."""
    d = wi[W_D]
    xs = wf[wi[W_XS] : wi[W_XS] + d]
    if t == t1:
        for i in range(d):
            xs[i] = wf[wi[W_YNEW] + i]
    elif t == t0:
        for i in range(d):
            xs[i] = wf[wi[W_Y] + i]
    else:
        dense_eval(t, t0, t1 - t0, wf, wi, xs)


def sample(i: int, n: int, t0: float, t1: float, wf: Array, wi: Ints) -> float:
    """Sample ``i`` of ``n`` of the step into ``xs`` (the interpolant at ``i / n``, the end exactly); its time."""
    d = wi[W_D]
    xs = wf[wi[W_XS] : wi[W_XS] + d]
    if i >= n:
        for k in range(d):
            xs[k] = wf[wi[W_YNEW] + k]
        return t1
    h = t1 - t0
    s1 = i / n
    s2 = s1 * s1
    s3 = s2 * s1
    s4 = s3 * s1
    y = wi[W_Y]
    q = wi[W_Q]
    for k in range(d):
        c = q + 4 * k
        xs[k] = h * (wf[c] * s1 + wf[c + 1] * s2 + wf[c + 2] * s3 + wf[c + 3] * s4) + wf[y + k]
    return t0 + h * i / n


def watch_on_curve(fns: Fns, tab: Ints, m: int, t: float, t0: float, t1: float, wf: Array,
                   wi: Ints) -> float:  # fmt: skip
    """The watch at ``t`` on the step's curve (the state left in ``xs``)."""
    d = wi[W_D]
    curve_at(t, t0, t1, wf, wi)
    return watch_at(fns, tab, m, t, wf[wi[W_XS] : wi[W_XS] + d], wf, wi)


def locate(fns: Fns, tab: Ints, m: int, a: float, wa: float, b: float, wb: float, t0: float,
           t1: float, wf: Array, wi: Ints) -> float:  # fmt: skip
    """The first instant in ``[a, b]`` where the watch is at or below 0 (``wa > 0 >= wb``):
    ``brentq`` on that predicate (an exact 0 counts as :data:`BELOW`), else ``b``."""
    if not (wa > 0.0 and math.isfinite(wa) and math.isfinite(wb)):
        return b
    xpre, xcur, fpre, fcur = a, b, wa, BELOW if wb == 0.0 else wb
    xblk, fblk, spre, scur = 0.0, 0.0, 0.0, 0.0
    for _ in range(100):
        if fpre != 0.0 and fcur != 0.0 and (fpre < 0.0) != (fcur < 0.0):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (TOL + TOL * abs(xcur)) / 2.0
        sbis = (xblk - xcur) / 2.0
        if fcur == 0.0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:
                stry = -fcur * (xcur - xpre) / (fcur - fpre)  # interpolate
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
        if xcur == a:
            fcur = wa
        elif xcur == b:
            fcur = wb
        else:
            fcur = watch_on_curve(fns, tab, m, xcur, t0, t1, wf, wi)
        if fcur == 0.0:
            fcur = BELOW
        if fcur != fcur:
            return b  # scipy refuses a NaN (ValueError): the safe end
    return b  # no convergence (RuntimeError): the safe end


def _phi(fns: Fns, tab: Ints, m: int, t: float, a: float, wa: float, c: float, wc: float,
         t0: float, t1: float, wf: Array, wi: Ints) -> float:  # fmt: skip
    if t == a:
        return wa
    if t == c:
        return wc
    return watch_on_curve(fns, tab, m, t, t0, t1, wf, wi)


def fminbound(fns: Fns, tab: Ints, m: int, a: float, wa: float, c: float, wc: float,
              xatol: float, t0: float, t1: float, wf: Array,
              wi: Ints) -> tuple[float, float]:  # fmt: skip
    """``(x, f(x))``: the minimum of the watch over ``[a, c]``, as ``minimize_scalar(method="bounded")``."""
    lo, hi = a, c
    sqrt_eps = math.sqrt(2.2e-16)
    golden_mean = 0.5 * (3.0 - math.sqrt(5.0))
    fulc = lo + golden_mean * (hi - lo)
    nfc, xf = fulc, fulc
    rat = 0.0
    e = 0.0
    x = xf
    fx = _phi(fns, tab, m, x, a, wa, c, wc, t0, t1, wf, wi)
    num = 1
    ffulc = fnfc = fx
    xm = 0.5 * (lo + hi)
    tol1 = sqrt_eps * abs(xf) + xatol / 3.0
    tol2 = 2.0 * tol1
    while abs(xf - xm) > (tol2 - 0.5 * (hi - lo)):
        golden = True
        if abs(e) > tol1:
            golden = False
            r = (xf - nfc) * (fx - ffulc)
            q = (xf - fulc) * (fx - fnfc)
            p = (xf - fulc) * q - (xf - nfc) * r
            q = 2.0 * (q - r)
            if q > 0.0:
                p = -p
            q = abs(q)
            r = e
            e = rat
            if abs(p) < abs(0.5 * q * r) and p > q * (lo - xf) and p < q * (hi - xf):
                rat = (p + 0.0) / q
                x = xf + rat
                if (x - lo) < tol2 or (hi - x) < tol2:
                    gap = xm - xf
                    si = (1.0 if gap > 0.0 else (-1.0 if gap < 0.0 else 0.0)) + (1.0 if gap == 0.0 else 0.0)
                    rat = tol1 * si
            else:
                golden = True
        if golden:
            e = (lo - xf) if xf >= xm else (hi - xf)
            rat = golden_mean * e
        si = (1.0 if rat > 0.0 else (-1.0 if rat < 0.0 else 0.0)) + (1.0 if rat == 0.0 else 0.0)
        x = xf + si * max(abs(rat), tol1)
        fu = _phi(fns, tab, m, x, a, wa, c, wc, t0, t1, wf, wi)
        num += 1
        if fu <= fx:
            if x >= xf:
                lo = xf
            else:
                hi = xf
            fulc, ffulc = nfc, fnfc
            nfc, fnfc = xf, fx
            xf, fx = x, fu
        else:
            if x < xf:
                lo = x
            else:
                hi = x
            if fu <= fnfc or nfc == xf:
                fulc, ffulc = nfc, fnfc
                nfc, fnfc = x, fu
            elif fu <= ffulc or fulc == xf or fulc == nfc:  # noqa: SIM109 (as scipy)
                fulc, ffulc = x, fu
        xm = 0.5 * (lo + hi)
        tol1 = sqrt_eps * abs(xf) + xatol / 3.0
        tol2 = 2.0 * tol1
        if num >= 500:
            break
    return xf, fx


def dip(fns: Fns, tab: Ints, m: int, ta: float, wa: float, tb: float, wb: float, tc: float,
        wc: float, t0: float, t1: float, wf: Array, wi: Ints) -> tuple[int, float]:  # fmt: skip
    """An event hidden in a dip of the watch around the sample ``tb``: ``(kind, t)``."""
    if not (wb <= wa and wb <= wc and (wb < wa or wb < wc)):
        return EV_NONE, math.nan
    curvature = wa - 2.0 * wb + wc
    if not curvature > 0.0:
        return EV_NONE, math.nan
    lowest = wb - (wc - wa) ** 2 / (8.0 * curvature)
    if not lowest <= 0.5 * wb:
        return EV_NONE, math.nan
    xatol = max(TOL * abs(tb), 1e-10 * (tc - ta))
    t_min, w_min = fminbound(fns, tab, m, ta, wa, tc, wc, xatol, t0, t1, wf, wi)
    if not math.isfinite(w_min):
        return EV_NONE, math.nan
    if w_min < 0.0:
        return EV_CROSSING, locate(fns, tab, m, ta, wa, t_min, w_min, t0, t1, wf, wi)
    if w_min == 0.0:  # a touch of exactly 0, or a flat zero: where the watch arrives at 0
        return EV_TOUCH, locate(fns, tab, m, ta, wa, t_min, w_min, t0, t1, wf, wi)
    d = wi[W_D]
    curve_at(t_min, t0, t1, wf, wi)
    if w_min <= band(wf[wi[W_XS] : wi[W_XS] + d]):
        return EV_TOUCH, t_min
    return EV_NONE, math.nan


def first_event(fns: Fns, tab: Ints, m: int, t0: float, t1: float, w0: float, spacing: float,
                wf: Array, wi: Ints) -> tuple[int, float, float]:  # fmt: skip
    """The first event of the watch in the step ``[t0, t1]``: ``(kind, t, watch at t1)``.

    ``kind`` is ``EV_NONE``, ``EV_CROSSING``, ``EV_TOUCH`` (at ``t``), or
    ``EV_FAILED`` (an evaluation failed; ``t`` is the last good sample). ``w0``
    is the watch at ``t0``. On an event, the state at ``t`` is in ``xs``.
    """
    d = wi[W_D]
    n = parts(t1 - t0, spacing)
    xs = wf[wi[W_XS] : wi[W_XS] + d]
    gen = wi[W_SCAL] + S_GEN
    fail = wi[W_FAILI]
    arming = pending(tab, m, wf, wi)
    terms, tr_armed, inv_armed = wi[W_TERMS], wi[W_TRARMED], wi[W_INVARMED]
    first, inv0 = tab[tab[T_MODE_TR] + m], tab[tab[T_MODE_INV] + m]
    n_tr = tab[tab[T_MODE_TR] + m + 1] - first
    n_inv = tab[tab[T_MODE_INV] + m + 1] - inv0
    b0 = wf[wi[W_SCAL] + S_B0]
    ta, wa, ga = t0, math.inf, -1.0
    tb, wb, gb = t0, w0, wf[gen]
    for i in range(1, n + 1):
        t = sample(i, n, t0, t1, wf, wi)
        watch_terms(fns, m, t, xs, wf, wi)
        w = watch_min(wf, wi, terms, tr_armed, n_tr, inv_armed, n_inv, b0)
        if w != w:  # a term failed: recorded, the others' minimum
            w = watch_value(tab, m, t, xs, wf, wi)
        if wi[fail] != 0:
            curve_at(tb, t0, t1, wf, wi)
            return EV_FAILED, tb, w
        if w <= 0.0:
            root = locate(fns, tab, m, tb, wb, t, w, t0, t1, wf, wi)
            curve_at(root, t0, t1, wf, wi)
            return EV_CROSSING, root, w
        if i >= 2 and wb <= wa and wb <= w and (wb < wa or wb < w) and ga == gb == wf[gen]:
            kind, found = dip(fns, tab, m, ta, wa, tb, wb, t, w, t0, t1, wf, wi)
            if kind != EV_NONE:
                curve_at(found, t0, t1, wf, wi)
                return kind, found, w
            sample(i, n, t0, t1, wf, wi)  # the dip's search moved xs and the terms
            watch_terms(fns, m, t, xs, wf, wi)
        if arming and arm_at(fns, tab, m, t, xs, wf, wi):
            watch_terms(fns, m, t, xs, wf, wi)
            w = watch_value(tab, m, t, xs, wf, wi)
            arming = pending(tab, m, wf, wi)
        ta, wa, ga = tb, wb, gb
        tb, wb, gb = t, w, wf[gen]
    return EV_NONE, math.nan, wb
