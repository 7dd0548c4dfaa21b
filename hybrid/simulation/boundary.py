"""Boundary rules: whether a guard holds at a point, whether an invariant is being left,
and which of several enabled transitions fires.

A condition is decided by the sign of its ``rho`` (``<= 0`` holds) away from
its boundary. Within a band of the boundary (``rho`` within :func:`band` of
0) the slope of ``rho`` along the flow decides: falling means the guard is
starting to hold; rising means it is being left and the guard is *disarmed*
until it has been strictly false (docs/semantics.md); flat means it *sits* on
its boundary, and its boolean form decides with each comparison within the
band decided as on its boundary (non-strict holds, strict does not), not by
the sign of a rounding error. Where rho is not 0 but the point the slope test steps to has a
rho of exactly 0 (rho comes down to 0 and stays there: a flat zero), the
boolean form decides at that point. Among enabled transitions the highest priority fires, ties by
file order.

At a point where the search stopped (:func:`enabled_at_event`), an armed
guard's equality atoms are *snapped*: an atom whose two sides differ by at most
the band is true there (the level has been reached), any other false; the rest
of the guard is decided as above. At the start of a stay they are not: a state
that starts on a level and leaves it has not reached it.

Examples
--------
>>> import hybrid, numpy as np
>>> from hybrid.simulation.compiled import CompiledModel
>>> from hybrid.compose import as_system
>>> compiled = CompiledModel(as_system(hybrid.load("specs/bouncing_ball.yaml")))
>>> mode = compiled.mode(compiled.initial_key)
>>> chosen, enabled, armed = enabled_at_entry(mode, 0.0, np.array([0.0, -3.0]))
>>> chosen.name, armed
('bounce', [True])
>>> enabled_at_entry(mode, 0.0, np.array([0.0, 3.0]))[0] is None   # on the floor, rising
True
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from typing import Any

import numpy as np

from hybrid.simulation.compiled import CompiledMode, CompiledTransition
from hybrid.simulation.forms import Sitting

Fn = Callable[[float, Any], Any]
Looked = Callable[[], tuple[float, float, np.ndarray]]
"""What gives :func:`ahead`'s point ``(h, t + h, x + h x')`` (:func:`looking`)."""

__all__ = [
    "ahead",
    "band",
    "choose",
    "chosen_by",
    "decide_at_entry",
    "enabled_at_entry",
    "enabled_at_event",
    "holds_now",
    "invariant_left_at",
    "looking",
    "slope",
]


def band(x: np.ndarray) -> float:
    """Values of rho within this of 0 count as on the boundary."""
    return 1e-10 * (1.0 + max(map(abs, x.tolist()), default=0.0))


def ahead(mode: CompiledMode, t: float, x: np.ndarray) -> tuple[float, float, np.ndarray]:
    """The step ``h`` of the slope test and the point ``(t + h, x + h x')`` it looks at."""
    h = 1e-7 * max(1.0, abs(t))
    moved = [xi + h * di for xi, di in zip(x.tolist(), mode.rhs(t, x), strict=True)]
    return h, t + h, np.array(moved)


def slope(fn: Callable[[float, Any], float], mode: CompiledMode, t: float, x: np.ndarray) -> float:
    """d/dt of ``fn`` along the flow, by a small forward difference."""
    h, t1, x1 = ahead(mode, t, x)
    return float((fn(t1, x1) - fn(t, x)) / h)


def looking(mode: CompiledMode, t: float, x: np.ndarray) -> Looked:
    """:func:`ahead`'s point at ``(mode, t, x)``, computed when first asked for: it is the
    same for every guard decided there."""
    point: list[tuple[float, float, np.ndarray]] = []

    def look() -> tuple[float, float, np.ndarray]:
        if not point:
            point.append(ahead(mode, t, x))
        return point[0]

    return look


def holds_now(
    rho: Fn,
    holds: Fn,
    sitting: Callable[[], Sitting],
    mode: CompiledMode,
    t: float,
    x: np.ndarray,
    armed: bool,
    width: float,
    looked: Looked | None = None,
) -> tuple[bool, bool]:
    """``(enabled now, armed)`` for a guard given by its ``rho`` and boolean ``holds``
    forms; ``sitting()`` gives its form within the band (compiled when first needed).

    ``looked`` gives :func:`ahead`'s point (:func:`looking`), when it is known or
    shared by several guards; without it the point is computed here.
    """
    value = rho(t, x)
    if value < -width:
        return True, True
    if value > width:
        return False, True
    if not armed:
        return False, False
    h, t1, x1 = ahead(mode, t, x) if looked is None else looked()
    further = rho(t1, x1)
    if further == 0.0 and value != 0.0:
        # rho comes down to exactly 0 (a flat zero: `max(h, v, 0)`, `x - x > 0 and ...`):
        # its slope says nothing about the guard; the boolean form where the flow goes does
        now = bool(holds(t1, x1))
        return now, now
    rate = float((further - value) / h)
    if rate < -width:
        return True, True
    if rate > width:
        return False, False  # on the boundary, moving away: disarm until strictly false
    return sitting()(t, x, width), False


def decide_at_entry(
    tr: CompiledTransition,
    mode: CompiledMode,
    t: float,
    x: np.ndarray,
    width: float,
    reached: np.ndarray | None,
    width_then: float,
    used: Collection[str],
    looked: Looked,
) -> tuple[bool, bool]:
    """``(enabled, armed)`` of one transition where a stay starts (:func:`enabled_at_entry`)."""
    if tr.rho(t, x) > width and (reached is None or not tr.levels):
        return False, True  # strictly false: holds_now's first answer, without its call
    now, is_armed = holds_now(tr.rho, tr.holds, tr.sitting, mode, t, x, True, width, looked)
    if not now and tr.levels and reached is not None:
        then = [abs(d(t, reached)) <= width_then for d in tr.levels]
        at_level = tuple(
            abs(d(t, x)) <= width and was and key not in used
            for d, was, key in zip(tr.levels, then, tr.level_keys, strict=True)
        )
        if any(at_level):
            rho, holds, sitting = tr.snapped(at_level)
            now = holds_now(rho, holds, sitting, mode, t, x, True, width, looked)[0]
    return now, is_armed


def enabled_at_entry(
    mode: CompiledMode,
    t: float,
    x: np.ndarray,
    reached: np.ndarray | None = None,
    used: Collection[str] = (),
) -> tuple[CompiledTransition | None, list[CompiledTransition], list[bool]]:
    """At a point where a stay starts: the transition that fires, all enabled, and arming.

    ``reached``: the state where the last stay stopped, when that was at this
    instant (the jumps since were taken at ``t``). A level the flow reached
    there is still reached after jumps that left it where it is, until a jump
    whose guard reads it is taken: so a guard that does not hold here is
    decided again with its equality atoms snapped, each true where its two
    sides are within the band both here and at ``reached`` and its level (by
    ``level_keys``) is not in ``used`` (read by a guard taken at this instant,
    or by one disarmed in the stay: a state that starts on a level and leaves
    it has not reached it).
    """
    enabled: list[CompiledTransition] = []
    armed: list[bool] = []
    width = band(x)
    width_then = 0.0 if reached is None else band(reached)
    looked = looking(mode, t, x)
    for tr in mode.transitions:
        now, is_armed = decide_at_entry(tr, mode, t, x, width, reached, width_then, used, looked)
        armed.append(is_armed)
        if now:
            enabled.append(tr)
    return choose(enabled), enabled, armed


def enabled_at_event(
    mode: CompiledMode, t: float, x: np.ndarray, armed: Callable[[int], bool]
) -> list[CompiledTransition]:
    """The transitions enabled at a point where the search stopped (``armed(i)``: in the watch).

    A crossing the search found still has to pass the boundary rule: rho may
    reach 0 and stay there while a strict guard never holds. A disarmed guard
    counts only if it is at or below its boundary there.
    """
    width = band(x)
    enabled: list[CompiledTransition] = []
    looked = looking(mode, t, x)
    for i, tr in enumerate(mode.transitions):
        if armed(i):
            at_level = tuple(abs(d(t, x)) <= width for d in tr.levels)
            rho, holds, sitting = tr.snapped(at_level)
        elif tr.rho(t, x) <= width:
            rho, holds, sitting = tr.rho, tr.holds, tr.sitting
        else:
            continue
        if holds_now(rho, holds, sitting, mode, t, x, True, width, looked)[0]:
            enabled.append(tr)
    return enabled


def invariant_left_at(mode: CompiledMode, t: float, x: np.ndarray) -> str | None:
    """The name of an invariant that does not hold, or is being left, at ``(t, x)``."""
    width = band(x)
    for inv in mode.invariants:
        value = inv.rho(t, x)
        if value > width:
            return inv.name
        if value >= -width:
            rate = slope(inv.rho, mode, t, x)
            if rate > width or (abs(rate) <= width and not inv.sitting()(t, x, width)):
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
