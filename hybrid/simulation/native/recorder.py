"""Kernel source: recording points, jumps and steps, and the end of a run.

The compiled counterpart of :class:`hybrid.simulation.recorder.Recorder`
(``points``, ``jump``, ``stay``'s dense segments) and of building a
:class:`~hybrid.simulation.result.Termination`: everything goes into the
run's arrays (:class:`~hybrid.simulation.native.buffers.RunArrays`), which Python turns
into a :class:`~hybrid.simulation.result.Run`. Signals are computed when a
point is stored (a signal that fails ends the run there, as in the recorder).
A full buffer sets ``I_OVERFLOW`` and the call returns False: Python then runs
again with room for more.

Copied into the kernel module (below the ``kernel`` marker).
"""

from __future__ import annotations

from hybrid.simulation.native.buffers import (
    F_FAIL_T,
    F_NOW,
    F_SIGNALS,
    F_T,
    F_ZENO_TIME,
    I_CAUSE,
    I_DETAIL,
    I_DETAIL_INDEX,
    I_FAIL_INDEX,
    I_FAIL_KIND,
    I_FAIL_MODE,
    I_J,
    I_JUMPS,
    I_MODE,
    I_OVERFLOW,
    I_POINTS,
    I_STORED_STEPS,
    J_J,
    J_KEY,
    J_T,
    J_TR,
    J_X,
    N_OUT_F,
    OP_OUTPUTS,
    P_J,
    P_M,
    P_T,
    P_X,
    PACKED_WIDTH,
    Q_H,
    Q_J,
    Q_STAY,
    Q_T0,
    Q_TV,
    Q_Y,
    S_FAIL_T,
    S_SIG_T,
    T_MODE_TR,
    W_D,
    W_ENABLED,
    W_EXTREMES,
    W_FAILI,
    W_FAILX,
    W_PE,
    W_SCAL,
    W_SIGFAIL,
    W_SIGX,
)
from hybrid.simulation.native.kernel_types import Array, Array2, Fns, Ints, at

__all__ = ["finish", "record_jump", "record_point", "record_step"]

# --- kernel ---


def record_point(fns: Fns, pts: Array2, oi: Ints, t: float, j: int, m: int, x: Array, wf: Array,
                 wi: Ints) -> bool:  # fmt: skip
    """Store the point ``(t, j, m, x)`` with its signals; False if the buffer is full.

    A signal that cannot be evaluated is recorded apart (the first one): the
    reference computes a stay's signals when the stay ends, so such a failure
    ends the run only then.
    """
    n = oi[I_POINTS]
    if n >= pts.shape[0]:
        oi[I_OVERFLOW] = 1
        return False
    row = pts[n]
    row[P_T] = t
    row[P_J] = j
    row[P_M] = m
    d = x.shape[0]
    ext = wi[W_EXTREMES]
    for i in range(d):
        row[P_X + i] = x[i]
        if x[i] < wf[ext + i]:  # a NaN is neither: left out, as np.fmin leaves it
            wf[ext + i] = x[i]
        if x[i] > wf[ext + d + i]:
            wf[ext + d + i] = x[i]
    signals = row[P_X + d :]
    fns(OP_OUTPUTS, m, t, at(x, 0), at(wf, wi[W_PE]), at(signals, 0))
    for c in range(signals.shape[0]):
        if signals[c] != signals[c]:
            sig = wi[W_SIGFAIL]
            if wi[sig] == 0:
                wi[sig], wi[sig + 1], wi[sig + 2] = F_SIGNALS, m, m
                wf[wi[W_SCAL] + S_SIG_T] = t
                for i in range(d):
                    wf[wi[W_SIGX] + i] = x[i]
            break
    oi[I_POINTS] = n + 1
    return True


def record_jump(tab: Ints, jps: Array2, oi: Ints, t: float, j: int, m: int, tr: int,
                before: Array, after: Array, wi: Ints) -> bool:  # fmt: skip
    """Store a jump of global transition ``tr`` from mode ``m`` (enabled flags from ``wi``).

    ``J_KEY`` packs the transition and the flags (as
    :meth:`~hybrid.simulation.native.assemble.Layout.jump_keys` does) up to
    ``PACKED_WIDTH`` flag columns, so the assembler reads one number per jump.
    """
    n = oi[I_JUMPS]
    if n >= jps.shape[0]:
        oi[I_OVERFLOW] = 1
        return False
    row = jps[n]
    row[J_T] = t
    row[J_J] = j
    row[J_TR] = tr
    d = before.shape[0]
    for i in range(d):
        row[J_X + i] = before[i]
        row[J_X + d + i] = after[i]
    count = tab[tab[T_MODE_TR] + m + 1] - tab[tab[T_MODE_TR] + m]
    enabled = wi[W_ENABLED]
    width = row.shape[0] - J_X - 2 * d
    key = float(tr) * float(1 << width) if width <= PACKED_WIDTH else -1.0
    for k in range(width):
        on = k < count and wi[enabled + k] != 0
        row[J_X + 2 * d + k] = 1.0 if on else 0.0
        if on and width <= PACKED_WIDTH:
            key += float(1 << k)
    row[J_KEY] = key
    oi[I_JUMPS] = n + 1
    return True


def record_step(sts: Array2, oi: Ints, t_old: float, h: float, t_valid: float, j: int,
                stay: int, y_old: Array, q: Array) -> bool:  # fmt: skip
    """Store one step's interpolant (``dense=True``), valid on ``[t_old, t_valid]``."""
    n = oi[I_STORED_STEPS]
    if n >= sts.shape[0]:
        oi[I_OVERFLOW] = 1
        return False
    row = sts[n]
    row[Q_T0] = t_old
    row[Q_H] = h
    row[Q_TV] = t_valid
    row[Q_J] = j
    row[Q_STAY] = stay
    d = y_old.shape[0]
    for i in range(d):
        row[Q_Y + i] = y_old[i]
        for c in range(4):
            row[Q_Y + d + 4 * i + c] = q[4 * i + c]
    oi[I_STORED_STEPS] = n + 1
    return True


def finish(oi: Ints, of: Array, cause: int, t: float, j: int, m: int, detail: int, index: int,
           zeno_time: float, wf: Array, wi: Ints) -> None:  # fmt: skip
    """End the run: its cause, where, why, and the evaluation failure if there was one."""
    oi[I_CAUSE] = cause
    oi[I_J] = j
    oi[I_MODE] = m
    oi[I_DETAIL] = detail
    oi[I_DETAIL_INDEX] = index
    of[F_T] = t
    of[F_NOW] = t
    of[F_ZENO_TIME] = zeno_time
    fi = wi[W_FAILI]
    oi[I_FAIL_KIND] = wi[fi]
    oi[I_FAIL_INDEX] = wi[fi + 1]
    oi[I_FAIL_MODE] = wi[fi + 2]
    of[F_FAIL_T] = wf[wi[W_SCAL] + S_FAIL_T]
    fx = wi[W_FAILX]
    for i in range(wi[W_D]):
        of[N_OUT_F + i] = wf[fx + i]
