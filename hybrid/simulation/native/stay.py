"""Kernel source: one stay in a mode, integrated until the first event or the end.

The compiled counterpart of ``EventLoop._flow`` and ``EventLoop._solver_end``
(:mod:`hybrid.simulation.loop`), of the watch event
(:func:`hybrid.simulation.events.watch_factory`) and of what ``solve_ivp``
does with it, with the announced first-crossing rule:

- :func:`start_arming` is the arming at the start of a stay (``inv_armed``
  in ``_flow``, and the watch's first call at ``t0`` that arms a disarmed term
  whose value is already strictly positive);
- :func:`terms_at`, :func:`watch_of` and :func:`arm_from` are the watch:
  every guard's rho (falling through 0: it starts to hold), every equality
  level ``a - b`` (changing sign: the level is reached), every invariant's
  ``-rho`` (falling through 0: it stops holding); a disarmed term joins once
  strictly positive (a level: once nonzero);
- :func:`scan_step` is the first-crossing rule: the watch is sampled at
  ``samples`` interior points of each accepted step (on its interpolant) and
  at its end, and the earliest sample where it falls to 0 or below brackets
  the crossing, so a guard that holds only inside one step is still seen;
- :func:`locate` is ``solve_event_equation`` (Brent's method on the
  interpolant, tolerances ``4 eps``, as scipy's ``brentq``);
- :func:`flow_stay` is ``_flow`` and ``_solver_end``: the steps, the points
  recorded (step ends, or the ``dt`` grid), the end of the stay (an event
  decided by :func:`~hybrid.simulation.native.decide.decide_at_event`,
  ``t_end``, a collapsed step size, Ctrl-C) and the warm start of the next
  stay (``_first_step``).

Copied into every generated model module (below the ``kernel`` marker).
"""

from __future__ import annotations

import math

from hybrid.simulation.native.buffers import (
    CF_ATOL,
    CF_DT,
    CF_MAX_STEP,
    CF_RTOL,
    CF_T_END,
    CF_T_START,
    CI_DENSE,
    CI_SAMPLES,
    D_BLOCKED_FLOW,
    D_EVAL,
    D_FLOW,
    D_NONE,
    D_STATE_NONFINITE,
    D_STEP_TOO_SMALL,
    F_FLOW,
    F_GUARD,
    F_INVARIANT,
    I_POINTS,
    P_J,
    P_T,
    S_FAIL_T,
    S_FLOW_FAIL,
    S_FLOW_T,
    S_LAST_STEP,
    S_TS0,
    S_TS1,
    S_TS2,
    S_TS_COUNT,
    T_INV_RHO,
    T_LV_E,
    T_MODE_INV,
    T_MODE_TR,
    T_TR_LV,
    T_TR_RHO,
    W_CUR,
    W_D,
    W_F,
    W_FAILI,
    W_FAILX,
    W_FLOWX,
    W_INVARMED,
    W_K,
    W_LVARMED,
    W_LVSIGN,
    W_NT,
    W_PREV,
    W_Q,
    W_SCAL,
    W_TRARMED,
    W_XS,
    W_Y,
    W_YNEW,
)
from hybrid.simulation.native.decide import (
    band,
    decide_at_event,
    invariant_left_at,
    value_checked,
)
from hybrid.simulation.native.integrator import dense_eval, eval_rhs, initial_step, rk45_step
from hybrid.simulation.native.kernel_types import Array, Array2, Fns, Ints
from hybrid.simulation.native.store import finish, record_point, record_step

__all__ = [
    "STAY_DONE",
    "STAY_EVENT",
    "arm_from",
    "flow_stay",
    "locate",
    "scan_step",
    "start_arming",
    "terms_at",
    "watch_of",
]

# --- kernel ---

STAY_EVENT = 0
STAY_DONE = 1
EPS = 2.220446049250313e-16
C_T_END, C_BLOCKED, C_NONFINITE, C_SOLVER_FAILURE, C_INTERRUPTED = 0, 3, 4, 5, 6  # CAUSE_CODES


def terms_at(fns: Fns, tab: Ints, m: int, t: float, x: Array, p: Array, out: Array, wf: Array,
             wi: Ints) -> None:  # fmt: skip
    """Raw values of the watch's terms at ``(t, x)``: guards' rho, levels, invariants' rho."""
    first = tab[tab[T_MODE_TR] + m]
    n_tr = tab[tab[T_MODE_TR] + m + 1] - first
    lv0 = tab[tab[T_TR_LV] + first]
    n_lv = tab[tab[T_TR_LV] + first + n_tr] - lv0
    for k in range(n_tr):
        tr = first + k
        out[k] = value_checked(fns, tab[tab[T_TR_RHO] + tr], F_GUARD, tr, m, t, x, p, wf, wi)
        for a in range(tab[tab[T_TR_LV] + tr], tab[tab[T_TR_LV] + tr + 1]):
            e_form = tab[tab[T_LV_E] + a]
            out[n_tr + a - lv0] = value_checked(fns, e_form, F_GUARD, tr, m, t, x, p, wf, wi)
    inv0 = tab[tab[T_MODE_INV] + m]
    for k in range(tab[tab[T_MODE_INV] + m + 1] - inv0):
        inv = inv0 + k
        rho_f = tab[tab[T_INV_RHO] + inv]
        out[n_tr + n_lv + k] = value_checked(fns, rho_f, F_INVARIANT, inv, m, t, x, p, wf, wi)


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
    fail = wi[W_FAILI]
    t_prev = t
    for i in range(1, samples + 2):
        if i <= samples:
            tau = t + h * (i / (samples + 1.0))
            dense_eval(tau, t, h, y, q, xs)
            terms_at(fns, tab, m, tau, xs, p, cur, wf, wi)
        else:
            tau = t_new
            terms_at(fns, tab, m, tau, y_new, p, cur, wf, wi)
        if wi[fail] != 0:
            return math.nan
        fb = watch_of(tab, m, cur, wf, wi)
        if fb <= 0.0:
            fa = watch_of(tab, m, prev, wf, wi)
            return locate(fns, tab, m, t_prev, tau, fa, fb, t, h, p, wf, wi)
        arm_from(tab, m, cur, True, wf, wi)
        for k in range(used):
            prev[k] = cur[k]
        t_prev = tau
    return math.nan


def record_grid(fns: Fns, pts: Array2, oi: Ints, k_next: int, lo: float, hi: float,
                inclusive: bool, t_old: float, h: float, j: int, m: int, p: Array, cfg_f: Array,
                wf: Array, wi: Ints) -> int:  # fmt: skip
    """Store the ``dt`` grid points in ``(lo, hi)`` (``hi`` too if ``inclusive``); next index."""
    d = wi[W_D]
    y = wf[wi[W_Y] : wi[W_Y] + d]
    q = wf[wi[W_Q] : wi[W_Q] + 4 * d].reshape((d, 4))
    xs = wf[wi[W_XS] : wi[W_XS] + d]
    while True:
        g = cfg_f[CF_T_START] + cfg_f[CF_DT] * k_next
        if g > hi or (g == hi and not inclusive):
            return k_next
        if g > lo:
            dense_eval(g, t_old, h, y, q, xs)
            if not record_point(fns, pts, oi, g, j, m, xs, p, wf, wi):
                return -1
        k_next += 1


def flow_stay(fns: Fns, tab: Ints, m: int, t0: float, x: Array, j: int, stay: int, p: Array,
              cfg_f: Array, cfg_i: Ints, pts: Array2, sts: Array2, oi: Ints, of: Array,
              wf: Array, wi: Ints, flag: Ints) -> tuple[int, float, int]:  # fmt: skip
    """Integrate one stay from ``(t0, x)``: ``(STAY_EVENT, t, chosen)`` or ``(STAY_DONE, t, -1)``.

    On ``STAY_EVENT`` the event point is in ``x`` and recorded, and ``chosen``
    is the global transition that fires there (-1: none, the stay goes on).
    On ``STAY_DONE`` the run has ended (its termination is in ``oi``/``of``),
    or a buffer is full (``I_OVERFLOW``).
    """
    t_end, rtol, atol = cfg_f[CF_T_END], cfg_f[CF_RTOL], cfg_f[CF_ATOL]
    max_step = cfg_f[CF_MAX_STEP]
    gridded = cfg_f[CF_DT] == cfg_f[CF_DT]
    dense = cfg_i[CI_DENSE] != 0
    samples = cfg_i[CI_SAMPLES]
    d = wi[W_D]
    sc = wi[W_SCAL]
    fail = wi[W_FAILI]
    y = wf[wi[W_Y] : wi[W_Y] + d]
    f = wf[wi[W_F] : wi[W_F] + d]
    y_new = wf[wi[W_YNEW] : wi[W_YNEW] + d]
    xs = wf[wi[W_XS] : wi[W_XS] + d]
    q = wf[wi[W_Q] : wi[W_Q] + 4 * d].reshape((d, 4))
    K = wf[wi[W_K] : wi[W_K] + 7 * d].reshape((7, d))
    start_arming(fns, tab, m, t0, x, p, wf, wi)
    if wi[fail] != 0:
        finish(oi, of, C_NONFINITE, wf[sc + S_FAIL_T], j, m, D_EVAL, 0, math.nan, wf, wi)
        return STAY_DONE, t0, -1
    for i in range(d):
        y[i] = x[i]
    wf[sc + S_FLOW_FAIL] = 0.0
    eval_rhs(fns, m, t0, y, p, f, wf, wi)
    warm = wf[sc + S_LAST_STEP]
    if warm == warm and warm > 0.0:
        h_abs = min(warm, max_step, t_end - t0)
    else:
        h_abs = initial_step(fns, m, t0, t_end, max_step, rtol, atol, p, wf, wi)
    t = t0
    wf[sc + S_TS0], wf[sc + S_TS1], wf[sc + S_TS2], wf[sc + S_TS_COUNT] = math.nan, math.nan, t0, 1.0
    k_next = 0
    if gridded:
        k_next = int(math.floor((t0 - cfg_f[CF_T_START]) / cfg_f[CF_DT])) + 1
    while True:
        ok, t_new, h_abs, h = rk45_step(fns, m, t, t_end, h_abs, max_step, rtol, atol, p, wf, wi)
        if not ok:
            if gridded and not record_point(fns, pts, oi, t, j, m, y, p, wf, wi):
                return STAY_DONE, t, -1
            if wf[sc + S_FLOW_FAIL] != 0.0:
                wi[fail], wi[fail + 1], wi[fail + 2] = F_FLOW, m, m
                wf[sc + S_FAIL_T] = wf[sc + S_FLOW_T]
                for i in range(d):
                    wf[wi[W_FAILX] + i] = wf[wi[W_FLOWX] + i]
                finish(oi, of, C_NONFINITE, t, j, m, D_FLOW, 0, math.nan, wf, wi)
            else:
                finish(oi, of, C_SOLVER_FAILURE, t, j, m, D_STEP_TOO_SMALL, 0, math.nan, wf, wi)
            return STAY_DONE, t, -1
        finite = True
        for i in range(d):
            if not math.isfinite(y_new[i]):
                finite = False
        if not finite:
            record_point(fns, pts, oi, t_new, j, m, y_new, p, wf, wi)
            finish(oi, of, C_NONFINITE, t_new, j, m, D_STATE_NONFINITE, 0, math.nan, wf, wi)
            return STAY_DONE, t_new, -1
        t_event = scan_step(fns, tab, m, t, t_new, h, samples, p, wf, wi)
        if wi[fail] != 0:
            finish(oi, of, C_NONFINITE, wf[sc + S_FAIL_T], j, m, D_EVAL, 0, math.nan, wf, wi)
            return STAY_DONE, t, -1
        found = t_event == t_event
        stop = t_event if found else t_new
        if gridded:
            inclusive = not found and t_new < t_end
            k_next = record_grid(fns, pts, oi, k_next, t, stop, inclusive, t, h, j, m, p, cfg_f,
                                 wf, wi)  # fmt: skip
            if k_next < 0:
                return STAY_DONE, t, -1
        if dense and not record_step(sts, oi, t, h, stop, j, stay, y, q):
            return STAY_DONE, t, -1
        wf[sc + S_TS0], wf[sc + S_TS1], wf[sc + S_TS2] = wf[sc + S_TS1], wf[sc + S_TS2], stop
        wf[sc + S_TS_COUNT] += 1.0
        if wf[sc + S_TS_COUNT] >= 3.0:  # the next stay starts with the last full step
            wf[sc + S_LAST_STEP] = wf[sc + S_TS1] - wf[sc + S_TS0]
        if found:
            dense_eval(t_event, t, h, y, q, xs)
            for i in range(d):
                x[i] = xs[i]
            if not record_point(fns, pts, oi, t_event, j, m, x, p, wf, wi):
                return STAY_DONE, t_event, -1
            chosen = -1
            if wi[fail] == 0:
                chosen = decide_at_event(fns, tab, m, t_event, x, p, wf, wi)
            if wi[fail] != 0:
                finish(oi, of, C_NONFINITE, wf[sc + S_FAIL_T], j, m, D_EVAL, 0, math.nan, wf, wi)
                return STAY_DONE, t_event, -1
            if chosen < 0:
                left = invariant_left_at(fns, tab, m, t_event, x, p, wf, wi)
                if left >= 0:
                    finish(oi, of, C_BLOCKED, t_event, j, m, D_BLOCKED_FLOW, left, math.nan, wf, wi)
                    return STAY_DONE, t_event, -1
            return STAY_EVENT, t_event, chosen
        if not gridded and not record_point(fns, pts, oi, t_new, j, m, y_new, p, wf, wi):
            return STAY_DONE, t_new, -1
        for i in range(d):
            y[i] = y_new[i]
            f[i] = K[6, i]
            x[i] = y[i]
        t = t_new
        if wi[fail] != 0:
            finish(oi, of, C_NONFINITE, wf[sc + S_FAIL_T], j, m, D_EVAL, 0, math.nan, wf, wi)
            return STAY_DONE, t, -1
        if t >= t_end or flag[0] != 0:
            last = oi[I_POINTS] - 1
            stored = last >= 0 and pts[last, P_T] == t and pts[last, P_J] == j
            if gridded and not stored and not record_point(fns, pts, oi, t, j, m, y, p, wf, wi):
                return STAY_DONE, t, -1
            cause = C_T_END if t >= t_end else C_INTERRUPTED
            finish(oi, of, cause, t, j, m, D_NONE, 0, math.nan, wf, wi)
            return STAY_DONE, t, -1
