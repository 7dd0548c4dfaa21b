"""Kernel source: one stay in a mode, as :class:`hybrid.simulation.stay.StayIntegrator` runs it.

:func:`flow_stay` is ``EventLoop._flow`` around ``StayIntegrator.stay``, step
for step:

- the watch of the stay (:func:`~hybrid.simulation.native.events.watch_start`);
- the flow at the start (``_start``): a failing or non-finite derivative ends
  the run as ``nonfinite`` before the first step;
- the integrator started warm with the last full step of the run
  (``_first_step``), else with scipy's initial step;
- each accepted step: a step size that collapses, or a non-finite state, ends
  the run at the last accepted point (``_gave_up``, ``nonfinite`` when the
  flow failed on the way); :data:`STALL_STEPS` steps that do not advance, or a
  crawl (``CRAWL_*``), end it as ``solver_failure``; then the step is searched
  (:func:`~hybrid.simulation.native.crossing.first_event`) before it is
  recorded: an event ends the stay there (the points of the step before it,
  then the event point), and the transitions are decided
  (:func:`~hybrid.simulation.native.boundary.enabled_at_event`; ``blocked`` if
  none is enabled while an invariant is being left); a failed evaluation
  ends the run at the last good sample; ``t_end`` and Ctrl-C end it at the
  step's end;
- evaluation failures take precedence over every other end (``_eval_failure``).

Points are recorded as the reference's ``StayRecord`` stores them: step ends
(or the ``dt`` grid points of each step) and the end of the stay.

Copied into the kernel module (below the ``kernel`` marker).
"""

from __future__ import annotations

import math

from hybrid.simulation.native.boundary import choose, note_failure
from hybrid.simulation.native.buffers import (
    ASK_EVENT,
    ASK_LEFT,
    ASK_WATCH,
    CF_ATOL,
    CF_DT,
    CF_MAX_STEP,
    CF_RTOL,
    CF_T_END,
    CF_T_START,
    CI_DENSE,
    D_BLOCKED_FLOW,
    D_CRAWL,
    D_EVAL,
    D_FLOW,
    D_FLOW_START,
    D_NONE,
    D_NOT_ADVANCING,
    D_STATE_NONFINITE,
    D_STEP_TOO_SMALL,
    F_AUX0,
    F_AUX1,
    F_FLOW,
    F_NOW,
    F_PEAK,
    I_STEPS,
    OP_RHS,
    S_FAIL_T,
    S_FLOW_FAIL,
    S_FLOW_T,
    S_LAST_STEP,
    S_SIG_T,
    W_D,
    W_F,
    W_FAILI,
    W_FAILX,
    W_FLOWX,
    W_K,
    W_PE,
    W_Q,
    W_SCAL,
    W_SIGFAIL,
    W_SIGX,
    W_XS,
    W_Y,
    W_YNEW,
)
from hybrid.simulation.native.crossing import EV_CROSSING, EV_FAILED, EV_NONE
from hybrid.simulation.native.events import (
    far_edge_guards,
    far_edge_left,
    watch_terms,
    watch_value,
)
from hybrid.simulation.native.integrator import dense_eval, initial_step
from hybrid.simulation.native.kernel_types import (
    Array,
    Array2,
    DecideFn,
    Fns,
    Ints,
    SearchFn,
    StepFn,
    at,
)
from hybrid.simulation.native.recorder import finish, record_point, record_step

__all__ = [
    "CRAWL_DROP",
    "CRAWL_PROJECTION",
    "CRAWL_STEPS",
    "STALL_STEPS",
    "STAY_DONE",
    "STAY_EVENT",
    "end_run",
    "failed",
    "flow_stay",
    "record_grid",
]

# --- kernel ---

STAY_EVENT = 0
STAY_DONE = 1
C_T_END, C_BLOCKED, C_NONFINITE, C_SOLVER_FAILURE, C_INTERRUPTED = 0, 3, 4, 5, 6  # CAUSE_CODES
STALL_STEPS = 50
CRAWL_STEPS = 1000
CRAWL_DROP = 1e-6
CRAWL_PROJECTION = 1e6


def failed(wi: Ints) -> bool:
    """Whether an evaluation has failed at a point of the trajectory (a signal included)."""
    return bool(wi[wi[W_FAILI]] != 0 or wi[wi[W_SIGFAIL]] != 0)


def end_run(oi: Ints, of: Array, cause: int, t: float, j: int, m: int, detail: int, index: int,
            zeno_time: float, wf: Array, wi: Ints) -> None:  # fmt: skip
    """End the run, unless an evaluation failed first: then ``nonfinite`` at the failure.

    The first failure recorded wins (the search's and the decisions' before a
    signal's, which the reference computes when a stay's points are stored).
    """
    fail = wi[W_FAILI]
    sig = wi[W_SIGFAIL]
    if wi[fail] == 0 and wi[sig] != 0:
        wi[fail], wi[fail + 1], wi[fail + 2] = wi[sig], wi[sig + 1], wi[sig + 2]
        wf[wi[W_SCAL] + S_FAIL_T] = wf[wi[W_SCAL] + S_SIG_T]
        for i in range(wi[W_D]):
            wf[wi[W_FAILX] + i] = wf[wi[W_SIGX] + i]
    if wi[fail] != 0:
        finish(oi, of, C_NONFINITE, wf[wi[W_SCAL] + S_FAIL_T], j, m, D_EVAL, 0, math.nan, wf, wi)
    else:
        finish(oi, of, cause, t, j, m, detail, index, zeno_time, wf, wi)


def record_grid(fns: Fns, pts: Array2, oi: Ints, lo: float, hi: float, inclusive: bool,
                t_old: float, h: float, j: int, m: int, cfg_f: Array, wf: Array,
                wi: Ints) -> bool:  # fmt: skip
    """Store the ``dt`` grid points in ``(lo, hi)`` (``hi`` too if ``inclusive``); False if full."""
    d = wi[W_D]
    xs = wf[wi[W_XS] : wi[W_XS] + d]
    start, dt = cfg_f[CF_T_START], cfg_f[CF_DT]
    k0 = math.floor((lo - start) / dt)
    k1 = math.floor((hi - start) / dt) + 1
    for k in range(k0, k1 + 1):
        g = start + dt * k
        if g > lo and (g <= hi if inclusive else g < hi):
            dense_eval(g, t_old, h, wf, wi, xs)
            if not record_point(fns, pts, oi, g, j, m, xs, wf, wi):
                return False
    return True


def _peak(of: Array, wf: Array, wi: Ints) -> None:
    """The largest ``|state|`` at the last accepted point, for the message."""
    big = 0.0
    for i in range(wi[W_D]):
        big = max(big, abs(wf[wi[W_Y] + i]))
    of[F_PEAK] = big


def _gave_up(oi: Ints, of: Array, t: float, j: int, m: int, detail: int, cause: int, wf: Array,
             wi: Ints) -> None:  # fmt: skip
    """The end of a stay whose integrator cannot go on, at the last accepted point (``_gave_up``)."""
    _peak(of, wf, wi)
    sc = wi[W_SCAL]
    if wf[sc + S_FLOW_FAIL] != 0.0:
        fail = wi[W_FAILI]
        if wi[fail] == 0 and wi[wi[W_SIGFAIL]] == 0:
            wi[fail], wi[fail + 1], wi[fail + 2] = F_FLOW, m, m
            wf[sc + S_FAIL_T] = wf[sc + S_FLOW_T]
            for i in range(wi[W_D]):
                wf[wi[W_FAILX] + i] = wf[wi[W_FLOWX] + i]
            finish(oi, of, C_NONFINITE, t, j, m, D_FLOW, 0, math.nan, wf, wi)
            return
    end_run(oi, of, cause, t, j, m, detail, 0, math.nan, wf, wi)


def flow_stay(fns: Fns, step: StepFn, search: SearchFn, decide: DecideFn, tab: Ints, m: int,
              t0: float, x: Array, j: int, stay: int, spacing: float, cfg_f: Array, cfg_i: Ints,
              pts: Array2, sts: Array2, oi: Ints, of: Array, wf: Array, wi: Ints,
              flag: Ints) -> tuple[int, float, int]:  # fmt: skip
    """Integrate one stay from ``(t0, x)``: ``(STAY_EVENT, t, chosen)`` or ``(STAY_DONE, t, -1)``.

    On ``STAY_EVENT`` the event point is in ``x`` and recorded, and ``chosen``
    is the global transition that fires there (-1: none, a new stay starts
    there). On ``STAY_DONE`` the run has ended (its termination is in
    ``oi``/``of``), or a buffer is full (``I_OVERFLOW``).
    """
    t_end, rtol, atol = cfg_f[CF_T_END], cfg_f[CF_RTOL], cfg_f[CF_ATOL]
    max_step = cfg_f[CF_MAX_STEP]
    gridded = cfg_f[CF_DT] == cfg_f[CF_DT]
    dense = cfg_i[CI_DENSE] != 0
    d = wi[W_D]
    sc = wi[W_SCAL]
    fail = wi[W_FAILI]
    y = wf[wi[W_Y] : wi[W_Y] + d]
    f = wf[wi[W_F] : wi[W_F] + d]
    y_new = wf[wi[W_YNEW] : wi[W_YNEW] + d]
    xs = wf[wi[W_XS] : wi[W_XS] + d]
    k_last = wf[wi[W_K] + 6 * d : wi[W_K] + 7 * d]  # K[6]: the derivative at the step's end
    pe = wf[wi[W_PE] :]
    decide(ASK_WATCH, fns, tab, m, t0, x, wf, wi)
    if wi[fail] != 0:
        end_run(oi, of, C_NONFINITE, t0, j, m, D_EVAL, 0, math.nan, wf, wi)
        return STAY_DONE, t0, -1
    for i in range(d):
        y[i] = x[i]
    wf[sc + S_FLOW_FAIL] = 0.0
    fns(OP_RHS, m, t0, at(y, 0), at(wf, wi[W_PE]), at(f, 0))
    for i in range(d):
        if not math.isfinite(f[i]):  # the flow at the start: the assembler words it
            note_failure(F_FLOW, m, m, t0, y, wf, wi)
            finish(oi, of, C_NONFINITE, t0, j, m, D_FLOW_START, i, math.nan, wf, wi)
            return STAY_DONE, t0, -1
    warm = wf[sc + S_LAST_STEP]
    if warm == warm and warm > 0.0 and t_end > t0:
        h_abs = min(warm, max_step, t_end - t0)
    else:
        h_abs = initial_step(fns, m, t0, t_end, max_step, rtol, atol, pe, wf, wi)
    watch_terms(fns, m, t0, y, wf, wi)
    w = watch_value(tab, m, t0, y, wf, wi)
    t = t0
    stalls = steps = 0
    longest, window_start = 0.0, t0
    while True:
        if d == 0:  # scipy steps a stateless system to its end at once
            t_new, h = t_end, t_end - t
        else:
            ok, t_new, h_abs, h = step(fns, m, t, t_end, h_abs, max_step, rtol, atol, pe, wf, wi)
            if not ok:
                _gave_up(oi, of, t, j, m, D_STEP_TOO_SMALL, C_SOLVER_FAILURE, wf, wi)
                return STAY_DONE, t, -1
        finite = True
        for i in range(d):
            if not math.isfinite(y_new[i]):
                finite = False
        if not finite:
            _gave_up(oi, of, t, j, m, D_STATE_NONFINITE, C_NONFINITE, wf, wi)
            return STAY_DONE, t, -1
        stalls = stalls + 1 if t_new - t <= 4e-16 * max(1.0, abs(t_new)) else 0
        if stalls > STALL_STEPS:
            _peak(of, wf, wi)
            end_run(oi, of, C_SOLVER_FAILURE, t, j, m, D_NOT_ADVANCING, 0, math.nan, wf, wi)
            return STAY_DONE, t, -1
        longest = max(longest, h)
        steps += 1
        oi[I_STEPS] += 1
        if steps % CRAWL_STEPS == 0:
            pace = (t_new - window_start) / CRAWL_STEPS
            window_start = t_new
            if pace < CRAWL_DROP * longest and t_end - t_new > CRAWL_PROJECTION * pace:
                of[F_AUX0], of[F_AUX1] = pace, longest
                _peak(of, wf, wi)
                end_run(oi, of, C_SOLVER_FAILURE, t, j, m, D_CRAWL, 0, math.nan, wf, wi)
                return STAY_DONE, t, -1
        kind, t_event, w = search(fns, tab, m, t, t_new, w, spacing, wf, wi)
        stop = t_new if kind == EV_NONE else t_event
        finished = t_new >= t_end
        going_on = kind == EV_NONE and not finished and flag[0] == 0
        if kind != EV_NONE:  # the event point, before the grid's points reuse ``xs``
            for i in range(d):
                x[i] = xs[i]
        if gridded and not record_grid(fns, pts, oi, t, stop, going_on, t, h, j, m, cfg_f, wf, wi):
            return STAY_DONE, t, -1
        if dense and not record_step(sts, oi, t, h, stop, j, stay, y, wf[wi[W_Q] : wi[W_Q] + 4 * d]):
            return STAY_DONE, t, -1
        if kind != EV_NONE:
            if not record_point(fns, pts, oi, t_event, j, m, x, wf, wi):
                return STAY_DONE, t_event, -1
            if kind == EV_FAILED or failed(wi):
                end_run(oi, of, C_NONFINITE, t_event, j, m, D_EVAL, 0, math.nan, wf, wi)
                return STAY_DONE, t_event, -1
            chosen = decide(ASK_EVENT, fns, tab, m, t_event, x, wf, wi)
            if chosen < 0 and kind == EV_CROSSING and far_edge_guards(fns, tab, m, t_event, x, wf,
                                                                      wi):  # fmt: skip
                chosen = choose(tab, m, wi)  # a disarmed guard a band beyond its boundary holds
            if failed(wi) or wf[sc + S_FLOW_FAIL] != 0.0:
                if wi[fail] == 0 and wi[wi[W_SIGFAIL]] == 0:  # a flow failure at a trial point
                    wi[fail], wi[fail + 1], wi[fail + 2] = F_FLOW, m, m
                    wf[sc + S_FAIL_T] = wf[sc + S_FLOW_T]
                    for i in range(d):
                        wf[wi[W_FAILX] + i] = wf[wi[W_FLOWX] + i]
                end_run(oi, of, C_NONFINITE, t_event, j, m, D_EVAL, 0, math.nan, wf, wi)
                return STAY_DONE, t_event, -1
            if chosen < 0 and t_event >= t_end:  # at t_end: nothing left to flow
                end_run(oi, of, C_T_END, t_event, j, m, D_NONE, 0, math.nan, wf, wi)
                return STAY_DONE, t_event, -1
            if chosen < 0:
                left = far_edge_left(fns, tab, m, t_event, x, wf, wi) if kind == EV_CROSSING else -1
                if left < 0:
                    left = decide(ASK_LEFT, fns, tab, m, t_event, x, wf, wi)
                if left >= 0:
                    finish(oi, of, C_BLOCKED, t_event, j, m, D_BLOCKED_FLOW, left, math.nan, wf, wi)
                    return STAY_DONE, t_event, -1
            of[F_NOW] = t_event
            return STAY_EVENT, t_event, chosen
        wf[sc + S_FLOW_FAIL] = 0.0  # only at trial points the integrator rejected: stepped around
        if not going_on:
            for i in range(d):
                x[i] = y_new[i]
            if not record_point(fns, pts, oi, t_new, j, m, x, wf, wi):
                return STAY_DONE, t_new, -1
            cause = C_T_END if finished else C_INTERRUPTED
            end_run(oi, of, cause, t_new, j, m, D_NONE, 0, math.nan, wf, wi)
            return STAY_DONE, t_new, -1
        if not gridded and not record_point(fns, pts, oi, t_new, j, m, y_new, wf, wi):
            return STAY_DONE, t_new, -1
        wf[sc + S_LAST_STEP] = h
        for i in range(d):
            y[i] = y_new[i]
            f[i] = k_last[i]
        t = t_new
        of[F_NOW] = t
