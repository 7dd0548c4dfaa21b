"""Kernel source: the Dormand–Prince 5(4) integrator with its continuous extension.

The same method, step control and interpolant as scipy's ``RK45`` (the
reference engine's default), function by function:

- :func:`rk45_step` is ``RungeKutta._step_impl`` with ``rk_step`` (error norm, SAFETY 0.9,
  factors in [0.2, 10], no growth right after a rejection, the minimum step
  ``10 * spacing(t)``, the step clamped at ``t_bound``);
- :func:`initial_step` is ``scipy.integrate._ivp.common.select_initial_step``;
- the coefficients ``q = K^T P`` computed at each accepted step and
  :func:`dense_eval` are ``RkDenseOutput`` (the DOPRI5 continuous extension,
  4th order, Shampine's optimum ``c_6``).

So a stay integrated here takes the steps scipy takes, up to rounding, and
event times agree to the root finder's tolerance. Evaluation failures of the
right-hand side (NaN) at trial points are remembered (the latest one, like :class:`hybrid.simulation.compiled.LatestFailure`): they
only matter if the step size then collapses.

Copied into the kernel module (below the ``kernel`` marker).
"""

from __future__ import annotations

import math

import numpy as np

from hybrid.simulation.native.buffers import (
    OP_RHS,
    S_FLOW_FAIL,
    S_FLOW_T,
    W_D,
    W_F,
    W_FLOWX,
    W_K,
    W_Q,
    W_RATE,
    W_SCAL,
    W_Y,
    W_YNEW,
    W_YTMP,
)
from hybrid.simulation.native.kernel_types import Array, Fns, Ints, at

__all__ = [
    "P_DENSE",
    "dense_eval",
    "eval_rhs",
    "initial_step",
    "min_step_at",
    "remember_flow_failure",
    "rk45_step",
]

# --- kernel ---

SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0
ERROR_EXPONENT = -1.0 / 5.0
TEN_EPS = 2.220446049250313e-15
"""``10 * 2**-52``, exactly: ``10 * spacing(t) <= TEN_EPS * |t|`` for every normal ``t``."""

C2, C3, C4, C5 = 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0
A21 = 1.0 / 5.0
A31, A32 = 3.0 / 40.0, 9.0 / 40.0
A41, A42, A43 = 44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0
A51, A52, A53, A54 = 19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0
A61, A62, A63 = 9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0
A64, A65 = 49.0 / 176.0, -5103.0 / 18656.0
B1, B3, B4, B5, B6 = 35.0 / 384.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0
E1, E3, E4 = -71.0 / 57600.0, 71.0 / 16695.0, -71.0 / 1920.0
E5, E6, E7 = 17253.0 / 339200.0, -22.0 / 525.0, 1.0 / 40.0

TABLEAU = np.array(
    [
        [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [A21, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [A31, A32, 0.0, 0.0, 0.0, 0.0, 0.0],
        [A41, A42, A43, 0.0, 0.0, 0.0, 0.0],
        [A51, A52, A53, A54, 0.0, 0.0, 0.0],
        [A61, A62, A63, A64, A65, 0.0, 0.0],
        [B1, 0.0, B3, B4, B5, B6, 0.0],
    ]
)  # fmt: skip
"""Stage ``s`` (1-6) evaluates at ``y + h * sum(TABLEAU[s, r] * K[r])``; row 6 is ``y_new``
(the weights B, its K[6] the derivative at the step's end). One loop over this table,
not six stages written out: half the compile time, the same sums in the same order."""
STAGE_C = np.array([0.0, C2, C3, C4, C5, 1.0, 1.0])
ERROR = np.array([E1, 0.0, E3, E4, E5, E6, E7])

P_DENSE = np.array(
    [
        [1.0, -8048581381.0 / 2820520608.0, 8663915743.0 / 2820520608.0,
         -12715105075.0 / 11282082432.0],
        [0.0, 0.0, 0.0, 0.0],
        [0.0, 131558114200.0 / 32700410799.0, -68118460800.0 / 10900136933.0,
         87487479700.0 / 32700410799.0],
        [0.0, -1754552775.0 / 470086768.0, 14199869525.0 / 1410260304.0,
         -10690763975.0 / 1880347072.0],
        [0.0, 127303824393.0 / 49829197408.0, -318862633887.0 / 49829197408.0,
         701980252875.0 / 199316789632.0],
        [0.0, -282668133.0 / 205662961.0, 2019193451.0 / 616988883.0,
         -1453857185.0 / 822651844.0],
        [0.0, 40617522.0 / 29380423.0, -110615467.0 / 29380423.0, 69997945.0 / 29380423.0],
    ]
)  # fmt: skip


def remember_flow_failure(t: float, x: Array, out: Array, wf: Array, wi: Ints) -> None:
    """If ``out`` (the right-hand side at ``(t, x)``) has a NaN, remember where (the latest wins)."""
    for i in range(out.shape[0]):
        if out[i] != out[i]:
            sc = wi[W_SCAL]
            wf[sc + S_FLOW_FAIL] = 1.0
            wf[sc + S_FLOW_T] = t
            fx = wi[W_FLOWX]
            for k in range(x.shape[0]):
                wf[fx + k] = x[k]
            return


def eval_rhs(fns: Fns, m: int, t: float, x: Array, p: Array, out: Array, wf: Array, wi: Ints) -> None:
    """The right-hand side into ``out``; a NaN there is remembered (the latest wins)."""
    fns(OP_RHS, m, t, at(x, 0), at(p, 0), at(out, 0))
    remember_flow_failure(t, x, out, wf, wi)


def min_step_at(t: float) -> float:
    """scipy's smallest step at ``t``, ``10 * spacing(t)`` (``nextafter`` is a call into the C
    library, a twentieth of a short run's step: asked only below :data:`TEN_EPS` ``* |t|``)."""
    return 10.0 * abs(float(np.nextafter(t, math.inf)) - t)


def rk45_step(
    fns: Fns,
    m: int,
    t: float,
    t_bound: float,
    h_abs: float,
    max_step: float,
    rtol: float,
    atol: float,
    p: Array,
    wf: Array,
    wi: Ints,
) -> tuple[bool, float, float, float]:
    """One accepted step from ``(t, y)``: ``(ok, t_new, next h_abs, h)``; ok False: too small.

    On acceptance ``y_new``, ``K`` (its last row the derivative at ``t_new``)
    and the interpolant's coefficients ``q`` are in ``wf``.
    """
    d = wi[W_D]
    y = wf[wi[W_Y] : wi[W_Y] + d]
    f = wf[wi[W_F] : wi[W_F] + d]
    y_new = wf[wi[W_YNEW] : wi[W_YNEW] + d]
    z = wf[wi[W_YTMP] : wi[W_YTMP] + d]
    p_c = at(p, 0)
    k_at = wi[W_K]  # K[s, i] at wf[k_at + s * d + i] (flat: a reshape calls numba's runtime)
    # scipy's minimum step is at most ``above``: worked out only below it
    above = TEN_EPS * abs(t) + 1e-300
    min_step = min_step_at(t) if h_abs < above else 0.0
    if h_abs > max_step:
        h_abs = max_step
    elif h_abs < min_step:
        h_abs = min_step
    rejected = False
    while True:
        if h_abs < above and min_step == 0.0:
            min_step = min_step_at(t)
        if h_abs < min_step:
            return False, t, h_abs, 0.0
        t_new = t + h_abs
        if t_new - t_bound > 0.0:
            t_new = t_bound
        h = t_new - t
        h_abs = abs(h)
        for i in range(d):
            wf[k_at + i] = f[i]
        for s in range(1, 7):  # stage s at y + h * sum(A[s, r] K[r]); the 7th at y_new
            into = y_new if s == 6 else z
            for i in range(d):
                acc = wf[k_at + i] * TABLEAU[s, 0]
                for r in range(1, s):
                    if TABLEAU[s, r] != 0.0:
                        acc += wf[k_at + r * d + i] * TABLEAU[s, r]
                into[i] = y[i] + acc * h
            t_stage = t + STAGE_C[s] * h
            k_s = wf[k_at + s * d : k_at + (s + 1) * d]
            fns(OP_RHS, m, t_stage, at(into, 0), p_c, at(k_s, 0))
            for i in range(d):
                if k_s[i] != k_s[i]:
                    remember_flow_failure(t_stage, into, k_s, wf, wi)
                    break
        total = 0.0
        for i in range(d):
            scale = atol + max(abs(y[i]), abs(y_new[i])) * rtol
            e = wf[k_at + i] * ERROR[0]
            for r in range(1, 7):
                if ERROR[r] != 0.0:
                    e += wf[k_at + r * d + i] * ERROR[r]
            e = e * h / scale
            total += e * e
        error_norm = math.sqrt(total) / math.sqrt(d) if d > 0 else 0.0
        if error_norm < 1.0:
            if error_norm == 0.0:
                factor = MAX_FACTOR
            else:
                factor = SAFETY * error_norm**ERROR_EXPONENT
                if not factor < MAX_FACTOR:
                    factor = MAX_FACTOR
            if rejected and not factor < 1.0:
                factor = 1.0
            q = wi[W_Q]
            for i in range(d):
                for c in range(4):
                    acc = 0.0
                    for s in range(7):
                        acc += wf[k_at + s * d + i] * P_DENSE[s, c]
                    wf[q + 4 * i + c] = acc
            return True, t_new, h_abs * factor, h
        factor = SAFETY * error_norm**ERROR_EXPONENT
        if not factor > MIN_FACTOR:  # also when the error is NaN (a failing right-hand side)
            factor = MIN_FACTOR
        h_abs *= factor
        rejected = True


def initial_step(
    fns: Fns,
    m: int,
    t0: float,
    t_bound: float,
    max_step: float,
    rtol: float,
    atol: float,
    p: Array,
    wf: Array,
    wi: Ints,
) -> float:
    """scipy's ``select_initial_step`` for order 4 from ``(t0, y)`` with ``f = rhs(t0, y)``."""
    d = wi[W_D]
    y = wf[wi[W_Y] : wi[W_Y] + d]
    f = wf[wi[W_F] : wi[W_F] + d]
    z = wf[wi[W_YTMP] : wi[W_YTMP] + d]
    f1 = wf[wi[W_RATE] : wi[W_RATE] + d]
    if d == 0:
        return math.inf
    interval = abs(t_bound - t0)
    if interval == 0.0:
        return 0.0
    s0 = 0.0
    s1 = 0.0
    for i in range(d):
        scale = atol + abs(y[i]) * rtol
        s0 += (y[i] / scale) ** 2
        s1 += (f[i] / scale) ** 2
    d0 = math.sqrt(s0) / math.sqrt(d)
    d1 = math.sqrt(s1) / math.sqrt(d)
    h0 = 1e-6 if (d0 < 1e-5 or d1 < 1e-5) else 0.01 * d0 / d1
    if interval < h0:
        h0 = interval
    for i in range(d):
        z[i] = y[i] + h0 * f[i]
    eval_rhs(fns, m, t0 + h0, z, p, f1, wf, wi)
    s2 = 0.0
    for i in range(d):
        scale = atol + abs(y[i]) * rtol
        s2 += ((f1[i] - f[i]) / scale) ** 2
    d2 = math.sqrt(s2) / math.sqrt(d) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / 5.0)
    return min(100.0 * h0, h1, interval, max_step)


def dense_eval(t: float, t_old: float, h: float, wf: Array, wi: Ints, out: Array) -> None:
    """``out`` = the step's interpolant at ``t`` (``RkDenseOutput``; ``y`` and ``q`` read in ``wf``).

    Flat indices rather than a ``(d, 4)`` view of ``q``: a reshape inside the
    compiled code is a call into numba's runtime helper, each time.
    """
    s = (t - t_old) / h
    p2 = s * s
    p3 = p2 * s
    p4 = p3 * s
    y = wi[W_Y]
    q = wi[W_Q]
    for i in range(out.shape[0]):
        c = q + 4 * i
        out[i] = h * (wf[c] * s + wf[c + 1] * p2 + wf[c + 2] * p3 + wf[c + 3] * p4) + wf[y + i]
