"""Declared bounds, watched: where a run leaves the ``bounds:`` its spec declares.

``hybrid check`` proves its findings over the declared bounds of the state
(docs/check.md), so a run that leaves them is a run those proofs do not cover.
After a run, :func:`bound_excursions` finds, for each state variable, the first
stored point beyond its bounds by more than the solver's tolerance
(``atol + rtol * |bound|``), and :func:`warn_excursions` warns once per variable
with its time ``t`` and hybrid time ``j`` (:class:`BoundsWarning`). The run keeps
them as ``run.out_of_bounds`` and the events JSON as ``"out_of_bounds"``.

An ensemble (:func:`hybrid.simulate_many`) of thousands of runs warns once per
variable too, not once per run: :func:`warn_ensemble` counts the runs that left
that variable's bounds and names the first of them, with its ``t`` and ``j``.

Examples
--------
>>> import numpy as np
>>> from hybrid.model import StateVar
>>> h = StateVar("h", 1.0, lower=0.0, upper=3.0)
>>> t, j = np.array([0.0, 1.0, 2.0]), np.array([0, 0, 0])
>>> states = np.array([[1.0], [3.5], [4.0]])
>>> (found,) = bound_excursions((h,), ("h",), t, j, states, rtol=1e-6, atol=1e-9)
>>> found.message
'h left its declared bounds [0, 3] at t=1 j=0 (h = 3.5)'
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hybrid.errors import users_stacklevel
from hybrid.model import StateVar

__all__ = [
    "BoundExcursion",
    "BoundLimit",
    "BoundsWarning",
    "bound_excursions",
    "bound_limits",
    "run_excursions",
    "warn_ensemble",
    "warn_excursions",
]


class BoundsWarning(UserWarning):
    """A simulated run left the declared ``bounds:`` of a state variable."""


@dataclass(frozen=True)
class BoundExcursion:
    """The first stored point of a run where ``variable`` is beyond its declared bounds."""

    variable: str
    t: float
    j: int
    value: float
    lower: float
    upper: float

    @property
    def message(self) -> str:
        bounds = f"[{self.lower:g}, {self.upper:g}]"
        return (
            f"{self.variable} left its declared bounds {bounds} at t={self.t:.9g} j={self.j} "
            f"({self.variable} = {self.value:.9g})"
        )

    def as_dict(self) -> dict[str, Any]:
        """``{"variable", "t", "j", "value", "bounds": [lower, upper]}`` (the events JSON)."""
        return {
            "variable": self.variable,
            "t": self.t,
            "j": self.j,
            "value": self.value,
            "bounds": [self.lower, self.upper],
        }


_FMIN, _FMAX = np.fmin.reduce, np.fmax.reduce

Extremes = tuple[Sequence[float], Sequence[float]]
"""Each state's smallest values over a run's points, then its largest (NaN left out)."""
BoundLimit = tuple[int, StateVar, float, float]
"""A bounded variable's column, the variable, and the values beyond which a point is out."""
_PLAN: list[tuple[Any, ...] | None] = [None]
"""``(declared, names, rtol, atol, limits)`` of the last :func:`bound_limits` kept (tuples only)."""


def bound_limits(declared: Sequence[StateVar], names: Sequence[str], rtol: float,
                 atol: float) -> list[BoundLimit]:  # fmt: skip
    """The bounded variables of ``declared`` among ``names``: column, variable, limits
    (each bound widened by the solver's tolerance, ``atol + rtol * |bound|``).

    The answer for the same tuples (the very objects: a model's are frozen) and
    tolerances as the last call's is that call's (a loop of runs asks again
    and again).
    """
    last = _PLAN[0]
    if last is not None and last[0] is declared and last[1] is names and last[2] == rtol \
            and last[3] == atol:  # fmt: skip
        checks: list[BoundLimit] = last[4]
        return checks
    checks = []
    for var in declared:
        if (math.isinf(var.lower) and math.isinf(var.upper)) or var.name not in names:
            continue
        low = var.lower - (atol + rtol * abs(var.lower))
        high = var.upper + (atol + rtol * abs(var.upper))
        checks.append((names.index(var.name), var, low, high))
    if declared.__class__ is tuple and names.__class__ is tuple:
        _PLAN[0] = (declared, names, rtol, atol, checks)  # one tuple, replaced at once
    return checks


def bound_excursions(
    declared: Sequence[StateVar],
    names: Sequence[str],
    t: NDArray[np.float64],
    j: NDArray[np.int64],
    states: NDArray[np.float64],
    *,
    rtol: float,
    atol: float,
    extremes: Extremes | None = None,
) -> tuple[BoundExcursion, ...]:
    """Per bounded state variable, the first stored point beyond its bounds (tolerance above).

    A non-finite value is not an excursion: the run ends ``nonfinite`` and says so.
    ``extremes``: each state's smallest and largest value over the points (NaN
    left out), where the run kept them (``run.stored_extremes()``); else
    they are worked out here, a column at a time.
    """
    limits = bound_limits(declared, names, rtol, atol)
    return _excursions(limits, lambda: (t, j, states), extremes)


def run_excursions(declared: Sequence[StateVar], run: Any, *, rtol: float,
                   atol: float) -> tuple[BoundExcursion, ...]:  # fmt: skip
    """:func:`bound_excursions` of a :class:`~hybrid.simulation.result.Run`'s stored points.

    Its columns are read only when a bound is to be checked and, where the run
    kept each state's extremes (a compiled run), only when one lies beyond it: a
    short run within its bounds costs no column.

    Examples
    --------
    >>> import hybrid
    >>> ball = hybrid.load("specs/bouncing_ball.yaml")
    >>> run = hybrid.simulate(ball, t_end=1.0)
    >>> run_excursions(ball.states, run, rtol=1e-6, atol=1e-9)
    ()
    """
    limits = bound_limits(declared, run.state_names, rtol, atol)
    return _excursions(limits, run.checked_columns, run.stored_extremes()) if limits else ()


def _excursions(
    limits: list[BoundLimit],
    columns: Callable[[], tuple[NDArray[np.float64], NDArray[np.int64], NDArray[np.float64]]],
    extremes: Extremes | None,
) -> tuple[BoundExcursion, ...]:
    """The first point beyond each of ``limits`` (see :func:`bound_excursions`); ``columns()``
    gives ``(t, j, states)``, asked for only when a variable's extremes do not settle it."""
    found: list[BoundExcursion] = []
    read = None
    for k, var, low, high in limits:
        # its extremes (NaN left out) within: no point beyond (no column read); an infinite
        # side cannot be passed, so its extreme is not looked for
        if extremes is not None and not (extremes[0][k] < low or extremes[1][k] > high):
            continue
        if read is None:
            read = columns()
        t, j, states = read
        column = states[:, k]
        if extremes is None and (column.size == 0 or not (
                (low != -math.inf and _FMIN(column) < low)
                or (high != math.inf and _FMAX(column) > high))):  # fmt: skip
            continue
        below = column < low
        above = column > high
        beyond = np.flatnonzero((below | above) & np.isfinite(column))
        if beyond.size:
            k = int(beyond[0])
            found.append(
                BoundExcursion(
                    var.name, float(t[k]), int(j[k]), float(column[k]), var.lower, var.upper
                )
            )
    return tuple(found)


def warn_excursions(found: Sequence[BoundExcursion], stacklevel: int | None = None) -> None:
    """One :class:`BoundsWarning` per excursion (one per variable), at the user's call
    (``stacklevel``: else the first caller outside hybrid)."""
    level = stacklevel or users_stacklevel()
    for excursion in found:
        warnings.warn(excursion.message, BoundsWarning, stacklevel=level)


def warn_ensemble(
    found: Mapping[int, Sequence[BoundExcursion]], runs: int, stacklevel: int | None = None
) -> None:
    """One :class:`BoundsWarning` per variable over many runs (``found``: by run number).

    The message counts the runs that left the variable's bounds and gives the
    first of them (the lowest run number) with its ``t``, ``j`` and value.

    Examples
    --------
    >>> h = BoundExcursion("h", 3.1, 1, 3.05, 0.0, 3.0)
    >>> with warnings.catch_warnings(record=True) as caught:
    ...     warnings.simplefilter("always")
    ...     warn_ensemble({7: [h], 2: [h]}, runs=10)
    >>> print(caught[0].message)
    h left its declared bounds [0, 3] in 2 of 10 runs; the first, run 2, at t=3.1 j=1 (h = 3.05)
    """
    counts: dict[str, int] = {}
    first: dict[str, tuple[int, BoundExcursion]] = {}
    for run in sorted(found):
        for excursion in found[run]:
            counts[excursion.variable] = counts.get(excursion.variable, 0) + 1
            first.setdefault(excursion.variable, (run, excursion))
    level = stacklevel or users_stacklevel()
    for variable, (run, e) in first.items():
        warnings.warn(
            f"{variable} left its declared bounds [{e.lower:g}, {e.upper:g}] in "
            f"{counts[variable]} of {runs} runs; the first, run {run}, at t={e.t:.9g} j={e.j} "
            f"({variable} = {e.value:.9g})",
            BoundsWarning,
            stacklevel=level,
        )
