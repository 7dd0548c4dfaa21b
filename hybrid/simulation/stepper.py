"""scipy's explicit Runge-Kutta step, taken without its per-step Python wrapping.

The engine steps scipy's solvers one accepted step at a time
(:mod:`~hybrid.simulation.stay`). For ``RK45`` and ``RK23`` most of what a step
costs beyond the right-hand side is scipy's wrapping of it: every stage goes
through two wrappers (one counts the evaluations, one converts the returned list
with ``np.asarray``), the step's times are numpy scalars, the error norm goes
through ``np.linalg.norm`` and the smallest step through ``np.nextafter``. About
15 microseconds a step, on a step that a cheap model computes in 30.

:class:`SteppedRK45` and :class:`SteppedRK23` are scipy's classes with the same
step written again: the same stages (the same dot products of the same arrays:
``a.dot(b)`` is the C function ``np.dot`` wraps, without its dispatch),
the same step-size control, the same arithmetic in the same order on the same
doubles, so every accepted step, every rejected one and every interpolant is
**bit-identical** to scipy's (tests/simulation/test_sim_stepper.py compares them
step by step). What differs is only how the numbers travel: the right-hand side
is called directly, its list written into the stage row (the same conversion
``np.asarray`` makes), the times are Python floats. The right-hand side still
receives ``t`` as a numpy scalar, as from scipy, unless it is declared to take a
float (``float_time=True``: the engine's stepped flow, which converts it first
anyway); a numpy scalar does not raise where a float does, so the plain
right-hand side must see what it saw before. ``keeps=True`` (the stepped flow
again, given ``t`` as a float) says that the right-hand side keeps what it
computed for others to read at the step end
(:class:`~hybrid.expr.codegen.Stash`) unless a third argument ``False`` says
the point is only a stage: only the last evaluation of a step, at its end, is
kept.

Examples
--------
>>> import numpy as np
>>> from scipy.integrate import RK45
>>> def f(t, y): return [y[1], -y[0]]
>>> ours = SteppedRK45(f, 0.0, np.array([1.0, 0.0]), 10.0, rtol=1e-8, atol=1e-10)
>>> theirs = RK45(f, 0.0, np.array([1.0, 0.0]), 10.0, rtol=1e-8, atol=1e-10)
>>> while ours.status == "running":
...     _, _ = ours.step(), theirs.step()
...     assert ours.t == theirs.t and np.array_equal(ours.y, theirs.y)
>>> float(ours.t), theirs.status
(10.0, 'finished')
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from scipy.integrate import RK23, RK45
from scipy.integrate._ivp.common import select_initial_step, validate_first_step
from scipy.integrate._ivp.rk import MAX_FACTOR, MIN_FACTOR, SAFETY

__all__ = ["SteppedRK23", "SteppedRK45", "stepped"]

_float64 = np.float64


class _Stepped:
    """The step of scipy's ``RungeKutta._step_impl``, with Python floats around numpy's arrays."""

    # set by scipy's RungeKutta.__init__ and the class attributes of RK45 / RK23
    t: Any
    y: np.ndarray
    f: np.ndarray
    K: np.ndarray
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    E: np.ndarray
    h_abs: Any
    h_previous: Any
    y_old: Any
    max_step: Any
    rtol: Any
    atol: Any
    direction: Any
    t_bound: Any
    error_exponent: float
    error_estimator_order: int
    fun: Callable[..., Any]
    n: int
    TOO_SMALL_STEP: str

    def _stepped_setup(self, fun: Callable[..., Any], float_time: bool, keeps: bool) -> None:
        self._rhs = fun
        self._takes_float = float_time  # as constructed; a restart keeps it
        self._float_time = float_time or keeps
        self._keeps = keeps
        K = self.K  # written in place at every step: its views are made once
        # per stage: the rows of K so far (transposed), its row of A and its time, as
        # scipy's rk_step reads them (dot products of the same views of the same arrays)
        self._stages = [
            (s, K[:s].T, self.A[s][:s], float(self.C[s])) for s in range(1, len(self.C))
        ]
        self._k_body = K[:-1].T
        self._k_all = K.T

    def restart(
        self, fun: Callable[..., Any], t0: float, y0: np.ndarray, first_step: float | None,
        keeps: bool,
    ) -> None:  # fmt: skip
        """Start again at ``(t0, y0)`` with ``fun``: the solver scipy would construct there.

        The same fields, to the bit, as ``type(self)(fun, t0, y0, self.t_bound,
        first_step=first_step, keeps=keeps)`` with this solver's tolerances and
        ``max_step`` (validated when it was constructed; they are not read again):
        the derivative at the start through the same wrapper, the first step
        validated or chosen by ``select_initial_step``, the same ``ValueError`` for
        a non-finite ``y0`` or a first step out of range. A new stay of a run
        costs a few microseconds instead of scipy's 20 (its checks of every
        argument, its wrappers and ``K``): ``K`` and its stage views are kept.
        ``y0`` must be a float64 vector of this solver's size.
        """
        if not all(map(math.isfinite, y0.tolist())):
            raise ValueError("All components of the initial state `y0` must be finite.")

        def fun_wrapped(t: Any, y: np.ndarray) -> np.ndarray:  # check_arguments' wrapper
            return np.asarray(fun(t, y), dtype=float)

        self._fun = self.fun_single = fun_wrapped
        self._rhs, self._float_time, self._keeps = fun, self._takes_float or keeps, keeps
        self.t_old = None
        self.t = t0
        self.y = y0
        t_bound = self.t_bound
        self.direction = np.sign(t_bound - t0) if t_bound != t0 else 1
        self.status = "running"
        self.nfev = self.njev = self.nlu = 0
        self.y_old = None
        self.f = self.fun(t0, y0)
        if first_step is None:
            self.h_abs = select_initial_step(
                self.fun, t0, y0, t_bound, self.max_step, self.f, self.direction,
                self.error_estimator_order, self.rtol, self.atol,
            )  # fmt: skip
        else:
            self.h_abs = validate_first_step(first_step, t0, t_bound)
        self.h_previous = None

    def _step_impl(self) -> tuple[bool, str | None]:
        t = float(self.t)
        y = self.y
        max_step = self.max_step
        rtol, atol = self.rtol, self.atol
        direction = float(self.direction)
        t_bound = float(self.t_bound)
        min_step = 10 * abs(math.nextafter(t, direction * math.inf) - t)
        h_abs = float(self.h_abs)
        if h_abs > max_step:
            h_abs = float(max_step)
        elif h_abs < min_step:
            h_abs = min_step
        fun, K, B, E = self._rhs, self.K, self.B, self.E
        stages, k_body, k_all = self._stages, self._k_body, self._k_all
        as_float, keeps = self._float_time, self._keeps
        step_accepted = False
        step_rejected = False
        while not step_accepted:
            if h_abs < min_step:
                return False, self.TOO_SMALL_STEP
            h = h_abs * direction
            t_new = t + h
            if direction * (t_new - t_bound) > 0:
                t_new = t_bound
            h = t_new - t
            h_abs = abs(h)
            # rk_step
            K[0] = self.f
            if keeps:
                for s, k_s, a, c in stages:
                    K[s] = fun(t + c * h, y + k_s.dot(a) * h, False)
                y_new = y + h * k_body.dot(B)
                K[-1] = fun(t + h, y_new)
            elif as_float:
                for s, k_s, a, c in stages:
                    K[s] = fun(t + c * h, y + k_s.dot(a) * h)
                y_new = y + h * k_body.dot(B)
                K[-1] = fun(t + h, y_new)
            else:
                for s, k_s, a, c in stages:
                    K[s] = fun(_float64(t + c * h), y + k_s.dot(a) * h)
                y_new = y + h * k_body.dot(B)
                K[-1] = fun(_float64(t + h), y_new)
            # the error norm (scipy's norm: np.linalg.norm is sqrt(x . x) for a real vector)
            scale = atol + np.maximum(np.abs(y), np.abs(y_new)) * rtol
            err = k_all.dot(E) * h / scale
            error_norm = math.sqrt(float(err.dot(err))) / err.size**0.5
            if error_norm < 1:
                if error_norm == 0:
                    factor = float(MAX_FACTOR)
                else:
                    factor = min(MAX_FACTOR, SAFETY * error_norm**self.error_exponent)
                if step_rejected:
                    factor = min(1, factor)
                h_abs *= factor
                step_accepted = True
            else:
                h_abs *= max(MIN_FACTOR, SAFETY * error_norm**self.error_exponent)
                step_rejected = True
        self.h_previous = h
        self.y_old = y
        self.t = t_new
        self.y = y_new
        self.h_abs = h_abs
        self.f = K[-1].copy()
        return True, None


class SteppedRK45(_Stepped, RK45):  # type: ignore[misc]  # scipy is untyped
    """scipy's ``RK45``, its step without scipy's wrapping (bit-identical; module docstring)."""

    def __init__(
        self,
        fun: Callable[..., Any],
        *args: Any,
        float_time: bool = False,
        keeps: bool = False,
        **kwargs: Any,
    ):
        super().__init__(fun, *args, **kwargs)
        self._stepped_setup(fun, float_time, keeps)


class SteppedRK23(_Stepped, RK23):  # type: ignore[misc]  # scipy is untyped
    """scipy's ``RK23``, its step without scipy's wrapping (bit-identical; module docstring)."""

    def __init__(
        self,
        fun: Callable[..., Any],
        *args: Any,
        float_time: bool = False,
        keeps: bool = False,
        **kwargs: Any,
    ):
        super().__init__(fun, *args, **kwargs)
        self._stepped_setup(fun, float_time, keeps)


def stepped(method: type[Any]) -> type[Any] | None:
    """The stepped form of scipy's solver class ``method``, if it has one."""
    return {RK45: SteppedRK45, RK23: SteppedRK23}.get(method)
