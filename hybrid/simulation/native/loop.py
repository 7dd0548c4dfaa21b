"""Kernel source: the event loop of one run, as :class:`hybrid.simulation.loop.EventLoop` runs it.

Function by function:

- :func:`run_one` is ``EventLoop.run``: decide at the entry point (a jump
  enabled there fires at once), else flow until the watch stops the stay;
  ``max_jumps``, the per-instant cap (a zero-time cycle ends as ``zeno``), the
  stall counter (events without an enabled transition, ``solver_failure``),
  ``blocked`` at entry (an urgent mode where no transition fires at once, or an
  invariant that does not hold), non-finite resets, Zeno by geometric accumulation;
- :func:`jump` is ``EventLoop._jump`` (reset on pre-jump values, record the
  jump and the post-jump point);
- :func:`note_reached` and :func:`note_used` keep ``EventLoop.run``'s
  ``reached`` (the state where the last stay stopped, and when) and ``used``
  (the keys of the levels read by a guard disarmed in that stay or taken at
  that instant);
- :func:`zeno_update` is :meth:`hybrid.simulation.zeno.ZenoDetector.update`
  (window 6, spread 2 %, shrink 1e-3), its state in ``wf``;
- :func:`lay_out_work` sizes the scratch space (``wf``, ``wi``) of a run (Python
  allocates it, so that nothing compiled allocates), :func:`start_work` fills it:
  the run's parameter vector with the level slots after the parameters among it.

The flow of a stay is :func:`~hybrid.simulation.native.stay.flow_stay`; the
decisions at a point are :mod:`~hybrid.simulation.native.boundary`'s.

Copied into the kernel module (below the ``kernel`` marker).
"""

from __future__ import annotations

import math

from hybrid.simulation.native.boundary import note_failure
from hybrid.simulation.native.buffers import (
    ASK_ENTRY,
    ASK_LEFT,
    CF_T_END,
    CF_T_START,
    CI_MAX_JUMPS,
    CI_PER_INSTANT,
    CI_ZENO,
    D_BLOCKED_ENTRY,
    D_INITIAL,
    D_NONE,
    D_RESET_NONFINITE,
    D_STALL,
    D_URGENT,
    D_ZENO_GEOMETRIC,
    D_ZENO_INSTANT,
    F_RESET,
    FP_DECIDE,
    FP_MODEL,
    FP_SEARCH,
    FP_STAY,
    FP_STEP,
    I_CAUSE,
    N_SCALARS,
    OP_RESET,
    S_FLOW_FAIL,
    S_GEN,
    S_REACHED_T,
    T_LV_KEY,
    T_MAX_INV,
    T_MAX_LV,
    T_MAX_TR,
    T_MODE_TR,
    T_MODE_URGENT,
    T_N_PARAMS,
    T_N_STATES,
    T_TR_LV,
    T_TR_TARGET,
    W_AHEAD,
    W_ARMV,
    W_D,
    W_ENABLED,
    W_EXTREMES,
    W_F,
    W_FAILI,
    W_FAILX,
    W_FLOWX,
    W_INVARMED,
    W_K,
    W_NPE,
    W_NT,
    W_PE,
    W_Q,
    W_RATE,
    W_REACHED,
    W_SCAL,
    W_SIGFAIL,
    W_SIGX,
    W_TERMS,
    W_TRARMED,
    W_USED,
    W_X,
    W_XNEW,
    W_XS,
    W_Y,
    W_YNEW,
    W_YTMP,
    W_ZENO,
    WI_HEADER,
    ZENO_SIZE,
)
from hybrid.simulation.native.crossing import HORIZON_SAMPLES
from hybrid.simulation.native.kernel_types import (
    DECIDE_FN_T,
    MODEL_FN_T,
    SEARCH_FN_T,
    STAY_FN_T,
    STEP_FN_T,
    Array,
    Array2,
    Fns,
    Ints,
    at,
    function_at,
)
from hybrid.simulation.native.recorder import finish, record_jump, record_point
from hybrid.simulation.native.stay import STAY_EVENT, end_run, failed

__all__ = [
    "jump",
    "lay_out_work",
    "note_reached",
    "note_used",
    "run_one",
    "start_work",
    "zeno_update",
]

# --- kernel ---

ZENO_WINDOW = 6
ZENO_SPREAD = 0.02
ZENO_SHRINK = 1e-3
Z_LAST, Z_START, Z_GAPS, Z_RATIOS = 0, 1, 2, 3  # counts of gaps and ratios at 2 and 3
Z_GAP0 = 4  # gaps (up to window + 1, oldest first) from here
Z_RATIO0 = Z_GAP0 + ZENO_WINDOW + 1  # ratios (up to window) from here
L_T_END, L_MAX_JUMPS, L_ZENO, L_BLOCKED, L_NONFINITE, L_SOLVER_FAILURE, L_INTERRUPTED = (
    0, 1, 2, 3, 4, 5, 6,
)  # fmt: skip  # CAUSE_CODES


def lay_out_work(tab: Ints, wi: Ints) -> tuple[int, int]:
    """``wi``'s header (where each piece of the scratch starts); the lengths ``wf`` and ``wi`` need.

    It writes the header only (``WI_HEADER`` slots), so Python calls it too,
    uncompiled, on a header alone, to allocate ``wf`` and ``wi`` once per model
    (:meth:`~hybrid.simulation.native.engine.CompiledNative.buffers`): the compiled
    loop allocates nothing, so it needs no reference counting (numba's runtime).
    """
    d, max_tr, max_lv, max_inv = tab[T_N_STATES], tab[T_MAX_TR], tab[T_MAX_LV], tab[T_MAX_INV]
    n_pe = tab[T_N_PARAMS] + 2 * max_lv + 1  # parameters, level signs, snaps, the band
    sizes = (
        (W_K, 7 * d), (W_Y, d), (W_F, d), (W_YNEW, d), (W_YTMP, d), (W_XS, d), (W_Q, 4 * d),
        (W_RATE, d), (W_AHEAD, d), (W_XNEW, d), (W_TERMS, max_tr + max_inv),
        (W_ARMV, max_tr + max_lv), (W_ZENO, ZENO_SIZE), (W_FAILX, d), (W_FLOWX, d),
        (W_SIGX, d), (W_SCAL, N_SCALARS), (W_PE, n_pe), (W_X, d), (W_REACHED, d),
        (W_EXTREMES, 2 * d),
    )  # fmt: skip
    at = 0
    for slot, size in sizes:
        wi[slot] = at
        at += size
    floats = at
    at = WI_HEADER
    for slot, size in ((W_TRARMED, max_tr), (W_ENABLED, max_tr), (W_INVARMED, max_inv),
                       (W_FAILI, 3), (W_SIGFAIL, 3),
                       (W_USED, 1 + max_lv + tab.shape[0] - tab[T_LV_KEY])):  # fmt: skip
        wi[slot] = at
        at += size
    wi[W_D] = d
    wi[W_NT] = max_tr + max_inv
    wi[W_NPE] = n_pe
    return floats, at


def start_work(tab: Ints, p: Array, wf: Array, wi: Ints) -> None:
    """The scratch space (``wf``, ``wi``, sized by :func:`lay_out_work`) as a run starts:
    laid out, the run's parameter vector with the level slots after the parameters among it."""
    lay_out_work(tab, wi)
    for i in range(WI_HEADER, wi.shape[0]):
        wi[i] = 0
    for i in range(wf.shape[0]):
        wf[i] = 0.0
    n_pe = wi[W_NPE]
    pe = wi[W_PE]
    for i in range(p.shape[0]):
        wf[pe + i] = p[i]
    for i in range(p.shape[0], n_pe):
        wf[pe + i] = 1.0
    z = wi[W_ZENO]
    for i in range(ZENO_SIZE):
        wf[z + i] = math.nan
    wf[z + Z_GAPS] = 0.0
    wf[z + Z_RATIOS] = 0.0
    sc = wi[W_SCAL]
    for i in range(N_SCALARS):
        wf[sc + i] = math.nan
    wf[sc + S_FLOW_FAIL] = 0.0
    wf[sc + S_GEN] = 0.0
    ext = wi[W_EXTREMES]
    for i in range(wi[W_D]):
        wf[ext + i] = math.inf
        wf[ext + wi[W_D] + i] = -math.inf


def zeno_update(z: Array, t: float) -> float:
    """Record a jump at ``t``; the estimated accumulation time if Zeno, else NaN."""
    if z[Z_LAST] != z[Z_LAST]:
        z[Z_LAST] = t
        return math.nan
    gap = t - z[Z_LAST]
    z[Z_LAST] = t
    if gap <= 0.0:
        return math.nan  # zero-time jumps are counted by the per-instant cap
    n_gaps = int(z[Z_GAPS])
    n_ratios = int(z[Z_RATIOS])
    if n_gaps > 0:
        ratio = gap / z[Z_GAP0 + n_gaps - 1]
        if n_ratios == ZENO_WINDOW:
            for i in range(ZENO_WINDOW - 1):
                z[Z_RATIO0 + i] = z[Z_RATIO0 + i + 1]
            n_ratios -= 1
        z[Z_RATIO0 + n_ratios] = ratio
        n_ratios += 1
    if n_gaps == ZENO_WINDOW + 1:
        for i in range(ZENO_WINDOW):
            z[Z_GAP0 + i] = z[Z_GAP0 + i + 1]
        n_gaps -= 1
    z[Z_GAP0 + n_gaps] = gap
    n_gaps += 1
    z[Z_GAPS] = n_gaps
    z[Z_RATIOS] = n_ratios
    if n_ratios < ZENO_WINDOW:
        return math.nan
    latest = z[Z_RATIO0 + n_ratios - 1]
    limit = ZENO_SPREAD * latest
    for i in range(n_ratios):
        r = z[Z_RATIO0 + i]
        if not (0.0 < r < 1.0 and abs(r - latest) <= limit):
            z[Z_START] = math.nan
            return math.nan
    if z[Z_START] != z[Z_START]:
        z[Z_START] = z[Z_GAP0]
    if gap > ZENO_SHRINK * z[Z_START]:
        return math.nan
    estimate: float = t + gap * latest / (1.0 - latest)
    return estimate


def note_used(tab: Ints, tr: int, wi: Ints) -> None:
    """The levels the guard of transition ``tr`` reads are used at this instant."""
    used = wi[W_USED]
    for lv in range(tab[tab[T_TR_LV] + tr], tab[tab[T_TR_LV] + tr + 1]):
        key = tab[tab[T_LV_KEY] + lv]
        n = wi[used]
        seen = False
        for i in range(n):
            if wi[used + 1 + i] == key:
                seen = True
        if not seen:
            wi[used + 1 + n] = key
            wi[used] = n + 1


def note_reached(tab: Ints, m: int, t: float, x: Array, wf: Array, wi: Ints) -> None:
    """A stay in mode ``m`` stopped at ``(t, x)``: the levels reached there; the levels
    of the guards disarmed in it (``wi``'s armed flags) are used."""
    reached = wi[W_REACHED]
    for i in range(x.shape[0]):
        wf[reached + i] = x[i]
    wf[wi[W_SCAL] + S_REACHED_T] = t
    wi[wi[W_USED]] = 0
    first = tab[tab[T_MODE_TR] + m]
    for k in range(tab[tab[T_MODE_TR] + m + 1] - first):
        if wi[wi[W_TRARMED] + k] == 0:
            note_used(tab, first + k, wi)


def jump(fns: Fns, tab: Ints, pts: Array2, jps: Array2, oi: Ints, m: int, tr: int, t: float,
         j: int, x: Array, wf: Array, wi: Ints) -> bool:  # fmt: skip
    """Take transition ``tr`` at ``t``: reset into ``x``, record the jump and the new point."""
    d = wi[W_D]
    x_new = wf[wi[W_XNEW] : wi[W_XNEW] + d]
    fns(OP_RESET, tr, t, at(x, 0), at(wf, wi[W_PE]), at(x_new, 0))
    failed = False
    for i in range(d):
        if x_new[i] != x_new[i]:
            failed = True
    if failed:  # as a reset that raises: every value NaN, the failure named
        note_failure(F_RESET, tr, m, t, x, wf, wi)
        for i in range(d):
            x_new[i] = math.nan
    if not record_jump(tab, jps, oi, t, j, m, tr, x, x_new, wi):
        return False
    for i in range(d):
        x[i] = x_new[i]
    return record_point(fns, pts, oi, t, j + 1, tab[tab[T_TR_TARGET] + tr], x, wf, wi)


def run_one(fp: Ints, tab: Ints, p: Array, x0: Array, t0: float, m0: int, cfg_f: Array,
            cfg_i: Ints, pts: Array2, jps: Array2, sts: Array2, oi: Ints, of: Array,
            flag: Ints, wf: Array, wi: Ints) -> None:  # fmt: skip
    """Simulate from ``(t0, x0)`` in mode ``m0`` until the run ends; all of it into the arrays.

    ``fp`` holds the addresses of the model and of the kernel's pieces (``FP_*``).
    ``oi`` and ``of`` are reset first (as :func:`~hybrid.simulation.native.buffers.allocate`
    leaves them), so a run may reuse the arrays of the last; rows of ``pts``, ``jps``
    and ``sts`` are written whole before they are counted. ``wf`` and ``wi`` are the
    run's scratch space, sized by :func:`lay_out_work` (the run's state is kept there).
    """
    for i in range(oi.shape[0]):
        oi[i] = 0
    oi[I_CAUSE] = -1
    for i in range(of.shape[0]):
        of[i] = math.nan
    fns = function_at(fp[FP_MODEL], fp[FP_MODEL + 1], MODEL_FN_T)
    step = function_at(fp[FP_STEP], fp[FP_STEP + 1], STEP_FN_T)
    search = function_at(fp[FP_SEARCH], fp[FP_SEARCH + 1], SEARCH_FN_T)
    decide = function_at(fp[FP_DECIDE], fp[FP_DECIDE + 1], DECIDE_FN_T)
    stay_fn = function_at(fp[FP_STAY], fp[FP_STAY + 1], STAY_FN_T)
    start_work(tab, p, wf, wi)
    x = wf[wi[W_X] : wi[W_X] + x0.shape[0]]
    for i in range(x0.shape[0]):
        x[i] = x0[i]
    t, m, j = t0, m0, 0
    t_end = cfg_f[CF_T_END]
    spacing = (t_end - cfg_f[CF_T_START]) / HORIZON_SAMPLES
    max_jumps, per_instant = cfg_i[CI_MAX_JUMPS], cfg_i[CI_PER_INSTANT]
    for i in range(x.shape[0]):
        if not math.isfinite(x[i]):
            finish(oi, of, L_NONFINITE, t, j, m, D_INITIAL, 0, math.nan, wf, wi)
            return
    if not record_point(fns, pts, oi, t, j, m, x, wf, wi):
        return
    same_instant, last_jump_t, stalls, stay = 0, math.nan, 0, 0
    while True:
        if failed(wi):
            end_run(oi, of, L_NONFINITE, t, j, m, D_NONE, 0, math.nan, wf, wi)
            return
        if flag[0] != 0:
            finish(oi, of, L_INTERRUPTED, t, j, m, D_NONE, 0, math.nan, wf, wi)
            return
        chosen = decide(ASK_ENTRY, fns, tab, m, t, x, wf, wi)
        if failed(wi):
            continue  # ends as nonfinite above
        if chosen < 0 and tab[tab[T_MODE_URGENT] + m] != 0:  # no time may pass here
            finish(oi, of, L_BLOCKED, t, j, m, D_URGENT, 0, math.nan, wf, wi)
            return
        if chosen < 0:
            left = decide(ASK_LEFT, fns, tab, m, t, x, wf, wi)
            if left >= 0:
                finish(oi, of, L_BLOCKED, t, j, m, D_BLOCKED_ENTRY, left, math.nan, wf, wi)
                return
            if t >= t_end:  # a jump landed exactly at t_end: nothing left to flow
                finish(oi, of, L_T_END, t, j, m, D_NONE, 0, math.nan, wf, wi)
                return
            outcome, t_after, chosen = stay_fn(fns, step, search, decide, tab, m, t, x, j, stay,
                                               spacing, cfg_f, cfg_i, pts, sts, oi, of, wf, wi,
                                               flag)  # fmt: skip
            stay += 1
            if outcome != STAY_EVENT:
                return
            t_before, t = t, t_after
            note_reached(tab, m, t, x, wf, wi)
            if chosen < 0:
                stalls = stalls + 1 if t == t_before else 0
                if stalls > per_instant:
                    finish(oi, of, L_SOLVER_FAILURE, t, j, m, D_STALL, 0, math.nan, wf, wi)
                    return
                continue
        if j >= max_jumps:
            finish(oi, of, L_MAX_JUMPS, t, j, m, D_NONE, 0, math.nan, wf, wi)
            return
        same_instant = same_instant + 1 if t == last_jump_t else 1
        last_jump_t = t
        if same_instant > per_instant:
            finish(oi, of, L_ZENO, t, j, m, D_ZENO_INSTANT, chosen, t, wf, wi)
            return
        if not jump(fns, tab, pts, jps, oi, m, chosen, t, j, x, wf, wi):
            return
        note_used(tab, chosen, wi)
        m = tab[tab[T_TR_TARGET] + chosen]
        j += 1
        if failed(wi):
            continue
        for i in range(x.shape[0]):
            if not math.isfinite(x[i]):
                finish(oi, of, L_NONFINITE, t, j, m, D_RESET_NONFINITE, chosen, math.nan, wf, wi)
                return
        if cfg_i[CI_ZENO] != 0:
            estimate = zeno_update(wf[wi[W_ZENO] : wi[W_ZENO] + ZENO_SIZE], t)
            if estimate == estimate and estimate <= t_end:
                finish(oi, of, L_ZENO, t, j, m, D_ZENO_GEOMETRIC, 0, estimate, wf, wi)
                return
