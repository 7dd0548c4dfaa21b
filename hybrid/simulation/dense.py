"""The solver's interpolant over one accepted step, evaluated cheaply.

After each accepted step the simulator looks inside it (docs/semantics.md, "First
crossings inside a step"), so the interpolant is evaluated a few times per step
and about ten times more when a crossing is located. scipy's ``DenseOutput``
objects are general but slow for single points (about 30 microseconds for RK45,
most of it ``np.tile`` and ``np.cumprod``); the explicit Runge-Kutta methods'
interpolants are plain polynomials ``y_old + h * Q @ [x, x**2, ...]`` in
``x = (t - t_old) / h``, evaluated here with the same coefficients ``Q`` in a
few microseconds. Other methods use scipy's objects as they are.

The step end is returned exactly as the solver computed it (``x1``), not from
the interpolant: some interpolants (LSODA's) do not reproduce it to the last bit.

Examples
--------
>>> import numpy as np
>>> from scipy.integrate import RK45
>>> solver = RK45(lambda t, y: [y[1], -9.81], 0.0, np.array([10.0, 0.0]), 1.0, first_step=0.5)
>>> _ = solver.step()
>>> curve = step_curve(solver)
>>> round(float(curve.at(0.25)[0]), 12), bool(curve.at(curve.t1) is curve.x1)
(9.6934375, True)
>>> curve.many(np.array([0.1, 0.2])).shape
(2, 2)
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # scipy.integrate is imported where a step of its solvers is read
    from scipy.integrate import DenseOutput, OdeSolver

__all__ = ["StepCurve", "polynomial_curve", "step_curve"]


_FRACTIONS: dict[int, np.ndarray] = {}
_POWERS: dict[tuple[int, int], np.ndarray] = {}


def _fractions(m: int) -> np.ndarray:
    """``k / m`` for ``k = 1 .. m - 1`` (cached for the small ``m`` of most steps)."""
    found = _FRACTIONS.get(m)
    if found is None:
        found = np.arange(1, m, dtype=float) / m
        if len(_FRACTIONS) < 256:
            _FRACTIONS[m] = found
    return found


_EXPONENTS: dict[int, np.ndarray] = {}


def _exponents(n: int) -> np.ndarray:
    """``1, 2, ..., n`` as floats (read only; made once per ``n``)."""
    found = _EXPONENTS.get(n)
    if found is None:
        found = _EXPONENTS[n] = np.arange(1, n + 1, dtype=float)
        found.flags.writeable = False
    return found


class StepCurve:
    """The state over one accepted step ``[t0, t1]``: ``at(t)`` and ``many(ts)`` (rows)."""

    __slots__ = ("samples", "split", "t0", "t1", "x0", "x1")

    def __init__(self, t0: float, t1: float, x0: np.ndarray, x1: np.ndarray) -> None:
        self.t0 = t0
        self.t1 = t1
        self.x0 = x0
        self.x1 = x1
        self.split: tuple[int, np.ndarray] | None = None
        """The last :meth:`parts` asked for: the search and the monitor both cut the step so."""
        self.samples: tuple[int, list[float], list[np.ndarray]] | None = None
        """The search's samples of the whole step cut in ``m`` parts: ``(m, times, states)``,
        the step end included (read only; the monitor takes the same samples)."""

    def at(self, t: float) -> np.ndarray:
        """The state at ``t`` (exactly ``x1`` at ``t1``, ``x0`` at ``t0``)."""
        raise NotImplementedError

    def many(self, ts: np.ndarray) -> np.ndarray:
        """The states at the times ``ts`` (inside the step), one row each."""
        raise NotImplementedError

    def parts(self, m: int) -> np.ndarray:
        """The states at ``t0 + k (t1 - t0) / m`` for ``k = 1 .. m - 1``, one row each.

        The array is shared by the callers that ask for the same ``m`` (read only).
        """
        split = self.split
        if split is not None and split[0] == m:
            return split[1]
        rows = self._parts(m)
        self.split = (m, rows)
        return rows

    def _parts(self, m: int) -> np.ndarray:
        return self.many(self.t0 + (self.t1 - self.t0) * _fractions(m))

    def dense_output(self) -> DenseOutput:
        """A scipy ``DenseOutput`` of the step (kept in ``run.segments`` with ``dense=True``)."""
        raise NotImplementedError


class _PolynomialCurve(StepCurve):
    """An explicit Runge-Kutta interpolant: ``x0 + h * Q @ [s, s**2, ...]``, ``s = (t - t0) / h``."""

    __slots__ = ("h", "powers", "q")

    def __init__(self, t0: float, t1: float, x0: np.ndarray, x1: np.ndarray, q: np.ndarray) -> None:
        super().__init__(t0, t1, x0, x1)
        self.h = t1 - t0
        self.q = q
        self.powers = _exponents(q.shape[1])

    def at(self, t: float) -> np.ndarray:
        if t == self.t1:
            return self.x1
        if t == self.t0:
            return self.x0
        s = (t - self.t0) / self.h
        p = [s]
        for _ in range(len(self.powers) - 1):
            p.append(p[-1] * s)
        result: np.ndarray = self.x0 + self.h * self.q.dot(p)
        return result

    def many(self, ts: np.ndarray) -> np.ndarray:
        s = (ts - self.t0) / self.h
        p = s[None, :] ** self.powers[:, None]
        result: np.ndarray = (self.x0[:, None] + self.h * self.q.dot(p)).T
        return result

    def _parts(self, m: int) -> np.ndarray:
        key = (m, self.q.shape[1])
        p = _POWERS.get(key)
        if p is None:
            p = _fractions(m)[None, :] ** np.arange(1, key[1] + 1, dtype=float)[:, None]
            if len(_POWERS) < 256:
                _POWERS[key] = p
        result: np.ndarray = (self.x0[:, None] + self.h * self.q.dot(p)).T
        return result

    def dense_output(self) -> DenseOutput:
        from scipy.integrate._ivp.rk import RkDenseOutput

        return RkDenseOutput(self.t0, self.t1, self.x0, self.q)


class _SolverCurve(StepCurve):
    """Any other method: scipy's own interpolant of the step."""

    __slots__ = ("interpolant",)

    def __init__(self, t0: float, t1: float, x0: np.ndarray, x1: np.ndarray, dense: Any) -> None:
        super().__init__(t0, t1, x0, x1)
        self.interpolant = dense

    def at(self, t: float) -> np.ndarray:
        if t == self.t1:
            return self.x1
        if t == self.t0:
            return self.x0
        result: np.ndarray = self.interpolant(t)
        return result

    def many(self, ts: np.ndarray) -> np.ndarray:
        result: np.ndarray = np.asarray(self.interpolant(ts)).reshape(len(self.x1), -1).T
        return result

    def dense_output(self) -> DenseOutput:
        dense: DenseOutput = self.interpolant
        return dense


_RUNGE_KUTTA: tuple[type, ...] = ()
"""scipy's explicit Runge-Kutta solvers whose steps are polynomials (set on the first step)."""


def _runge_kutta() -> tuple[type, ...]:
    global _RUNGE_KUTTA
    from scipy.integrate import RK23, RK45

    _RUNGE_KUTTA = (RK45, RK23)
    return _RUNGE_KUTTA


def step_curve(solver: OdeSolver, x0: np.ndarray | None = None) -> StepCurve:
    """The curve of ``solver``'s last accepted step (``x0``: the state at its start, if known)."""
    t0, t1 = float(solver.t_old), float(solver.t)
    x1 = solver.y.copy()
    if isinstance(solver, _RUNGE_KUTTA or _runge_kutta()):
        rk: Any = solver  # RK45 or RK23: their stages and interpolation matrix
        start = rk.y_old.copy() if x0 is None else x0
        return _PolynomialCurve(t0, t1, start, x1, rk.K.T.dot(rk.P))
    dense = solver.dense_output()
    start = np.asarray(dense(t0), dtype=float) if x0 is None else x0
    return _SolverCurve(t0, t1, start, x1, dense)


def polynomial_curve(t0: float, t1: float, x0: np.ndarray, q: np.ndarray) -> StepCurve:
    """The curve ``x0 + h q @ [s, s**2, ...]`` of a Runge-Kutta step ``[t0, t1]``, ``h = t1 - t0``.

    The step's end state is the polynomial at ``s = 1`` (a compiled run keeps
    ``x0`` and ``q`` of each step, as ``RkDenseOutput`` does).

    Examples
    --------
    >>> curve = polynomial_curve(1.0, 3.0, np.array([0.0]), np.array([[0.5, 0.25]]))
    >>> float(curve.x1[0]), float(curve.at(2.0)[0])   # h (q1 + q2); at s = 1/2, h (q1/2 + q2/4)
    (1.5, 0.625)
    """
    h = t1 - t0
    x1 = x0 + h * q.sum(axis=1)
    return _PolynomialCurve(t0, t1, x0, x1, q)
