"""Kernel source: one stay in a mode, integrated until the first event or the end.

The compiled counterpart of ``EventLoop._flow`` and ``EventLoop._solver_end``
(:mod:`hybrid.simulation.loop`), of the watch event
(:func:`hybrid.simulation.events.watch_factory`) and of what ``solve_ivp``
does with it, with the announced first-crossing rule:

- the watch, its arming and the first-crossing rule are
  :mod:`~hybrid.simulation.native.watch`'s;
- :func:`flow_stay` is ``_flow`` and ``_solver_end``: the steps, the points
  recorded (step ends, or the ``dt`` grid), the end of the stay (an event
  decided by :func:`~hybrid.simulation.native.decide.decide_at_event`,
  ``t_end``, a collapsed step size, Ctrl-C) and the warm start of the next
  stay (``_first_step``).

Copied into the kernel module (below the ``kernel`` marker).
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
    W_D,
    W_F,
    W_FAILI,
    W_FAILX,
    W_FLOWX,
    W_K,
    W_Q,
    W_SCAL,
    W_XS,
    W_Y,
    W_YNEW,
)
from hybrid.simulation.native.decide import (
    decide_at_event,
    invariant_left_at,
)
from hybrid.simulation.native.integrator import dense_eval, eval_rhs, initial_step, rk45_step
from hybrid.simulation.native.kernel_types import Array, Array2, Fns, Ints
from hybrid.simulation.native.store import finish, record_point, record_step
from hybrid.simulation.native.watch import scan_step, start_arming

__all__ = ["STAY_DONE", "STAY_EVENT", "flow_stay", "record_grid"]

# --- kernel ---

STAY_EVENT = 0
STAY_DONE = 1
C_T_END, C_BLOCKED, C_NONFINITE, C_SOLVER_FAILURE, C_INTERRUPTED = 0, 3, 4, 5, 6  # CAUSE_CODES


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
        k_next = math.floor((t0 - cfg_f[CF_T_START]) / cfg_f[CF_DT]) + 1
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
