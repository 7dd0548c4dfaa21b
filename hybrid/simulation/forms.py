"""The compiled forms the simulator calls in a mode: conditions, transitions, modes.

:class:`~hybrid.simulation.compiled.CompiledModel` builds them, whole per mode
or from per-component parts (:mod:`~hybrid.simulation.parts`); the loop, the
boundary rules and the watch call them.

Examples
--------
>>> cond = CompiledCondition("x <= 1", rho=lambda t, x: x[0] - 1.0, holds=lambda t, x: x[0] <= 1.0)
>>> cond.rho(0.0, [0.5]) <= 0, cond.holds(0.0, [0.5])
(True, True)
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from hybrid.expr import ir
from hybrid.expr.codegen import CodeContext
from hybrid.expr.rho import guard_to_rho, oriented_rho, snapped
from hybrid.modes import Mode, TransitionView

__all__ = ["CompiledCondition", "CompiledMode", "CompiledTransition", "Fn", "Source"]

Fn = Callable[[float, Any], Any]


@dataclass
class CompiledCondition:
    """A guard or invariant: ``rho(t, x) <= 0`` iff ``holds(t, x)`` (off the boundary)."""

    name: str
    rho: Fn
    holds: Fn


@dataclass
class CompiledTransition(CompiledCondition):
    """A transition; a guard with equality atoms has ``levels`` and compiles variants on demand."""

    view: TransitionView
    reset: Fn
    levels: tuple[Fn, ...] = ()
    level_keys: tuple[str, ...] = ()
    """Each level's :func:`~hybrid.expr.rho.level_key`: one level read by several guards."""
    variant: Callable[[str, ir.Expr, str], Fn] | None = None
    move: tuple[int, str] | None = None
    """Of a mode's part (:mod:`~hybrid.simulation.parts`): the component's new location."""
    _oriented: dict[tuple[int, ...], Fn] = field(default_factory=dict)
    _snapped: dict[tuple[bool, ...], tuple[Fn, Fn]] = field(default_factory=dict)

    def oriented(self, signs: tuple[int, ...]) -> Fn:
        """Rho with level atom ``i`` read as ``signs[i] * (a - b) <= 0`` (``a == b`` for a 0).

        The plain rho for a guard without levels.
        """
        if not self.levels:
            return self.rho
        fn = self._oriented.get(signs)
        if fn is None:
            assert self.variant is not None
            tag = "".join("p" if s > 0 else "n" if s < 0 else "z" for s in signs)
            fn = self.variant(tag, oriented_rho(self.view.guard, signs), "rho")
            self._oriented[signs] = fn
        return fn

    def snapped(self, at_level: tuple[bool, ...]) -> tuple[Fn, Fn]:
        """``(rho, holds)`` of the guard with level atom ``i`` replaced by ``at_level[i]``."""
        if not self.levels:
            return self.rho, self.holds
        pair = self._snapped.get(at_level)
        if pair is None:
            assert self.variant is not None
            tag = "".join("y" if a else "n" for a in at_level)
            guard = snapped(self.view.guard, at_level)
            pair = (
                self.variant(tag, guard_to_rho(guard), "rho"),
                self.variant(tag, guard, "holds"),
            )
            self._snapped[at_level] = pair
        return pair


@dataclass
class CompiledMode:
    key: Mode
    name: str
    rhs: Fn
    outputs: Fn
    invariants: list[CompiledCondition]
    transitions: list[CompiledTransition]
    urgent: tuple[str, ...] = ()
    """Urgent locations of the mode: no time may pass while in one."""
    flow: Fn | None = None
    """What the solver steps, if not ``rhs``: ``rhs`` keeping its signals for the watch
    and the outputs at the step's end (:class:`~hybrid.expr.codegen.Stash`)."""


@dataclass(frozen=True)
class Source:
    """What a generated function computes, for messages: its role and its expressions."""

    what: str
    exprs: tuple[ir.Expr, ...]
    context: CodeContext
