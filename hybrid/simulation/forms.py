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

import functools
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from hybrid.expr import ir
from hybrid.expr.codegen import CodeContext, EvalFailure, compile_function
from hybrid.expr.rho import guard_to_rho, oriented_rho, snapped, within_band
from hybrid.modes import Mode, TransitionView

__all__ = [
    "Assembly",
    "CompiledCondition",
    "CompiledMode",
    "CompiledTransition",
    "Fn",
    "Part",
    "Sitting",
    "Source",
    "sitting_form",
]

Fn = Callable[[float, Any], Any]
Sitting = Callable[[float, Any, float], bool]
"""``(t, x, width)``: the condition with each comparison within ``width`` of its boundary
decided as on it (:func:`hybrid.expr.rho.within_band`)."""


def sitting_form(name: str, expr: ir.Expr, ctx: CodeContext) -> Sitting:
    """``expr`` decided within a band, compiled as ``name`` (the width read as a state after
    the others, under a name none of ``ctx``'s takes).

    >>> x = ir.Var("x", ir.STATE)
    >>> sit = sitting_form("sit", ir.Cmp(("<=",), (x, ir.Num(1.0))), CodeContext(states=["x"]))
    >>> sit(0.0, np.array([1.0 + 1e-15]), 1e-10), sit(0.0, np.array([1.0 + 1e-15]), 0.0)
    (True, False)
    """
    taken = {*ctx.states, *ctx.signals, *ctx.inputs, *ctx.params, *ctx.functions}
    band = "band"
    while band in taken:
        band += "_"
    wide = replace(ctx, states=(*ctx.states, band))
    fn = compile_function(name, [within_band(expr, ir.Var(band, ir.STATE))], wide, shape="scalar")

    def sitting(t: float, x: Any, width: float) -> bool:
        return bool(fn(t, np.append(x, width)))

    return sitting


@dataclass
class CompiledCondition:
    """A guard or invariant: ``rho(t, x) <= 0`` iff ``holds(t, x)`` (off the boundary).

    ``widen`` compiles a form of it decided within a band (:data:`Sitting`), on
    first use; without it, :meth:`sitting` is ``holds`` (rounding decides).
    """

    name: str
    rho: Fn
    holds: Fn
    widen: Callable[[ir.Expr], Sitting] | None = field(default=None, kw_only=True)
    expr: ir.Expr | None = field(default=None, kw_only=True)
    """The condition, for ``widen``."""
    _sitting: Sitting | None = field(default=None, init=False, repr=False)

    def sitting(self) -> Sitting:
        """The condition decided within a band (``(t, x, width) -> bool``)."""
        if self._sitting is None:
            if self.widen is None or self.expr is None:
                holds = self.holds
                self._sitting = lambda t, x, width: bool(holds(t, x))
            else:
                self._sitting = self.widen(self.expr)
        return self._sitting


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
    _snapped: dict[tuple[bool, ...], tuple[Fn, Fn, Callable[[], Sitting]]] = field(
        default_factory=dict
    )

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

    def snapped(self, at_level: tuple[bool, ...]) -> tuple[Fn, Fn, Callable[[], Sitting]]:
        """``(rho, holds, sitting)`` of the guard with level atom ``i`` replaced by
        ``at_level[i]`` (``sitting()`` as :meth:`sitting`)."""
        if not self.levels:
            return self.rho, self.holds, self.sitting
        found = self._snapped.get(at_level)
        if found is None:
            assert self.variant is not None and self.widen is not None
            tag = "".join("y" if a else "n" for a in at_level)
            guard = snapped(self.view.guard, at_level)
            found = (
                self.variant(tag, guard_to_rho(guard), "rho"),
                self.variant(tag, guard, "holds"),
                functools.cache(functools.partial(self.widen, guard)),  # compiled when first used
            )
            self._snapped[at_level] = found
        return found


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
    terms: Fn | None = None
    """Every transition's ``rho`` then every invariant's ``rho``, in one function (a tuple):
    the signals they share computed once (:class:`~hybrid.simulation.events.Watch`). It
    records failures in ``terms_failure``, never the model's: on a failure the watch
    evaluates the functions one by one instead, which record it as they always did."""
    terms_failure: EvalFailure | None = None
    assembly: Assembly | None = None
    """Of a mode built from its components' parts (:mod:`~hybrid.simulation.parts`)."""


@dataclass
class Part:
    """One component in one location, the locations it reads fixed: compiled once
    (:mod:`~hybrid.simulation.parts`)."""

    flow: Fn
    signals: Fn
    invariants: list[CompiledCondition]
    transitions: list[CompiledTransition]
    urgent: str | None


@dataclass(frozen=True)
class Assembly:
    """A mode built from parts: its parts in component order, and the names its joined
    right-hand side and signal outputs record their failures under."""

    parts: tuple[Part, ...]
    flow_where: str
    signals_where: str


@dataclass(frozen=True)
class Source:
    """What a generated function computes, for messages: its role and its expressions."""

    what: str
    exprs: tuple[ir.Expr, ...]
    context: CodeContext
