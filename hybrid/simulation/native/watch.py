"""Kernel source: the watch of a stay, and where it first falls to zero.

Part of the compiled counterpart of the watch event
(:func:`hybrid.simulation.events.watch_factory`) and of what ``solve_ivp``
does with it, with the announced first-crossing rule:

- :func:`terms_at`, :func:`watch_of` and :func:`arm_from` are the watch:
  every guard's rho (falling through 0: it starts to hold), every equality
  level ``a - b`` (changing sign: the level is reached), every invariant's
  ``-rho`` (falling through 0: it stops holding); a disarmed term joins once
  strictly positive (a level: once nonzero);
- :func:`start_arming` is the arming at the start of a stay (``inv_armed``
  in ``EventLoop._flow``, and the watch's first call at ``t0`` that arms a
  disarmed term whose value is already strictly positive);
- :func:`scan_step` is the first-crossing rule: the watch is sampled at
  ``samples`` interior points of each accepted step (on its interpolant) and
  at its end, and the earliest sample where it falls to 0 or below brackets
  the crossing, so a guard that holds only inside one step is still seen;
- :func:`locate` is ``solve_event_equation`` (Brent's method on the
  interpolant, tolerances ``4 eps``, as scipy's ``brentq``).

Copied into the kernel module (below the ``kernel`` marker).
"""

from __future__ import annotations

import math

from hybrid.simulation.native.buffers import (
    F_GUARD,
    F_INVARIANT,
    OP_TERMS,
    T_INV_RHO,
    T_LV_E,
    T_MODE_INV,
    T_MODE_TR,
    T_TR_LV,
    W_CUR,
    W_D,
    W_INVARMED,
    W_LVARMED,
    W_LVSIGN,
    W_NT,
    W_PREV,
    W_Q,
    W_TRARMED,
    W_XS,
    W_Y,
    W_YNEW,
)
from hybrid.simulation.native.decide import band, note_failure, value_checked
from hybrid.simulation.native.integrator import dense_eval
from hybrid.simulation.native.kernel_types import Array, Fns, Ints

__all__ = ["arm_from", "locate", "scan_step", "start_arming", "terms_at", "watch_of"]

# --- kernel ---

EPS = 2.220446049250313e-16


def terms_at(fns: Fns, tab: Ints, m: int, t: float, x: Array, p: Array, out: Array, wf: Array,
             wi: Ints) -> None:  # fmt: skip
    """Raw values of the watch's terms at ``(t, x)``: guards' rho, levels, invariants' rho.

    One call of the model's ``terms``; a NaN is recorded as the failure of its
    guard or invariant.
    """
    fns(OP_TERMS, m, t, x.ctypes, p.ctypes, out.ctypes)
    first = tab[tab[T_MODE_TR] + m]
    n_tr = tab[tab[T_MODE_TR] + m + 1] - first
    lv0 = tab[tab[T_TR_LV] + first]
    n_lv = tab[tab[T_TR_LV] + first + n_tr] - lv0
    inv0 = tab[tab[T_MODE_INV] + m]
    n_inv = tab[tab[T_MODE_INV] + m + 1] - inv0
    for k in range(n_tr + n_lv + n_inv):
        if out[k] != out[k]:
            if k < n_tr:
                note_failure(F_GUARD, first + k, m, t, x, wf, wi)
            elif k < n_tr + n_lv:
                tr = first
                while tab[tab[T_TR_LV] + tr + 1] <= lv0 + k - n_tr:
                    tr += 1
                note_failure(F_GUARD, tr, m, t, x, wf, wi)
            else:
                note_failure(F_INVARIANT, inv0 + k - n_tr - n_lv, m, t, x, wf, wi)
            return


def watch_of(tab: Ints, m: int, vals: Array, wf: Array, wi: Ints) -> float:
    """The watch: the smallest armed term (levels signed to start positive); 1 if none."""
    first = tab[tab[T_MODE_TR] + m]
    n_tr = tab[tab[T_MODE_TR] + m + 1] - first
    n_lv = tab[tab[T_TR_LV] + first + n_tr] - tab[tab[T_TR_LV] + first]
    n_inv = tab[tab[T_MODE_INV] + m + 1] - tab[tab[T_MODE_INV] + m]
    tr_armed, lv_armed, inv_armed = wi[W_TRARMED], wi[W_LVARMED], wi[W_INVARMED]
    lv_sign = wi[W_LVSIGN]
    v = 1.0e308
    for k in range(n_tr):
        if wi[tr_armed + k] != 0 and vals[k] < v:
            v = vals[k]
    for a in range(n_lv):
        if wi[lv_armed + a] != 0:
            s = wf[lv_sign + a] * vals[n_tr + a]
            if s < v:
                v = s
    for k in range(n_inv):
        if wi[inv_armed + k] != 0:
            s = -vals[n_tr + n_lv + k]
            if s < v:
                v = s
    if v >= 1.0e308:
        v = 1.0
    return v


def arm_from(tab: Ints, m: int, vals: Array, levels: bool, wf: Array, wi: Ints) -> None:
    """Arm the terms that are strictly on their safe side at this point (levels: nonzero)."""
    first = tab[tab[T_MODE_TR] + m]
    n_tr = tab[tab[T_MODE_TR] + m + 1] - first
    n_lv = tab[tab[T_TR_LV] + first + n_tr] - tab[tab[T_TR_LV] + first]
    n_inv = tab[tab[T_MODE_INV] + m + 1] - tab[tab[T_MODE_INV] + m]
    tr_armed, lv_armed, inv_armed = wi[W_TRARMED], wi[W_LVARMED], wi[W_INVARMED]
    for k in range(n_tr):
        if vals[k] > 0.0:
            wi[tr_armed + k] = 1
    if levels:
        for a in range(n_lv):
            e = vals[n_tr + a]
            if e > 0.0 or e < 0.0:
                wf[wi[W_LVSIGN] + a] = 1.0 if e > 0.0 else -1.0
                wi[lv_armed + a] = 1
    for k in range(n_inv):
        if -vals[n_tr + n_lv + k] > 0.0:
            wi[inv_armed + k] = 1


def start_arming(fns: Fns, tab: Ints, m: int, t: float, x: Array, p: Array, wf: Array,
                 wi: Ints) -> None:  # fmt: skip
    """Arming at the start of a stay (guards' arming comes from ``enabled_at_entry``)."""
    width = band(x)
    first = tab[tab[T_MODE_TR] + m]
    lv0 = tab[tab[T_TR_LV] + first]
    inv0 = tab[tab[T_MODE_INV] + m]
    for k in range(tab[tab[T_MODE_INV] + m + 1] - inv0):
        inv = inv0 + k
        rho = value_checked(fns, tab[tab[T_INV_RHO] + inv], F_INVARIANT, inv, m, t, x, p, wf, wi)
        wi[wi[W_INVARMED] + k] = 1 if rho < -width else 0
    for k in range(tab[tab[T_MODE_TR] + m + 1] - first):
        tr = first + k
        for a in range(tab[tab[T_TR_LV] + tr], tab[tab[T_TR_LV] + tr + 1]):
            e = value_checked(fns, tab[tab[T_LV_E] + a], F_GUARD, tr, m, t, x, p, wf, wi)
            wi[wi[W_LVARMED] + a - lv0] = 1 if abs(e) > width else 0
            wf[wi[W_LVSIGN] + a - lv0] = 1.0 if e > 0.0 else -1.0
    prev = wf[wi[W_PREV] : wi[W_PREV] + wi[W_NT]]
    terms_at(fns, tab, m, t, x, p, prev, wf, wi)
    arm_from(tab, m, prev, False, wf, wi)


def locate(fns: Fns, tab: Ints, m: int, xa: float, xb: float, fa: float, fb: float, t_old: float,
           h: float, p: Array, wf: Array, wi: Ints) -> float:  # fmt: skip
    """Brent's method for the watch's root in ``[xa, xb]`` (``fa > 0 >= fb``), as ``brentq``.

    The watch is evaluated on the interpolant of the step from ``(t_old, y)``.
    """
    d = wi[W_D]
    y = wf[wi[W_Y] : wi[W_Y] + d]
    q = wf[wi[W_Q] : wi[W_Q] + 4 * d].reshape((d, 4))
    xs = wf[wi[W_XS] : wi[W_XS] + d]
    cur = wf[wi[W_CUR] : wi[W_CUR] + wi[W_NT]]
    xtol = 4.0 * EPS
    rtol = 4.0 * EPS
    xpre, xcur, fpre, fcur = xa, xb, fa, fb
    xblk, fblk, spre, scur = 0.0, 0.0, 0.0, 0.0
    if fpre == 0.0:
        return xpre
    if fcur == 0.0:
        return xcur
    for _ in range(100):
        if fpre * fcur < 0.0:
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
                stry = -fcur * (xcur - xpre) / (fcur - fpre)  # secant
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
        dense_eval(xcur, t_old, h, y, q, xs)
        terms_at(fns, tab, m, xcur, xs, p, cur, wf, wi)
        fcur = watch_of(tab, m, cur, wf, wi)
    return xcur


def scan_step(fns: Fns, tab: Ints, m: int, t: float, t_new: float, h: float, samples: int,
              p: Array, wf: Array, wi: Ints) -> float:  # fmt: skip
    """The time of the first crossing in the step ``[t, t_new]``, or NaN if there is none.

    Samples at ``samples`` interior points and at the end; the terms are armed
    from sample to sample; the first sample where the watch is ``<= 0``
    brackets the crossing with the one before. Stops early (NaN) on an
    evaluation failure, which is then recorded.
    """
    n_terms = wi[W_NT]
    first = tab[tab[T_MODE_TR] + m]
    n_tr = tab[tab[T_MODE_TR] + m + 1] - first
    used = (
        n_tr + tab[tab[T_TR_LV] + first + n_tr] - tab[tab[T_TR_LV] + first]
        + tab[tab[T_MODE_INV] + m + 1] - tab[tab[T_MODE_INV] + m]
    )  # fmt: skip
    if used == 0:
        return math.nan
    d = wi[W_D]
    y = wf[wi[W_Y] : wi[W_Y] + d]
    y_new = wf[wi[W_YNEW] : wi[W_YNEW] + d]
    q = wf[wi[W_Q] : wi[W_Q] + 4 * d].reshape((d, 4))
    xs = wf[wi[W_XS] : wi[W_XS] + d]
    prev = wf[wi[W_PREV] : wi[W_PREV] + n_terms]
    cur = wf[wi[W_CUR] : wi[W_CUR] + n_terms]
    n_lv = tab[tab[T_TR_LV] + first + n_tr] - tab[tab[T_TR_LV] + first]
    tr_armed, lv_armed, inv_armed = wi[W_TRARMED], wi[W_LVARMED], wi[W_INVARMED]
    lv_sign = wi[W_LVSIGN]
    # the hot loop: the watch, its arming and the interpolant are written out here,
    # not called (a call of a kernel function passes every array field by field)
    p_c, xs_c, yn_c, cur_c = p.ctypes, xs.ctypes, y_new.ctypes, cur.ctypes
    t_prev = t
    for i in range(1, samples + 2):
        if i <= samples:
            tau = t + h * (i / (samples + 1.0))
            s1 = (tau - t) / h
            s2 = s1 * s1
            s3 = s2 * s1
            s4 = s3 * s1
            for k in range(d):
                xs[k] = h * (q[k, 0] * s1 + q[k, 1] * s2 + q[k, 2] * s3 + q[k, 3] * s4) + y[k]
            fns(OP_TERMS, m, tau, xs_c, p_c, cur_c)
        else:
            tau = t_new
            fns(OP_TERMS, m, tau, yn_c, p_c, cur_c)
        fb = 1.0e308
        failed = False
        for k in range(used):
            value = cur[k]
            if value != value:
                failed = True
            elif k < n_tr:
                if wi[tr_armed + k] != 0 and value < fb:
                    fb = value
            elif k < n_tr + n_lv:
                signed = wf[lv_sign + k - n_tr] * value
                if wi[lv_armed + k - n_tr] != 0 and signed < fb:
                    fb = signed
            elif wi[inv_armed + k - n_tr - n_lv] != 0 and -value < fb:
                fb = -value
        if failed:  # name the failing term (rare: evaluate again, recording)
            terms_at(fns, tab, m, tau, xs if i <= samples else y_new, p, cur, wf, wi)
            return math.nan
        if fb >= 1.0e308:
            fb = 1.0
        if fb <= 0.0:
            fa = watch_of(tab, m, prev, wf, wi)
            return locate(fns, tab, m, t_prev, tau, fa, fb, t, h, p, wf, wi)
        for k in range(used):
            value = cur[k]
            if k < n_tr:
                if value > 0.0:
                    wi[tr_armed + k] = 1
            elif k < n_tr + n_lv:
                if value > 0.0 or value < 0.0:
                    wf[lv_sign + k - n_tr] = 1.0 if value > 0.0 else -1.0
                    wi[lv_armed + k - n_tr] = 1
            elif -value > 0.0:
                wi[inv_armed + k - n_tr - n_lv] = 1
            prev[k] = value
        t_prev = tau
    return math.nan
