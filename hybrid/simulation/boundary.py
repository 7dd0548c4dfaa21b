"""Boundary rules: whether a guard holds at a point, whether an invariant is being left,
and which of several enabled transitions fires.

A condition is decided by the sign of its ``rho`` (``<= 0`` holds) away from
its boundary. Within a band of the boundary (``rho`` within :func:`band` of
0) the slope of ``rho`` along the flow decides: falling means the guard is
starting to hold; rising means it is being left and the guard is *disarmed*
until it has been strictly false (docs/semantics.md); flat means its boolean
form decides. Among enabled transitions the highest priority fires, ties by
file order.

Examples
--------
>>> import hybrid, numpy as np
>>> from hybrid.simulation.compiled import CompiledModel
>>> compiled = CompiledModel(hybrid.load("specs/bouncing_ball.yaml"))
>>> mode = compiled.mode(compiled.initial_key)
>>> chosen, enabled, armed = enabled_at_entry(mode, 0.0, np.array([0.0, -3.0]))
>>> chosen.name, armed
('bounce', [True])
>>> enabled_at_entry(mode, 0.0, np.array([0.0, 3.0]))[0] is None   # on the floor, rising
True
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from hybrid.simulation.compiled import CompiledCondition, CompiledMode, CompiledTransition

__all__ = [
    "band",
    "choose",
    "chosen_by",
    "enabled_at_entry",
    "holds_now",
    "invariant_left_at",
    "slope",
]


def band(x: np.ndarray) -> float:
    """Values of rho within this of 0 count as on the boundary."""
    return 1e-10 * (1.0 + max(map(abs, x.tolist()), default=0.0))


def slope(fn: Callable[[float, Any], float], mode: CompiledMode, t: float, x: np.ndarray) -> float:
    """d/dt of ``fn`` along the flow, by a small forward difference."""
    h = 1e-7 * max(1.0, abs(t))
    ahead = [xi + h * di for xi, di in zip(x.tolist(), mode.rhs(t, x), strict=True)]
    return float((fn(t + h, np.array(ahead)) - fn(t, x)) / h)


def holds_now(
    cond: CompiledCondition,
    mode: CompiledMode,
    t: float,
    x: np.ndarray,
    armed: bool,
    width: float,
) -> tuple[bool, bool]:
    """``(enabled now, armed)`` for a guard at a point where no event says so."""
    value = cond.rho(t, x)
    if value < -width:
        return True, True
    if value > width:
        return False, True
    if not armed:
        return False, False
    rate = slope(cond.rho, mode, t, x)
    if rate < -width:
        return True, True
    if rate > width:
        return False, False  # on the boundary, moving away: disarm until strictly false
    return bool(cond.holds(t, x)), False


def enabled_at_entry(
    mode: CompiledMode, t: float, x: np.ndarray
) -> tuple[CompiledTransition | None, list[CompiledTransition], list[bool]]:
    """At a point where a stay starts: the transition that fires, all enabled, and arming."""
    enabled: list[CompiledTransition] = []
    armed: list[bool] = []
    width = band(x)
    for tr in mode.transitions:
        now, is_armed = holds_now(tr, mode, t, x, True, width)
        armed.append(is_armed)
        if now:
            enabled.append(tr)
    return choose(enabled), enabled, armed


def invariant_left_at(mode: CompiledMode, t: float, x: np.ndarray) -> str | None:
    """The name of an invariant that does not hold, or is being left, at ``(t, x)``."""
    width = band(x)
    for inv in mode.invariants:
        value = inv.rho(t, x)
        if value > width:
            return inv.name
        if value >= -width:
            rate = slope(inv.rho, mode, t, x)
            if rate > width or (abs(rate) <= width and not inv.holds(t, x)):
                return inv.name
    return None


def choose(enabled: list[CompiledTransition]) -> CompiledTransition | None:
    """Highest priority first, then file order."""
    if not enabled:
        return None
    return min(enabled, key=lambda tr: (-tr.view.priority, tr.view.order))


def chosen_by(chosen: CompiledTransition, enabled: list[CompiledTransition]) -> str:
    """How ``chosen`` was picked among ``enabled``: ``only``, ``priority`` or ``file order``."""
    if len(enabled) == 1:
        return "only"
    top = [tr for tr in enabled if tr.view.priority == chosen.view.priority]
    return "priority" if len(top) == 1 else "file order"
