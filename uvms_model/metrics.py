"""Measures of a simulated mission: smoothness, switches, the index, the vehicle's effort.

All functions read a :class:`hybrid.Run` (ideally recorded on a uniform grid with
``dt``, e.g. 1 ms, which also keeps both rows of every jump) and return plain floats.

* :func:`windowed_change`: the largest change of a signal within any time window of a
  given width (20 ms for the smoothness figure). Unlike a comparison of the two rows
  of a jump (which reads ~1e-16 for any rate built from continuous states), it sees a
  step or a steep ramp wherever it happens.
* :func:`jump_steps`: the change of a signal across each jump (both rows share ``t``),
  for the accelerations at the automaton's switches.
* :func:`vehicle_energy` and :func:`vehicle_travel_time`: the effort the strategy
  saves against an always-on vehicle (:math:`\\int |v|^2 dt`, time with
  :math:`|v|` above a threshold).

Examples
--------
>>> import numpy as np
>>> t = np.linspace(0.0, 1.0, 1001)
>>> float(round(windowed_change(t, np.where(t < 0.5, 0.0, 1.0), 0.02), 12))
1.0
>>> float(round(windowed_change(t, 0.5 * t, 0.02), 12))   # a ramp of 0.5/s: 0.01 in 20 ms
0.01
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

__all__ = [
    "jump_steps",
    "trapezoid",
    "vehicle_energy",
    "vehicle_travel_time",
    "windowed_change",
]

FloatArray = npt.NDArray[np.float64]


def windowed_change(t: Sequence[float] | FloatArray, values: Sequence[float] | FloatArray,
                    window: float) -> float:  # fmt: skip
    """Largest ``|v(b) - v(a)|`` over recorded points with ``0 <= t_b - t_a <= window``.

    Parameters
    ----------
    t : array of float
        Non-decreasing times (jumps give two points with the same time).
    values : array of float
        The signal at those times.
    window : float
        Window width, s (positive).

    Returns
    -------
    float
        The largest change within any window; 0.0 for fewer than two points.
    """
    if not window > 0.0:
        raise ValueError("window must be positive")
    tt = np.asarray(t, dtype=np.float64)
    vv = np.asarray(values, dtype=np.float64)
    if tt.shape != vv.shape or tt.ndim != 1:
        raise ValueError("t and values must be 1-D arrays of the same length")
    best = 0.0
    n = len(tt)
    k = 1
    tol = 1e-12 * max(1.0, float(np.max(np.abs(tt)))) if n else 0.0
    while k < n:
        span = tt[k:] - tt[:-k]
        inside = span <= window + tol
        if not np.any(inside):
            break
        best = max(best, float(np.max(np.abs(vv[k:] - vv[:-k])[inside])))
        k += 1
    return best


def jump_steps(t: Sequence[float] | FloatArray, j: Sequence[int] | npt.NDArray[np.int64],
               values: Sequence[float] | FloatArray) -> list[tuple[float, float]]:  # fmt: skip
    """``(t, |after - before|)`` of a signal at every jump of a run.

    Parameters
    ----------
    t, j : arrays
        Times and jump counters of the recorded points (``run.t``, ``run.j``).
    values : array of float
        The signal at those points.

    Returns
    -------
    list of (float, float)
        One entry per jump, in order.

    Examples
    --------
    >>> jump_steps([0.0, 1.0, 1.0, 2.0], [0, 0, 1, 1], [0.0, 0.5, 0.75, 0.75])
    [(1.0, 0.25)]
    """
    tt = np.asarray(t, dtype=np.float64)
    jj = np.asarray(j)
    vv = np.asarray(values, dtype=np.float64)
    at = np.nonzero((tt[1:] == tt[:-1]) & (jj[1:] == jj[:-1] + 1))[0]
    return [(float(tt[i]), float(abs(vv[i + 1] - vv[i]))) for i in at]


def trapezoid(t: Sequence[float] | FloatArray, values: Sequence[float] | FloatArray) -> float:
    """Trapezoid rule over recorded points (zero-width intervals at jumps add nothing).

    Parameters
    ----------
    t, values : arrays of float
        Times and values.

    Returns
    -------
    float
        The integral.

    Examples
    --------
    >>> trapezoid([0.0, 1.0, 2.0], [0.0, 1.0, 0.0])
    1.0
    """
    tt = np.asarray(t, dtype=np.float64)
    vv = np.asarray(values, dtype=np.float64)
    return float(np.sum(0.5 * (vv[1:] + vv[:-1]) * np.diff(tt)))


def vehicle_energy(t: Sequence[float] | FloatArray, vx: Sequence[float] | FloatArray,
                   vy: Sequence[float] | FloatArray) -> float:  # fmt: skip
    """``int |v|^2 dt`` of the vehicle, m^2/s (a proxy of the thrusters' energy).

    Parameters
    ----------
    t : array of float
        Times.
    vx, vy : arrays of float
        Vehicle velocity.

    Returns
    -------
    float
        The integral.
    """
    v2 = np.asarray(vx, dtype=np.float64) ** 2 + np.asarray(vy, dtype=np.float64) ** 2
    return trapezoid(t, v2)


def vehicle_travel_time(t: Sequence[float] | FloatArray, speed: Sequence[float] | FloatArray,
                        threshold: float = 1e-3) -> float:  # fmt: skip
    """Time during which the vehicle moves faster than ``threshold`` m/s.

    Parameters
    ----------
    t : array of float
        Times.
    speed : array of float
        Vehicle speed.
    threshold : float
        Speed below which the vehicle counts as at rest.

    Returns
    -------
    float
        Seconds (intervals counted when both ends move).

    Examples
    --------
    >>> vehicle_travel_time([0.0, 1.0, 2.0, 3.0], [0.0, 0.5, 0.5, 0.0])
    1.0
    """
    tt = np.asarray(t, dtype=np.float64)
    moving = np.asarray(speed, dtype=np.float64) > threshold
    both = moving[1:] & moving[:-1]
    return float(np.sum(np.diff(tt)[both]))
