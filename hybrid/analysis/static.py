"""Static facts of one automaton, decided over the declared bounds of its state.

Everything here looks at one automaton alone (a component of a system sees
its inputs as unknowns): which edges can ever fire (*live*), where a run may
enter each location, where the flow can leave each location, and which
same-priority edges can be enabled together. Cycles of edges taken without
time passing are :mod:`hybrid.analysis.zerotime`'s.

Semantics (see docs/check.md, "What is proved"):

- the state ranges over the box of declared ``bounds`` (unbounded if none);
  ``t`` over ``[0, inf)``; an input over its declared ``range`` (in a system:
  a free input's range, the bounds of the state variable it reads, else
  unknown); vector signals are unknown;
- parameters are bound to the automaton's values and signals replaced by the
  definitions in force in the location (location overrides first);
- an edge may fire at a point of its source location where its guard may be
  found enabled (:func:`~hybrid.analysis.enabled.enabled_region`: where it
  holds, or on the boundary of a strict comparison the flow enters), that
  point being either in the closure of the source invariant (while flowing:
  an equality level is reached from the side the invariant keeps) or an
  *entry* point (the flow keeps the state on an equality level): the initial
  state, or a state right after an edge into the location fired, whether or
  not the invariant holds there;
- entry points are over-approximated by a box per location, the least
  fixpoint of "the initial set (in every initial location), and the reset of
  every box where an edge into the location may fire", widened to the
  declared bounds if it does not settle within :data:`ENTRY_ROUNDS` rounds;
- in an *urgent* location no time passes: a run is there only at entry
  points, so its edges fire only from there.

Examples
--------
>>> import hybrid
>>> ball = hybrid.load("specs/bouncing_ball.yaml")
>>> facts = AutomatonFacts(ball)
>>> [e.live for e in facts.edges], facts.locations["falling"].can_be_left
([True], True)
>>> facts.covered("falling", [0])
True
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from types import MappingProxyType

from hybrid.analysis.enabled import enabled_region, invariant_side, surely_enabled_at_entry
from hybrid.analysis.flows import exit_conditions
from hybrid.analysis.inline import inline_signals
from hybrid.analysis.linear import structural_key
from hybrid.analysis.solve import Box, Env, closure, conjoin, contract, negate, satisfiable
from hybrid.expr import ir
from hybrid.expr.interval import ENTIRE, Interval
from hybrid.expr.rho import level_key, levels
from hybrid.expr.transform import bind_parameters
from hybrid.model import Automaton, Edge

__all__ = [
    "ENTRY_ROUNDS",
    "AutomatonFacts",
    "EdgeFacts",
    "LocationFacts",
    "hull",
    "initial_box",
    "inline_signals",
]

ENTRY_ROUNDS = 32
_TIME = Interval(0.0, math.inf)


@dataclass(frozen=True)
class EdgeFacts:
    """An edge with parameters bound, where it may be enabled, and whether it can ever fire.

    ``enabled`` is the guard as the simulator may find it enabled while flowing
    in the source location, ``entry_enabled`` at an entry point of it
    (:func:`~hybrid.analysis.enabled.enabled_region`); ``idle`` holds wherever the
    guard may not be enabled at an entry point, ``idle_at_exit`` at a point where
    the flow leaves the invariant; ``fires`` a box holding every state it may fire
    from (``None``: never).
    """

    edge: Edge
    guard: ir.Expr
    reset: Mapping[str, ir.Expr]
    enabled: ir.Expr
    entry_enabled: ir.Expr
    idle: ir.Expr
    idle_at_exit: ir.Expr
    live: bool
    fires: Box | None = None


@dataclass(frozen=True)
class LocationFacts:
    """A location with parameters bound: its invariant, flow and exit conditions."""

    name: str
    env: Env
    invariant: ir.Expr
    closed: ir.Expr
    flow: Mapping[str, ir.Expr]
    region: Box | None
    exits: tuple[ir.Expr, ...]
    can_be_left: bool


def _may_snap(automaton: Automaton) -> list[bool]:
    """Per edge, whether an equality atom of its guard may be snapped at an entry of its
    source: the entry comes at the instant a stay stopped (jumps take no time), where a
    level reached and not used by the jump taken counts as reached (docs/semantics.md,
    "a level reached stays reached"). Not where every edge into the source uses each of
    the guard's levels (reads an equality atom over the same variables)."""
    params = automaton.parameters

    def keys(edge: Edge) -> set[str]:  # the simulator's identity of a level, one automaton
        return {level_key(d, ()) for d in levels(bind_parameters(edge.guard, params))}

    read = [keys(edge) for edge in automaton.edges]
    into: dict[str, list[int]] = {}
    for i, edge in enumerate(automaton.edges):
        into.setdefault(edge.target, []).append(i)
    return [
        bool(read[k]) and any(read[k] - read[i] for i in into.get(edge.source, []))
        for k, edge in enumerate(automaton.edges)
    ]


def initial_box(automaton: Automaton) -> dict[str, Interval]:
    """The box of initial states: the initial set of every state variable; ``t = 0``."""
    box = {name: Interval(r.lo, r.hi) for name, r in automaton.initial_set().items()}
    box["t"] = Interval.point(0.0)
    return box


def hull(a: Box | None, b: Box | None) -> dict[str, Interval] | None:
    """The smallest box holding both (a name absent from a box is unbounded there)."""
    if a is None:
        return None if b is None else dict(b)
    if b is None:
        return dict(a)
    result: dict[str, Interval] = {}
    for name in set(a) & set(b):
        result[name] = a[name].hull(b[name])
    if "t" in a or "t" in b:
        result["t"] = a.get("t", _TIME).hull(b.get("t", _TIME))
    return result


class AutomatonFacts:
    """The static facts of ``automaton``, computed once; queries are cached.

    Parameters
    ----------
    automaton
        The automaton, with the parameter values to analyse.
    inputs
        The interval of each input known to stay in one (default: the declared ranges).
    volatile
        Inputs another component's jump may change at once: after a jump, unknown again.
    """

    def __init__(
        self,
        automaton: Automaton,
        inputs: Mapping[str, Interval] | None = None,
        volatile: frozenset[str] = frozenset(),
    ) -> None:
        self.automaton = automaton
        params = automaton.parameters
        if inputs is None:
            inputs = {k: Interval(r.lo, r.hi) for k, r in automaton.input_ranges().items()}
        self.inputs = dict(inputs)
        self.volatile = volatile
        self.bounds: dict[str, Interval] = {
            s.name: Interval(s.lower, s.upper) for s in automaton.states
        }
        self.bounds.update(self.inputs)
        opaque = frozenset(n for n, f in automaton.functions.items() if not f.builtin)
        self.opaque = opaque
        vectors = automaton.vector_sizes  # their values are a library's: unknown here
        base = {
            k: bind_parameters(v, params) for k, v in automaton.signals.items() if k not in vectors
        }
        self.locations: dict[str, LocationFacts] = {}
        envs: dict[tuple[object, ...], Env] = {}  # locations with the same signals share one
        for name, loc in automaton.locations.items():
            signals = dict(base)
            signals.update(
                {k: bind_parameters(v, params) for k, v in loc.signals.items() if k not in vectors}
            )
            env_key = tuple(sorted((k, structural_key(v)) for k, v in signals.items()))
            env = envs.setdefault(env_key, Env(MappingProxyType(signals), opaque))
            invariant = bind_parameters(loc.invariant, params)
            closed = closure(invariant)
            flow = {k: bind_parameters(v, params) for k, v in loc.flow.items()}
            region = contract(closed, env, self.bounds)
            exits = tuple(exit_conditions(invariant, flow, signals, opaque))
            can_be_left = region is not None and any(
                satisfiable(x, env, self.bounds) for x in exits
            )
            if loc.urgent:  # never flowing: left at once on entry, or blocked
                region, exits, can_be_left = None, (), True
            self.locations[name] = LocationFacts(
                name, env, invariant, closed, MappingProxyType(flow), region, exits, can_be_left
            )
        self.edges = self._edge_facts(automaton)
        self._out: dict[str, list[EdgeFacts]] = {name: [] for name in self.locations}
        self._in: dict[str, list[EdgeFacts]] = {name: [] for name in self.locations}
        for ef in self.edges:
            self._out[ef.edge.source].append(ef)
            self._in[ef.edge.target].append(ef)
        self._covered: dict[tuple[str, frozenset[int]], bool] = {}
        self._overlap: dict[tuple[int, int], bool] = {}

    def _edge_facts(self, automaton: Automaton) -> list[EdgeFacts]:
        """Every edge's enabled regions, entry boxes of every location, then liveness."""
        params = automaton.parameters
        guards, resets, enabled, at_entry, flowing = [], [], [], [], []
        snaps = _may_snap(automaton)
        for k, edge in enumerate(automaton.edges):
            src = self.locations[edge.source]
            guard = bind_parameters(edge.guard, params)
            signals = src.env.signals
            side = invariant_side(src.closed, src.env, src.region)
            region = enabled_region(guard, src.flow, signals, self.opaque, side=side)
            guards.append(guard)
            resets.append({k: bind_parameters(v, params) for k, v in edge.reset.items()})
            enabled.append(region)
            at_entry.append(
                enabled_region(guard, src.flow, signals, self.opaque, entry=True, snapped=snaps[k])
            )
            # while flowing the state is in the closure of the invariant, within the bounds
            flowing.append(
                None
                if src.region is None
                else contract(conjoin(src.closed, region), src.env, src.region)
            )
        self.entries = self._entries(automaton, resets, at_entry, flowing)
        result: list[EdgeFacts] = []
        for k, edge in enumerate(automaton.edges):
            src = self.locations[edge.source]
            entry = self.entries[edge.source]
            live = False
            if flowing[k] is not None:
                live = satisfiable(conjoin(src.closed, enabled[k]), src.env, src.region or {})
            if not live and entry is not None:
                live = satisfiable(at_entry[k], src.env, entry)
            fires = hull(flowing[k], self._at_entry(k, at_entry, entry)) if live else None
            surely = [
                surely_enabled_at_entry(
                    guards[k], src.flow, src.env.signals, self.opaque, snapped=snapped
                )
                for snapped in (False, True)
            ]
            result.append(
                EdgeFacts(
                    edge,
                    guards[k],
                    MappingProxyType(resets[k]),
                    enabled[k],
                    at_entry[k],
                    negate(surely[0]),
                    negate(surely[1]),
                    live,
                    fires,
                )
            )
        return result

    def _at_entry(self, k: int, enabled: list[ir.Expr], entry: Box | None) -> Box | None:
        if entry is None:
            return None
        src = self.locations[self.automaton.edges[k].source]
        return contract(enabled[k], src.env, entry)

    def _entries(
        self,
        automaton: Automaton,
        resets: list[dict[str, ir.Expr]],
        enabled: list[ir.Expr],
        flowing: list[dict[str, Interval] | None],
    ) -> dict[str, dict[str, Interval] | None]:
        """Per location, a box holding every state a run may enter it with (``None``: none)."""
        entries: dict[str, dict[str, Interval] | None] = {name: None for name in self.locations}
        for name in automaton.initial_locations:
            entries[name] = {**initial_box(automaton), **self.inputs}
        rounds = 0
        while True:
            changed = False
            for k, edge in enumerate(automaton.edges):
                fire = hull(flowing[k], self._at_entry(k, enabled, entries[edge.source]))
                if fire is None:
                    continue
                post = self.reset_box(edge.source, resets[k], fire)
                if post is None:
                    continue
                grown = hull(entries[edge.target], post)
                if grown != entries[edge.target]:
                    entries[edge.target] = grown
                    changed = True
            if not changed:
                return entries
            rounds += 1
            if rounds >= ENTRY_ROUNDS:  # not settling (a growing loop): widen to the bounds
                for name, box in entries.items():
                    if box is not None:
                        entries[name] = hull(box, self.bounds)

    def reset_box(
        self, location: str, reset: Mapping[str, ir.Expr], box: Box, *, keep: bool = False
    ) -> dict[str, Interval] | None:
        """The box of states right after a reset applied in ``box``, within the bounds
        (``keep``: volatile inputs keep their values, as when no other component jumps)."""
        ev = self.locations[location].env.evaluator(box)
        after = dict(box)
        for var, expr in reset.items():
            after[var] = ev.number(expr)
        for var in () if keep else self.volatile:  # another component's jump may change it
            after.pop(var, None)
        for var, bound in self.bounds.items():
            narrowed = after.get(var, ENTIRE).intersect(bound)
            if narrowed is None:
                return None
            after[var] = narrowed
        return after

    def outgoing(self, location: str) -> list[EdgeFacts]:
        """Facts of the edges leaving ``location``, in file order."""
        return self._out[location]

    def incoming(self, location: str) -> list[EdgeFacts]:
        """Facts of the edges entering ``location``, in file order."""
        return self._in[location]

    def overlap(self, first: int, second: int) -> bool:
        """Whether edges ``first`` and ``second`` (same source) can be enabled at once.

        While flowing (in the closure of the invariant) or at an entry point.
        """
        key = (min(first, second), max(first, second))
        if key not in self._overlap:
            a, b = self.edges[key[0]], self.edges[key[1]]
            name = a.edge.source
            src = self.locations[name]
            both = conjoin(a.enabled, b.enabled)
            entry = self.entries[name]
            self._overlap[key] = (
                a.live
                and b.live
                and (
                    (
                        src.region is not None
                        and satisfiable(conjoin(src.closed, both), src.env, src.region)
                    )
                    or (
                        entry is not None
                        and satisfiable(
                            conjoin(a.entry_enabled, b.entry_enabled), src.env, entry
                        )
                    )
                )
            )
        return self._overlap[key]

    def conflicts(self, location: str) -> list[tuple[int, int]]:
        """Pairs of live edges of ``location`` with the same priority that can be enabled at once."""
        live = [f.edge for f in self.outgoing(location) if f.live]
        return [
            (a.index, b.index)
            for a, b in itertools.combinations(live, 2)
            if a.priority == b.priority and self.overlap(a.index, b.index)
        ]

    def covered(self, location: str, edges: Iterable[int]) -> bool:
        """Whether every point where a run may have to leave ``location`` enables one of ``edges``.

        Those points are the exits of the invariant (its boundary, where the
        flow points outward) and the entry points where the invariant does not
        hold. ``True`` also when the location can be neither left nor entered
        outside its invariant.
        """
        chosen = frozenset(edges)
        key = (location, chosen)
        if key not in self._covered:
            loc = self.locations[location]
            # at an exit of the invariant an edge may be idle wherever it is not surely enabled
            negated = [self.edges[i].idle_at_exit for i in sorted(chosen)]
            urgent = self.automaton.locations[location].urgent
            stuck = (
                not urgent
                and loc.can_be_left
                and any(satisfiable(conjoin(x, *negated), loc.env, self.bounds) for x in loc.exits)
            )
            entry = self.entries[location]
            if not stuck and entry is not None:
                # on entry an edge may be idle wherever it is not surely enabled; an urgent
                # location must be left at once wherever it is entered
                idle = [self.edges[i].idle for i in sorted(chosen)]
                leaving = (ir.BoolConst(True),) if urgent else (negate(loc.invariant), *loc.exits)
                stuck = any(satisfiable(conjoin(v, *idle), loc.env, entry) for v in leaving)
            self._covered[key] = not stuck
        return self._covered[key]
