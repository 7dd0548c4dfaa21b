"""The watch of a stay in a mode: one value for every guard and invariant.

During a stay the simulator watches one function of ``(t, x)``, the *watch*:
the smallest of every armed guard's rho (the guard starts to hold when it falls
to 0) and every armed invariant's ``-rho`` (the invariant stops holding when it
falls to 0). Its first zero is the first event of the stay, whichever guard or
invariant causes it, so one search per step finds it
(:mod:`~hybrid.simulation.crossing`).

**Arming** (docs/semantics.md, "Re-arming"). A guard or invariant on its
boundary at the start of a stay (moving away, or sitting still) is *disarmed*:
it is armed again once it is strictly on its safe side (its value beyond the
band ``b0`` of :func:`~hybrid.simulation.boundary.band` at the start of the
stay) at a point the search looks at. Until then it is watched from the far
edge of the band: a disarmed guard as ``rho + b0``, a disarmed invariant as
``-rho + b0``, so a state that leaves the boundary on the other side (the
guard starts to hold, the invariant stops holding) is an event too.

**Orientation** (docs/semantics.md, "Equality guards"). A guard with equality
atoms is watched in its oriented form: atom ``a == b`` reads
``s * (a - b) <= 0`` with ``s`` the sign of ``a - b`` when the guard is armed
(within the band of the level, the side the flow moves to: the sign of a
rounding error says nothing), so the term falls through 0 when the level is
reached; an atom exactly at its
level then (``s = 0``) reads ``a == b`` itself, which holds while the state
stays on the level, until the state is beyond the band of the level: then it
is oriented to the side the state is on (like arming), so that a return to the
level is a crossing again.

The watch function is generated from a template (:func:`watch_factory`) per
pattern of terms, cached by the caller, and never contains user text.

Examples
--------
>>> import hybrid, numpy as np
>>> from hybrid.simulation.compiled import CompiledModel
>>> from hybrid.compose import as_system
>>> compiled = CompiledModel(as_system(hybrid.load("specs/bouncing_ball.yaml")))
>>> mode = compiled.mode(compiled.initial_key)
>>> watch = Watch(mode, [True], 0.0, np.array([10.0, 0.0]), 1e-9, {})
>>> float(watch.value(0.0, np.array([10.0, 0.0])))   # min(max(h, v), h): 10 m above the floor
10.0
>>> watch.pending
False
>>> rest = Watch(mode, [False], 0.0, np.array([0.0, 0.0]), 1e-9, {})   # at rest on the floor
>>> rest.pending, float(rest.value(0.0, np.array([-1e-9, -1e-3])))       # both terms at the band's far edge
(True, 0.0)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

from hybrid.expr.generated import define
from hybrid.simulation import boundary
from hybrid.simulation.compiled import CompiledMode, CompiledTransition

__all__ = ["Watch", "joint_watch_factory", "orientation", "watch_factory"]

Fn = Callable[[float, Any], Any]
Factory = Callable[[Sequence[Fn], float], Fn]
Term = tuple[float, bool]
"""A term of the watch: its sign (``+1`` a guard, ``-1`` an invariant) and whether it is shifted."""


def watch_factory(terms: tuple[Term, ...]) -> Factory:
    """Source-built ``make(fns, b0)`` giving ``watch(t, x) = min_i sign_i * fns[i](t, x) (+ b0)``.

    ``terms[i]`` is ``(sign, shifted)``: a shifted term (a disarmed one) has
    ``b0`` added. A term that cannot be evaluated (NaN) is left out (the failure
    is recorded where it happened and ends the run); with no finite term the
    watch is ``inf``.
    """
    # the functions are taken from their sequence at each call: as cells of a closure they
    # would be one object each, made at every stay (hundreds in a system of many components)
    lines = ["def make(_fns, _b0):", "    _fns = (*_fns,)", "    def watch(t, x):"]
    if terms:
        lines.append(f"        {', '.join(f'_f{i}' for i in range(len(terms)))}, = _fns")
    lines += [*_least(terms, "_f{}(t, x)"), "    return watch"]
    factory: Factory = define("make", "\n".join(lines) + "\n", {"_inf": math.inf})
    return factory


def _least(terms: tuple[Term, ...], value: str) -> list[str]:
    """The watch's body from its first value on: the least of the terms, each the value
    ``value.format(i)`` signed and shifted, returned (the one arithmetic of both factories)."""
    lines = ["        v = _inf"]
    for i, (sign, shifted) in enumerate(terms):
        lines += [
            f"        w = {'-' if sign < 0 else ''}{value.format(i)}{' + _b0' if shifted else ''}",
            "        if w < v:",
            "            v = w",
        ]
    return [*lines, "        return v"]


JointFactory = Callable[[Fn, Any, Fn, float], Fn]

_JOINT: dict[tuple[Term, ...], JointFactory] = {}
"""The joint watch factory of each pattern of terms (a few per process; no user text)."""


def joint_watch_factory(terms: tuple[Term, ...]) -> JointFactory:
    """Source-built ``make(values, failure, each, b0)``: the watch of :func:`watch_factory`
    from ``values(t, x)``, the tuple of every term's function's value at once.

    The values are the terms' own (the same expressions compiled together, their
    shared signals computed once), combined in the same order with the same
    arithmetic, so the watch is the same number. Where ``values`` fails (it
    records the failure in ``failure``, or raises), the watch is ``each(t, x)``,
    the terms one by one, which record the failure as they always do.
    """
    lines = [
        "def make(_values, _failure, _each, _b0):",
        "    def watch(t, x):",
        "        try:",
        "            _v = _values(t, x)",
        "        except Exception:",
        "            return _each(t, x)",
        "        if _failure.error is not None:",
        "            _failure.clear()",
        "            return _each(t, x)",
        *_least(terms, "_v[{}]"),
        "    return watch",
    ]
    factory: JointFactory = define("make", "\n".join(lines) + "\n", {"_inf": math.inf})
    return factory


_PLAIN: dict[tuple[Term, ...], Factory] = {}
"""The watch factory of each pattern of terms, as :data:`_JOINT` (made once per process)."""


def _plain(terms: tuple[Term, ...]) -> Factory:
    """:func:`watch_factory` of ``terms``, made once per pattern (not once per run)."""
    found = _PLAIN.get(terms)
    if found is None:
        found = _PLAIN[terms] = watch_factory(terms)
    return found


def _joint(terms: tuple[Term, ...]) -> JointFactory:
    """:func:`joint_watch_factory` of ``terms``, made once per pattern."""
    found = _JOINT.get(terms)
    if found is None:
        found = _JOINT[terms] = joint_watch_factory(terms)
    return found


def orientation(
    tr: CompiledTransition, t: float, x: Any, mode: CompiledMode, width: float
) -> tuple[int, ...]:
    """The side of each level of ``tr`` at ``(t, x)``: ``1``, ``-1``, or ``0`` exactly on it.

    A level within ``width`` of the state (on it up to rounding) that the flow
    leaves takes the side the flow moves to (its slope beyond ``width``), not
    the sign of the rounding error, so a return to the level is a crossing.
    """
    signs = []
    ahead: tuple[float, float, Any] | None = None
    for difference in tr.levels:
        value = difference(t, x)
        side = 1 if value > 0.0 else -1 if value < 0.0 else 0
        if abs(value) <= width:
            if ahead is None:
                ahead = boundary.ahead(mode, t, x)
            h, t1, x1 = ahead
            rate = (difference(t1, x1) - value) / h
            side = 1 if rate > width else -1 if rate < -width else side
        signs.append(side)
    return tuple(signs)


class Watch:
    """The terms of one stay and their watch function (``value``; None if there is none).

    ``signs[i]`` is the orientation of armed transition ``i``, None while it is
    disarmed; ``inv_armed[k]`` says whether invariant ``k`` is armed; disarmed
    terms are watched shifted by ``width`` (the band at the start of the stay).
    ``pending`` says whether some term is still disarmed (then :meth:`arm` is
    called at every point the search looks at); ``generation`` changes each time
    the watch function does.
    """

    __slots__ = (
        "factories",
        "generation",
        "inv_armed",
        "mode",
        "pending",
        "signs",
        "value",
        "width",
    )

    def __init__(
        self,
        mode: CompiledMode,
        guards_armed: Sequence[bool],
        t: float,
        x: Any,
        width: float,
        factories: dict[tuple[Term, ...], Factory],
    ) -> None:
        self.mode = mode
        self.factories = factories
        self.width = width
        self.signs: list[tuple[int, ...] | None] = [
            orientation(tr, t, x, mode, width) if armed else None
            for tr, armed in zip(mode.transitions, guards_armed, strict=True)
        ]
        self.inv_armed = [inv.rho(t, x) < -width for inv in mode.invariants]
        self.generation = 0
        self.value: Fn | None = None
        self.pending = False
        self._build()

    def armed(self, index: int) -> bool:
        """Whether transition ``index`` takes part in the watch with its real (oriented) rho."""
        return self.signs[index] is not None

    def _build(self) -> None:
        fns: list[Fn] = []
        terms: list[Term] = []
        for tr, side in zip(self.mode.transitions, self.signs, strict=True):
            fns.append(tr.oriented(side) if side is not None else tr.rho)
            terms.append((1.0, side is None))
        for inv, armed in zip(self.mode.invariants, self.inv_armed, strict=True):
            fns.append(inv.rho)
            terms.append((-1.0, not armed))
        key = tuple(terms)
        factory = self.factories.get(key)
        if factory is None and fns:
            factory = self.factories[key] = _plain(key)
        self.value = factory(fns, self.width) if factory is not None and fns else None
        mode = self.mode
        if (
            self.value is not None
            and mode.terms is not None
            and all(
                not tr.levels or side is None
                for tr, side in zip(mode.transitions, self.signs, strict=True)
            )
        ):
            # every term is its plain rho: take them all from one call of the mode's terms
            joint = _joint(key)
            self.value = joint(mode.terms, mode.terms_failure, self.value, self.width)
        self.pending = (
            None in self.signs
            or not all(self.inv_armed)
            or any(side is not None and 0 in side for side in self.signs)
        )
        self.generation += 1

    def far_edge_guards(self, t: float, x: Any) -> list[CompiledTransition]:
        """The disarmed guards whose far-edge term ``rho + b0`` is the watch's least at
        ``(t, x)``, where a crossing stopped the stay (docs/semantics.md, "Re-arming": a
        band beyond its boundary, such a guard holds)."""
        least = self._least(t, x)
        return [
            tr for tr, side in zip(self.mode.transitions, self.signs, strict=True)
            if side is None and tr.rho(t, x) + self.width <= least
        ]  # fmt: skip

    def _least(self, t: float, x: Any) -> float:
        """The watch at ``(t, x)``, at least 0 (the root finder may land on either side of 0)."""
        return max(float(self.value(t, x)), 0.0) if self.value is not None else math.inf

    def far_edge_left(self, t: float, x: Any) -> str | None:
        """The name of a disarmed invariant whose far-edge term ``-rho + b0`` is the watch's
        least at ``(t, x)``, where a crossing stopped the stay (docs/semantics.md,
        "Re-arming": at that event the invariant is being left); None if there is none."""
        if self.value is None:
            return None
        least = self._least(t, x)
        for inv, armed in zip(self.mode.invariants, self.inv_armed, strict=True):
            if not armed and self.width - inv.rho(t, x) <= least:
                return inv.name
        return None

    def arm(self, t: float, x: Any, width: float) -> bool:
        """Arm each disarmed term that is beyond ``width`` on its safe side, and orient each
        level atom read on its level (0) that the state is beyond ``width`` of; True if one was."""
        changed = False
        for i, tr in enumerate(self.mode.transitions):
            side = self.signs[i]
            if side is None:
                if tr.rho(t, x) > width:
                    self.signs[i] = orientation(tr, t, x, self.mode, width)
                    changed = True
            elif 0 in side:
                moved = tuple(
                    s if s != 0 or not abs(value) > width else (1 if value > 0.0 else -1)
                    for s, value in zip(side, (d(t, x) for d in tr.levels), strict=True)
                )
                if moved != side:
                    self.signs[i] = moved
                    changed = True
        for k, inv in enumerate(self.mode.invariants):
            if not self.inv_armed[k] and -inv.rho(t, x) > width:
                self.inv_armed[k] = True
                changed = True
        if changed:
            self._build()
        return changed
