"""First crossings inside a step: where, within one accepted solver step, the watch first reaches 0.

The rule (docs/semantics.md, "First crossings inside a step"; a compiled
backend implements the same and is tested against this one):

1. **Samples.** An accepted step ``[t0, t1]`` of length ``h`` is cut into ``m``
   equal parts, ``m = max(SAMPLES_PER_STEP, ceil(h / spacing))`` with
   ``spacing = (t_end - t_start) / HORIZON_SAMPLES``; the watch is evaluated in
   order at ``t0 + k h / m`` for ``k = 1 .. m`` on the solver's interpolant
   (the step end on the solver's own state).
2. **Arming.** At each sample, before it is used as the left end of the next
   part, disarmed terms that are beyond the band on their safe side are armed
   (:meth:`~hybrid.simulation.events.Watch.arm`).
3. **Crossing.** The first sample whose watch value is ``<= 0`` ends the search:
   the first instant at or below 0 is located between it and the sample before
   by Brent's method on the interpolant (``brentq``, tolerances ``4 eps``
   absolute and relative, as scipy's events), with the two known end values, so
   the bracket is exact; a value of exactly 0 counts as below, so a watch that
   comes down to 0 and stays there is located where it arrives.
4. **Dip.** Before that, each sample that is a local minimum of the sampled
   values (no higher than both neighbours, lower than one) is examined when the
   parabola through it and its neighbours dips at least half way from it to
   0: the watch is minimised between the neighbours (bounded Brent). A minimum
   ``< 0`` gives a crossing, located between the left neighbour and the
   minimum; a minimum of exactly 0 a *touch* located the same way; a minimum
   above 0 within the band a *touch* at the minimum. A dip before the first
   crossing holds the earliest event of the step.

What it cannot see: a window in which the watch is below 0 that lies between
two samples and leaves no dip in the sampled values (a kink, as of ``x >= 5
and x <= 5.001``, between samples that fall on both slopes of it); and, inside
one part, any but one of several zeros. ``max_step`` bounds the parts.

Examples
--------
>>> import numpy as np
>>> from hybrid.simulation.dense import StepCurve
>>> class Line(StepCurve):          # x(t) = t over one long step [0, 10]
...     def at(self, t): return np.array([t])
...     def many(self, ts): return ts.reshape(-1, 1)
>>> class Sine:                     # watch: sin(t) + 0.5, the guard sin(t) <= -0.5
...     value = staticmethod(lambda t, x: np.sin(t) + 0.5)
...     pending, generation = False, 0
>>> found, _ = first_event(Line(0.0, 10.0, np.array([0.0]), np.array([10.0])), Sine(), 0.5, 100.0)
>>> round(found.t, 12) == round(7 * np.pi / 6, 12), found.kind
(True, 'crossing')
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from hybrid.simulation.dense import StepCurve

__all__ = ["HORIZON_SAMPLES", "SAMPLES_PER_STEP", "Found", "first_event", "parts"]

SAMPLES_PER_STEP = 4
"""Fewest parts a step is cut into for the search."""

HORIZON_SAMPLES = 1000
"""The parts of a step are at most ``(t_end - t_start) / HORIZON_SAMPLES`` long."""

_EPS = float(np.finfo(float).eps)
_TOL = 4 * _EPS
_BELOW = -5e-324
"""What a watch value of exactly 0 counts as while the first instant at or below 0 is bracketed."""


class WatchLike(Protocol):
    """What the search reads of a :class:`~hybrid.simulation.events.Watch`."""

    value: Any
    pending: bool
    generation: int


@dataclass(frozen=True)
class Found:
    """An event inside a step: where (``t``, ``x``) and how (``crossing`` or ``touch``)."""

    t: float
    x: np.ndarray
    kind: str


@dataclass
class Failed:
    """An evaluation failed at a sample; the last good sample is (``t``, ``x``)."""

    t: float
    x: np.ndarray


def band(x: np.ndarray) -> float:
    """Values of rho within this of 0 count as on the boundary (as in :mod:`boundary`)."""
    return 1e-10 * (1.0 + max(map(abs, x.tolist()), default=0.0))


def parts(h: float, spacing: float) -> int:
    """How many equal parts a step of length ``h`` is cut into."""
    if not h < spacing * SAMPLES_PER_STEP:
        return max(SAMPLES_PER_STEP, math.ceil(h / spacing))
    return SAMPLES_PER_STEP


def first_event(
    curve: StepCurve,
    watch: WatchLike,
    w0: float,
    spacing: float,
    arm: Any = None,
    failure: Any = None,
) -> tuple[Found | Failed | None, float]:
    """The first event of the watch inside ``curve``'s step, and the watch at the step end.

    The rule is in the module docstring. ``w0`` is the watch's value at the step
    start (``inf`` if nothing is armed); ``arm(t, x)`` arms disarmed terms at a
    sample (while ``watch.pending``); ``failure.error`` is set when an evaluation
    has failed.
    """
    t0, t1 = curve.t0, curve.t1
    h = t1 - t0
    m = parts(h, spacing)
    rows = [*curve.parts(m), curve.x1] if m > 1 else [curve.x1]
    times = [t0 + h * k / m for k in range(1, m)]
    times.append(t1)
    curve.samples = (m, times, rows)  # the monitor's samples of the step too
    if arm is None or not watch.pending:
        fn = watch.value
        if fn is None:
            return None, math.inf
        values = [w0]
        append = values.append
        crossing: Found | None = None
        w = w0
        for t, x in zip(times, rows, strict=True):
            w = fn(t, x)
            if failure is not None and failure.error is not None:
                t_prev = times[len(values) - 2] if len(values) > 1 else t0
                return Failed(t_prev, curve.at(t_prev)), w
            if w <= 0.0:
                t_prev = times[len(values) - 2] if len(values) > 1 else t0
                root = _locate(fn, curve, t_prev, values[-1], t, w)
                crossing = Found(root, curve.at(root), "crossing")
                break
            append(w)
        # a dip before the first crossing (or anywhere, without one) holds an earlier event
        for k in range(1, len(values) - 1):  # sample k is at times[k - 1]
            wb = values[k]
            if wb <= values[k - 1] and wb <= values[k + 1]:
                ta = times[k - 2] if k >= 2 else t0
                dip = _dip(fn, curve, ta, values[k - 1], times[k - 1], wb, times[k], values[k + 1])
                if dip is not None:
                    return dip, w
        return crossing, w
    return _with_arming(curve, watch, w0, times, rows, arm, failure)


def _with_arming(
    curve: StepCurve,
    watch: WatchLike,
    w0: float,
    times: list[float],
    rows: list[np.ndarray],
    arm: Any,
    failure: Any,
) -> tuple[Found | Failed | None, float]:
    """:func:`first_event` while some term is disarmed: arm at each sample, in order."""
    ts = [curve.t0]
    values = [w0]
    gens = [watch.generation]
    for t, x in zip(times, rows, strict=True):
        fn = watch.value
        w = fn(t, x) if fn is not None else math.inf
        if failure is not None and failure.error is not None:
            return Failed(ts[-1], curve.at(ts[-1])), w
        if w <= 0.0:
            root = _locate(fn, curve, ts[-1], values[-1], t, w)
            return Found(root, curve.at(root), "crossing"), w
        if len(ts) >= 2 and gens[-2] == gens[-1] == watch.generation:
            dip = _dip(fn, curve, ts[-2], values[-2], ts[-1], values[-1], t, w)
            if dip is not None:
                return dip, w
        if watch.pending and arm(t, x):
            fn = watch.value
            w = fn(t, x) if fn is not None else math.inf
        ts.append(t)
        values.append(w)
        gens.append(watch.generation)
    return None, values[-1]


def _phi(fn: Any, curve: StepCurve, a: float, wa: float, b: float, wb: float) -> Any:
    def phi(t: float) -> float:
        if t == a:
            return wa
        if t == b:
            return wb
        return float(fn(t, curve.at(t)))

    return phi


def _locate(fn: Any, curve: StepCurve, a: float, wa: float, b: float, wb: float) -> float:
    """The first instant in ``[a, b]`` where the watch is at or below 0 (``wa > 0 >= wb``).

    The root is bracketed on that predicate: a value of exactly 0 counts as
    below (:data:`_BELOW`), so a watch that falls to 0 and stays there (rho
    ``max(h, v, 0)``, a flat zero) is located where it arrives at 0, not at the
    sample that first saw it.
    """
    if not (wa > 0.0 and math.isfinite(wa) and math.isfinite(wb)):
        return b
    from scipy.optimize import brentq  # here, at an event: the module itself loads no scipy

    phi = _phi(fn, curve, a, wa, b, wb)

    def at_or_below(t: float) -> float:
        value = phi(t)
        return _BELOW if value == 0.0 else value

    try:
        root: float = brentq(at_or_below, a, b, xtol=_TOL, rtol=_TOL)
    except (ValueError, RuntimeError):  # a non-finite value inside: keep the safe end
        return b
    return root


def _dip(
    fn: Any,
    curve: StepCurve,
    ta: float,
    wa: float,
    tb: float,
    wb: float,
    tc: float,
    wc: float,
) -> Found | None:
    """An event hidden in a dip of the watch around the sample ``tb`` (step 4 of the rule)."""
    if not (wb <= wa and wb <= wc and (wb < wa or wb < wc)):
        return None
    curvature = wa - 2.0 * wb + wc
    if not curvature > 0.0:
        return None
    lowest = wb - (wc - wa) ** 2 / (8.0 * curvature)
    if not lowest <= 0.5 * wb:
        return None
    from scipy.optimize import minimize_scalar  # here, at a dip: as brentq in _locate

    phi = _phi(fn, curve, ta, wa, tc, wc)
    span = tc - ta
    best = minimize_scalar(
        phi,
        bounds=(ta, tc),
        method="bounded",
        options={"xatol": max(_TOL * abs(tb), 1e-10 * span)},
    )
    t_min = float(best.x)
    w_min = float(best.fun)
    if not math.isfinite(w_min):
        return None
    if w_min < 0.0:
        root = _locate(fn, curve, ta, wa, t_min, w_min)
        return Found(root, curve.at(root), "crossing")
    if w_min == 0.0:  # a touch of exactly 0, or a flat zero: where the watch arrives at 0
        root = _locate(fn, curve, ta, wa, t_min, w_min)
        return Found(root, curve.at(root), "touch")
    x_min = curve.at(t_min)
    if w_min <= band(x_min):
        return Found(t_min, x_min, "touch")
    return None
