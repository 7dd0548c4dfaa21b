"""The per-mode view of a system: what is in force when each component is in a location.

A *mode* is one location per component. :func:`mode_of` gives its flows,
signals, invariants and outgoing transitions (synchronised ones included) with
parameters already bound, so that a single automaton and a system look the
same to the simulator and the analysis (an automaton is a system of one
component, :func:`hybrid.compose.as_system`). Edges whose label several
components declare fire together, one edge from each; the others fire alone.

Examples
--------
>>> import hybrid
>>> from hybrid.compose import compose
>>> a = hybrid.load_text("automaton: a\\nstate: {x: {}}\\nlocations: {l: {flow: {x: 1}}}\\n")
>>> b = hybrid.load_text("automaton: b\\nstate: {y: {}}\\nlocations: {m: {flow: {y: 2}}}\\n")
>>> s = compose(a, b)
>>> s.mode_name(s.initial_mode), list(mode_of(s, s.initial_mode).flow)
('a.l|b.m', ['x', 'y'])
"""

from __future__ import annotations

import itertools
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

from hybrid.compose import System
from hybrid.expr import ir
from hybrid.expr.transform import bind_parameters
from hybrid.held import HeldCache
from hybrid.model import Edge

__all__ = ["Binder", "Mode", "ModeView", "TransitionView", "mode_of", "transitions_of"]

Mode = tuple[str, ...]


@dataclass(frozen=True)
class TransitionView:
    """An outgoing transition of a mode: one edge, or one edge per synchronising component."""

    name: str
    label: str | None
    edges: tuple[tuple[int, Edge], ...]
    guard: ir.Expr
    reset: Mapping[str, ir.Expr]
    priority: int
    order: tuple[int, ...]
    target: Mode


@dataclass(frozen=True)
class ModeView:
    """Everything in force in one mode, parameters bound."""

    key: Mode
    name: str
    flow: Mapping[str, ir.Expr]
    signals: Mapping[str, ir.Expr]
    """Every signal's definition in force (vector ones are calls of multi-output functions)."""
    invariants: tuple[tuple[str, ir.Expr], ...]
    transitions: tuple[TransitionView, ...]
    urgent: tuple[str, ...] = ()
    """The urgent locations of the mode (qualified): while there is one, no time passes."""


class Binder:
    """Binds a component's parameters into its expressions once, for many modes.

    ``mode_of(system, key, binder=Binder(system))`` gives the same view as
    without it, but an expression met again in another mode is not bound
    again: its bound copy is reused (the same object, so whoever caches by
    expression, as the compiled model does, finds it again). Another model
    whose parameters an expression reads with the same values gets the same
    copy too (:func:`_bound_copy`).
    """

    def __init__(self, system: System) -> None:
        self.system = system
        self._bound: dict[tuple[int, int], tuple[ir.Expr, ir.Expr]] = {}

    def __call__(self, i: int, node: ir.Expr) -> ir.Expr:
        key = (i, id(node))
        found = self._bound.get(key)
        if found is None or found[0] is not node:
            found = (node, _bound_copy(node, self.system.components[i].automaton.parameters))
            self._bound[key] = found
        return found[1]


_COPIES = HeldCache[ir.Expr](1 << 16)
"""Bound copies by the expression's identity (held) and the values of what it reads."""


def _bound_copy(node: ir.Expr, parameters: Mapping[str, float]) -> ir.Expr:
    """``bind_parameters(node, parameters)``, the same object again wherever the values of
    the parameters ``node`` reads are the same, bit for bit: the variants of a sweep share
    the bound expressions their changed parameters do not reach, and whatever is kept of
    them (a compiled function, keyed by what it computes)."""
    values = tuple(float(parameters[p]).hex() for p in sorted(ir.names_in(node, ir.PARAM)))
    return _COPIES.get((id(node), values), node, lambda: bind_parameters(node, parameters))


def transitions_of(
    system: System, key: Mode, *, bind: bool = True, binder: Binder | None = None
) -> tuple[TransitionView, ...]:
    """The transitions leaving mode ``key``, in priority-then-file order of their edges."""
    owners = system.shared_labels
    result: list[TransitionView] = []
    shared: dict[str, list[list[Edge]]] = {}
    for i, (c, loc) in enumerate(zip(system.components, key, strict=True)):
        for edge in c.automaton.outgoing(loc):
            if edge.label is None or edge.label not in owners:
                result.append(_single(system, key, i, edge, bind, binder))
            else:
                shared.setdefault(edge.label, [[] for _ in owners[edge.label]])
                slot = owners[edge.label].index(i)
                shared[edge.label][slot].append(edge)
    for label, per_comp in shared.items():
        comps = owners[label]
        for combo in itertools.product(*per_comp):
            result.append(
                _synchronised(
                    system, key, label, list(zip(comps, combo, strict=True)), bind, binder
                )
            )
    result.sort(key=lambda tr: tr.order)
    return tuple(result)


def _bound(
    system: System, i: int, node: ir.Expr, bind: bool, binder: Binder | None = None
) -> ir.Expr:
    if not bind:
        return node
    if binder is not None:
        return binder(i, node)
    return bind_parameters(node, system.components[i].automaton.parameters)


def _single(
    system: System, key: Mode, i: int, edge: Edge, bind: bool, binder: Binder | None = None
) -> TransitionView:
    target = list(key)
    target[i] = edge.target
    return TransitionView(
        name=system.qualified(i, edge.name),
        label=edge.label,
        edges=((i, edge),),
        guard=_bound(system, i, edge.guard, bind, binder),
        reset=MappingProxyType(
            {k: _bound(system, i, v, bind, binder) for k, v in edge.reset.items()}
        ),
        priority=edge.priority,
        order=(i, edge.index),
        target=tuple(target),
    )


def _synchronised(
    system: System,
    key: Mode,
    label: str,
    parts: list[tuple[int, Edge]],
    bind: bool,
    binder: Binder | None = None,
) -> TransitionView:
    target = list(key)
    reset: dict[str, ir.Expr] = {}
    guards: list[ir.Expr] = []
    for i, edge in parts:
        target[i] = edge.target
        guards.append(_bound(system, i, edge.guard, bind, binder))
        reset.update({k: _bound(system, i, v, bind, binder) for k, v in edge.reset.items()})
    return TransitionView(
        name="+".join(system.qualified(i, e.name) for i, e in parts),
        label=label,
        edges=tuple(parts),
        guard=guards[0] if len(guards) == 1 else ir.BoolOp("and", tuple(guards)),
        reset=MappingProxyType(reset),
        priority=max(e.priority for _, e in parts),
        order=tuple(x for i, e in parts for x in (i, e.index)),
        target=tuple(target),
    )


def mode_of(
    system: System, key: Mode, *, bind: bool = True, binder: Binder | None = None
) -> ModeView:
    """Flows, signals, invariants and transitions of mode ``key``, parameters bound.

    ``binder`` (a :class:`Binder`) reuses the bound expressions of earlier calls;
    ``bind=False`` leaves the parameters as names (the compiled backend's slots).
    """
    flow: dict[str, ir.Expr] = {}
    signals: dict[str, ir.Expr] = {}
    invariants: list[tuple[str, ir.Expr]] = []
    urgent: list[str] = []
    for i, (c, loc_name) in enumerate(zip(system.components, key, strict=True)):
        a = c.automaton
        loc = a.locations[loc_name]
        if loc.urgent:
            urgent.append(system.qualified(i, loc_name))
        for name in a.signal_names:
            signals[name] = _bound(system, i, loc.signals.get(name, a.signals[name]), bind, binder)
        for var, expr in loc.flow.items():
            flow[var] = _bound(system, i, expr, bind, binder)
        if not (isinstance(loc.invariant, ir.BoolConst) and loc.invariant.value):
            invariants.append(
                (system.qualified(i, loc_name), _bound(system, i, loc.invariant, bind, binder))
            )
    return ModeView(
        key=key,
        name=system.mode_name(key),
        flow=MappingProxyType(flow),
        signals=MappingProxyType(signals),
        invariants=tuple(invariants),
        transitions=transitions_of(system, key, bind=bind, binder=binder),
        urgent=tuple(urgent),
    )
