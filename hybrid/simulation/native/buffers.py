"""The arrays a compiled run fills, and the codes it leaves in them.

Python allocates :class:`RunArrays` per run (or per chunk of an ensemble, one
row per run) and reads them back when the compiled loop returns, and the
loop's scratch space beside them (``wf``, ``wi``: the compiled code allocates
nothing, so it runs without numba's reference counting); the loop reads the
model's tables from one integer array (``tab``). A few plain
arrays, not structures: numba compiles functions of a few array arguments
many times faster than functions of records of many arrays. This module
imports no numba: the Python side reads the layouts below without it, and
the kernel reads them as constants.

The slot constants index ``oi`` (integers) and ``of`` (floats);
``CAUSE_CODES`` follows :data:`hybrid.simulation.result.CAUSES`.

Examples
--------
>>> b = allocate(n_states=2, n_signals=1, max_transitions=1, points=4, jumps=2)
>>> b.pts.shape, b.jps.shape, int(b.oi[I_CAUSE])
((4, 6), (2, 9), -1)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "ASK_ENTRY",
    "ASK_EVENT",
    "ASK_LEFT",
    "ASK_WATCH",
    "CAUSE_CODES",
    "CF_ATOL",
    "CF_DT",
    "CF_MAX_STEP",
    "CF_RTOL",
    "CF_T_END",
    "CF_T_START",
    "CI_DENSE",
    "CI_MAX_JUMPS",
    "CI_PER_INSTANT",
    "CI_ZENO",
    "D_BLOCKED_ENTRY",
    "D_BLOCKED_FLOW",
    "D_CRAWL",
    "D_EVAL",
    "D_FLOW",
    "D_FLOW_START",
    "D_INITIAL",
    "D_NONE",
    "D_NOT_ADVANCING",
    "D_RESET_NONFINITE",
    "D_STALL",
    "D_STATE_NONFINITE",
    "D_STEP_TOO_SMALL",
    "D_URGENT",
    "D_ZENO_GEOMETRIC",
    "D_ZENO_INSTANT",
    "FP_DECIDE",
    "FP_MODEL",
    "FP_RUN",
    "FP_SEARCH",
    "FP_STAY",
    "FP_STEP",
    "F_AUX0",
    "F_AUX1",
    "F_FAIL_T",
    "F_FLOW",
    "F_GUARD",
    "F_INVARIANT",
    "F_NONE",
    "F_NOW",
    "F_PEAK",
    "F_RESET",
    "F_SIGNALS",
    "F_T",
    "F_ZENO_TIME",
    "I_CAUSE",
    "I_DETAIL",
    "I_DETAIL_INDEX",
    "I_FAIL_INDEX",
    "I_FAIL_KIND",
    "I_FAIL_MODE",
    "I_J",
    "I_JUMPS",
    "I_MODE",
    "I_OVERFLOW",
    "I_POINTS",
    "I_RHS_CALLS",
    "I_STEPS",
    "I_STORED_STEPS",
    "J_J",
    "J_KEY",
    "J_T",
    "J_TR",
    "J_X",
    "N_CFG_F",
    "N_CFG_I",
    "N_FP",
    "N_OUT_F",
    "N_OUT_I",
    "N_SCALARS",
    "OP_ARM",
    "OP_OUTPUTS",
    "OP_RESET",
    "OP_RHS",
    "OP_TRUTH",
    "OP_VALUE",
    "OP_WATCH",
    "PACKED_WIDTH",
    "P_J",
    "P_M",
    "P_T",
    "P_X",
    "Q_H",
    "Q_J",
    "Q_STAY",
    "Q_T0",
    "Q_TV",
    "Q_Y",
    "S_B0",
    "S_FAIL_T",
    "S_FLOW_FAIL",
    "S_FLOW_T",
    "S_GEN",
    "S_LAST_STEP",
    "S_REACHED_T",
    "S_SIG_T",
    "TABLES",
    "TAB_HEADER",
    "T_INV_BOOL",
    "T_INV_RHO",
    "T_LV_KEY",
    "T_MAX_INV",
    "T_MAX_LV",
    "T_MAX_TR",
    "T_MODE_INV",
    "T_MODE_TR",
    "T_MODE_URGENT",
    "T_N_PARAMS",
    "T_N_SIGNALS",
    "T_N_STATES",
    "T_TR_BOOL",
    "T_TR_LV",
    "T_TR_PRIORITY",
    "T_TR_RHO",
    "T_TR_SBOOL",
    "T_TR_SRHO",
    "T_TR_TARGET",
    "WI_HEADER",
    "W_AHEAD",
    "W_ARMV",
    "W_D",
    "W_ENABLED",
    "W_EXTREMES",
    "W_F",
    "W_FAILI",
    "W_FAILX",
    "W_FLOWX",
    "W_INVARMED",
    "W_K",
    "W_NPE",
    "W_NT",
    "W_PE",
    "W_Q",
    "W_RATE",
    "W_REACHED",
    "W_SCAL",
    "W_SIGFAIL",
    "W_SIGX",
    "W_TERMS",
    "W_TRARMED",
    "W_USED",
    "W_X",
    "W_XNEW",
    "W_XS",
    "W_Y",
    "W_YNEW",
    "W_YTMP",
    "W_ZENO",
    "ZENO_SIZE",
    "RunArrays",
    "allocate",
]

CAUSE_CODES = ("t_end", "max_jumps", "zeno", "blocked", "nonfinite", "solver_failure", "interrupted")
"""Termination cause by code (the order of ``hybrid.simulation.result.CAUSES``)."""

# out_i slots
I_POINTS, I_JUMPS, I_STORED_STEPS, I_CAUSE, I_J, I_MODE = 0, 1, 2, 3, 4, 5
I_DETAIL, I_DETAIL_INDEX, I_OVERFLOW, I_RHS_CALLS, I_STEPS = 6, 7, 8, 9, 10
I_FAIL_KIND, I_FAIL_INDEX, I_FAIL_MODE = 11, 12, 13
N_OUT_I = 16
# out_f slots (F_NOW: the time reached so far, for progress; F_AUX*: numbers for a message)
F_T, F_ZENO_TIME, F_FAIL_T, F_NOW, F_AUX0, F_AUX1, F_PEAK = 0, 1, 2, 3, 4, 5, 6
N_OUT_F = 8

# the run's settings: cfg_f (floats) and cfg_i (integers)
CF_T_END, CF_RTOL, CF_ATOL, CF_MAX_STEP, CF_DT, CF_T_START = 0, 1, 2, 3, 4, 5
N_CFG_F = 6
CI_MAX_JUMPS, CI_ZENO, CI_PER_INSTANT, CI_DENSE = 0, 1, 2, 3
N_CFG_I = 4

# what ended the run, beyond its cause (for the message)
D_NONE, D_INITIAL, D_BLOCKED_ENTRY, D_BLOCKED_FLOW, D_STALL = 0, 1, 2, 3, 4
D_ZENO_INSTANT, D_ZENO_GEOMETRIC, D_RESET_NONFINITE, D_EVAL, D_FLOW = 5, 6, 7, 8, 9
D_STEP_TOO_SMALL, D_STATE_NONFINITE, D_FLOW_START, D_NOT_ADVANCING, D_CRAWL = 10, 11, 12, 13, 14
D_URGENT = 15

# which compiled function could not be evaluated (out_i[I_FAIL_KIND])
F_NONE, F_GUARD, F_INVARIANT, F_SIGNALS, F_RESET, F_FLOW = 0, 1, 2, 3, 4, 5


# what the model's one compiled function computes: fns(op, index, t, x*, p*, out*)
OP_RHS, OP_OUTPUTS, OP_VALUE, OP_TRUTH, OP_RESET, OP_WATCH, OP_ARM = 0, 1, 2, 3, 4, 5, 6

# the addresses the compiled loop calls (``fp``): C wrapper, then compiled code, of each
FP_MODEL, FP_STEP, FP_SEARCH, FP_DECIDE, FP_STAY, FP_RUN = 0, 2, 4, 6, 8, 10
N_FP = 12

# what the decisions piece is asked (``pieces.decide``)
ASK_ENTRY, ASK_EVENT, ASK_LEFT, ASK_WATCH = 0, 1, 2, 3

# the model's tables (one int64 array, ``tab``): sizes, then where each table starts
T_N_STATES, T_N_SIGNALS, T_MAX_TR, T_MAX_LV, T_MAX_INV, T_N_PARAMS = 0, 1, 2, 3, 4, 5
T_MODE_TR, T_MODE_INV, T_TR_TARGET, T_TR_PRIORITY, T_TR_RHO, T_TR_BOOL = 6, 7, 8, 9, 10, 11
T_TR_SRHO, T_TR_SBOOL, T_TR_LV, T_INV_RHO, T_INV_BOOL, T_MODE_URGENT = 12, 13, 14, 15, 16, 17
T_LV_KEY = 18  # a level's key (hybrid.expr.rho.level_key) as a number
TAB_HEADER = 19
TABLES = (
    "MODE_TR", "MODE_INV", "TR_TARGET", "TR_PRIORITY", "TR_RHO", "TR_BOOL",
    "TR_SRHO", "TR_SBOOL", "TR_LV", "INV_RHO", "INV_BOOL", "MODE_URGENT", "LV_KEY",
)  # fmt: skip
"""The tables in ``tab`` order (from ``T_MODE_TR`` on; ``LV_KEY`` last, its length the
number of levels of all modes)."""

# the scratch space of a run: ``wf`` (floats) and ``wi`` (integers); wi's header says
# where each piece starts (float pieces in wf, integer pieces in wi)
W_D, W_NT = 0, 1
W_K, W_Y, W_F, W_YNEW, W_YTMP, W_XS, W_Q, W_RATE, W_AHEAD, W_XNEW = 2, 3, 4, 5, 6, 7, 8, 9, 10, 11
W_PE, W_TERMS, W_ARMV, W_ZENO, W_FAILX, W_FLOWX, W_SIGX, W_SCAL = 12, 13, 14, 15, 16, 17, 18, 19
W_TRARMED, W_ENABLED, W_INVARMED, W_FAILI, W_SIGFAIL = 20, 21, 22, 23, 24
W_NPE, W_X = 25, 26  # W_X: the run's state (a float piece)
W_USED = 27  # keys of the levels used at this instant: count, then keys
W_REACHED = 28  # the state where the last stay stopped (a float piece)
W_EXTREMES = 29  # the smallest, then the largest value of each state over the stored points
WI_HEADER = 30
# scalars in wf from wi[W_SCAL]
# (S_B0: the band at the start of the stay, the shift of the watch's disarmed terms;
# S_REACHED_T: when the last stay stopped, where W_REACHED holds the state)
S_FAIL_T, S_FLOW_FAIL, S_FLOW_T, S_LAST_STEP, S_SIG_T, S_GEN, S_B0, S_REACHED_T = range(8)
N_SCALARS = 8
ZENO_SIZE = 17  # last t, start gap, counts (2), 7 gaps, 6 ratios

# columns of the recorded arrays
P_T, P_J, P_M, P_X = 0, 1, 2, 3  # pts: t, j, mode, state..., signals...
# jps: t, j, transition, key (transition and enabled flags packed), before..., after..., enabled...
J_T, J_J, J_TR, J_KEY, J_X = 0, 1, 2, 3, 4
PACKED_WIDTH = 32
"""Most enabled flags a jump's ``J_KEY`` packs: ``transition * 2**width`` plus ``2**k`` per
enabled flag ``k`` (``width`` flag columns); -1 for wider rows."""
Q_T0, Q_H, Q_TV, Q_J, Q_STAY, Q_Y = 0, 1, 2, 3, 4, 5  # sts: t_old, h, valid to, j, stay, y, q


@dataclass(frozen=True)
class RunArrays:
    """What one run records (one row of each per run in an ensemble chunk).

    ``pts``: points ``(t, j, mode, x..., signals...)``; ``jps``: jumps ``(t, j,
    transition, key, before..., after..., enabled flags...)`` (the key packs the
    transition and its flags, :data:`PACKED_WIDTH`); ``sts``: dense steps
    ``(t_old, h, valid to, j, stay, y_old..., q...)``; ``oi`` and ``of``: the
    counts and the termination (slots ``I_*`` and ``F_*``), the point of an
    evaluation failure in ``of[N_OUT_F:]``; ``wf`` and ``wi``: the loop's scratch
    space (laid out by :func:`~hybrid.simulation.native.loop.lay_out_work`).
    """

    pts: NDArray[np.float64]
    jps: NDArray[np.float64]
    sts: NDArray[np.float64]
    oi: NDArray[np.int64]
    of: NDArray[np.float64]
    wf: NDArray[np.float64]
    wi: NDArray[np.int64]

    def row(self, r: int) -> RunArrays:
        """Run ``r`` of a chunk."""
        return RunArrays(self.pts[r], self.jps[r], self.sts[r], self.oi[r], self.of[r],
                         self.wf[r], self.wi[r])  # fmt: skip


def allocate(
    n_states: int,
    n_signals: int,
    max_transitions: int,
    points: int,
    jumps: int,
    steps: int = 1,
    runs: int | None = None,
    work: tuple[int, int] = (0, 0),
) -> RunArrays:
    """Empty arrays for one run, or with ``runs`` a leading axis of one row per run.

    ``work``: the lengths of the scratch space (``wf``, ``wi``) a run needs.
    """
    lead: tuple[int, ...] = () if runs is None else (runs,)
    d, s, width = n_states, n_signals, max(1, max_transitions)
    oi = np.zeros((*lead, N_OUT_I), dtype=np.int64)
    oi[..., I_CAUSE] = -1
    return RunArrays(
        pts=np.empty((*lead, points, P_X + d + s)),
        jps=np.zeros((*lead, jumps, J_X + 2 * d + width)),
        sts=np.empty((*lead, steps, Q_Y + 5 * d)),
        oi=oi,
        of=np.full((*lead, N_OUT_F + d), np.nan),
        wf=np.zeros((*lead, work[0])),
        wi=np.zeros((*lead, work[1]), dtype=np.int64),
    )
