"""The watch of a stay in a mode: one value for every armed guard and invariant.

During a stay the simulator watches one function of ``(t, x)``, the *watch*:
the smallest of every armed guard's rho (the guard starts to hold when it falls
to 0) and every armed invariant's ``-rho`` (the invariant stops holding when it
falls to 0). Its first zero is the first event of the stay, whichever guard or
invariant causes it, so one search per step finds it
(:mod:`~hybrid.simulation.crossing`).

**Arming** (docs/semantics.md, "Re-arming"). A guard or invariant on its
boundary at the start of a stay and moving away is *disarmed*: it is left out
of the watch until it is strictly on its safe side (its value beyond the band
of :func:`~hybrid.simulation.boundary.band`) at a point the search looks at.

**Orientation** (docs/semantics.md, "Equality guards"). A guard with equality
atoms is watched in its oriented form: atom ``a == b`` reads
``s * (a - b) <= 0`` with ``s`` the sign of ``a - b`` when the guard is armed,
so the term falls through 0 when the level is reached. While some ``a - b`` is
exactly 0 the guard stays disarmed.

The watch function is generated from a template (:func:`watch_factory`) per
pattern of signs, cached by the caller, and never contains user text.

Examples
--------
>>> import hybrid, numpy as np
>>> from hybrid.simulation.compiled import CompiledModel
>>> compiled = CompiledModel(hybrid.load("specs/bouncing_ball.yaml"))
>>> mode = compiled.mode(compiled.initial_key)
>>> watch = Watch(mode, [True], 0.0, np.array([10.0, 0.0]), 1e-9, {})
>>> float(watch.value(0.0, np.array([10.0, 0.0])))   # min(max(h, v), h): 10 m above the floor
10.0
>>> watch.pending
False
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

from hybrid.expr.generated import define
from hybrid.simulation.compiled import CompiledMode, CompiledTransition

__all__ = ["Watch", "orientation", "watch_factory"]

Fn = Callable[[float, Any], Any]
Factory = Callable[[Sequence[Fn]], Fn]


def watch_factory(signs: tuple[float, ...]) -> Factory:
    """Source-built ``make(fns)`` giving ``watch(t, x) = min_i signs[i] * fns[i](t, x)``.

    A term that cannot be evaluated (NaN) is left out (the failure is recorded
    where it happened and ends the run); with no finite term the watch is
    ``inf``.
    """
    lines = ["def make(_fns):"]
    lines += [f"    _f{i} = _fns[{i}]" for i in range(len(signs))]
    lines += ["    def watch(t, x):", "        v = _inf"]
    for i, sign in enumerate(signs):
        lines += [
            f"        w = {'-' if sign < 0 else ''}_f{i}(t, x)",
            "        if w < v:",
            "            v = w",
        ]
    lines += ["        return v", "    return watch"]
    factory: Factory = define("make", "\n".join(lines) + "\n", {"_inf": math.inf})
    return factory


def orientation(tr: CompiledTransition, t: float, x: Any) -> tuple[int, ...] | None:
    """The side of each level of ``tr`` at ``(t, x)``; None while one is exactly at its level."""
    signs = []
    for difference in tr.levels:
        value = difference(t, x)
        if value > 0.0:
            signs.append(1)
        elif value < 0.0:
            signs.append(-1)
        else:
            return None
    return tuple(signs)


class Watch:
    """The armed terms of one stay and their watch function (``value``; None if none is armed).

    ``pending`` says whether some term is still disarmed (then :meth:`arm` is
    called at every point the search looks at); ``generation`` changes each time
    the watch function does.
    """

    __slots__ = ("factories", "generation", "inv_armed", "mode", "pending", "signs", "value")

    def __init__(
        self,
        mode: CompiledMode,
        guards_armed: Sequence[bool],
        t: float,
        x: Any,
        width: float,
        factories: dict[tuple[float, ...], Factory],
    ) -> None:
        self.mode = mode
        self.factories = factories
        self.signs: list[tuple[int, ...] | None] = [
            orientation(tr, t, x) if armed else None
            for tr, armed in zip(mode.transitions, guards_armed, strict=True)
        ]
        self.inv_armed = [inv.rho(t, x) < -width for inv in mode.invariants]
        self.generation = 0
        self.value: Fn | None = None
        self.pending = False
        self._build()

    def armed(self, index: int) -> bool:
        """Whether transition ``index`` takes part in the watch."""
        return self.signs[index] is not None

    def _build(self) -> None:
        fns: list[Fn] = []
        signs: list[float] = []
        for tr, side in zip(self.mode.transitions, self.signs, strict=True):
            if side is not None:
                fns.append(tr.oriented(side))
                signs.append(1.0)
        for inv, armed in zip(self.mode.invariants, self.inv_armed, strict=True):
            if armed:
                fns.append(inv.rho)
                signs.append(-1.0)
        key = tuple(signs)
        factory = self.factories.get(key)
        if factory is None and fns:
            factory = self.factories[key] = watch_factory(key)
        self.value = factory(fns) if factory is not None and fns else None
        self.pending = None in self.signs or not all(self.inv_armed)
        self.generation += 1

    def arm(self, t: float, x: Any, width: float) -> bool:
        """Arm each disarmed term that is beyond ``width`` on its safe side; True if one was."""
        changed = False
        for i, tr in enumerate(self.mode.transitions):
            if self.signs[i] is None and tr.rho(t, x) > width:
                side = orientation(tr, t, x)
                if side is not None:
                    self.signs[i] = side
                    changed = True
        for k, inv in enumerate(self.mode.invariants):
            if not self.inv_armed[k] and -inv.rho(t, x) > width:
                self.inv_armed[k] = True
                changed = True
        if changed:
            self._build()
        return changed
