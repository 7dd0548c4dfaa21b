"""Static facts of one automaton, decided over the declared bounds of its state.

Everything here looks at one automaton alone (a component of a system sees
its inputs as unknowns): which edges can ever fire (*live*), where the flow can
leave each location, which same-priority edges can be enabled together, and
which cycles of edges can be taken without time passing.

Semantics (see docs/cli.md, "How the checks decide"):

- the state ranges over the box of declared ``bounds`` (unbounded if none);
  ``t`` over ``[0, inf)``; inputs and vector signals are unknown;
- parameters are bound to the automaton's values and signals replaced by the
  definitions in force in the location (location overrides first);
- a jump happens in the closure of the source invariant (strict comparisons of
  an invariant count as non-strict), where the guard holds (strictness kept);
- after a reset the reset variables take the range of their reset expression
  over the box where the edge fires, the others keep theirs.

Examples
--------
>>> import hybrid
>>> ball = hybrid.load("specs/bouncing_ball.yaml")
>>> facts = AutomatonFacts(ball)
>>> [e.live for e in facts.edges], facts.locations["falling"].can_be_left
([True], True)
>>> facts.covered("falling", [0]), facts.zero_time_cycles()
(True, [])
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from types import MappingProxyType

import networkx as nx

from hybrid.analysis.flows import exit_conditions
from hybrid.analysis.linear import structural_key
from hybrid.analysis.solve import Box, Env, closure, conjoin, contract, negate, satisfiable
from hybrid.expr import ir
from hybrid.expr.interval import Interval
from hybrid.expr.transform import bind_parameters
from hybrid.model import Automaton, Edge

__all__ = ["AutomatonFacts", "EdgeFacts", "Instant", "LocationFacts", "inline_signals"]

CYCLE_CAP = 200
FACTS_CAP = 16
INLINE_BUDGET = 400


@dataclass(frozen=True)
class EdgeFacts:
    """An edge with parameters bound, and whether its guard can ever hold."""

    edge: Edge
    guard: ir.Expr
    reset: Mapping[str, ir.Expr]
    live: bool


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


class AutomatonFacts:
    """The static facts of ``automaton``, computed once; queries are cached.

    Parameters
    ----------
    automaton
        The automaton, with the parameter values to analyse.
    """

    def __init__(self, automaton: Automaton) -> None:
        self.automaton = automaton
        params = automaton.parameters
        self.bounds: dict[str, Interval] = {
            s.name: Interval(s.lower, s.upper) for s in automaton.states
        }
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
            self.locations[name] = LocationFacts(
                name, env, invariant, closed, MappingProxyType(flow), region, exits, can_be_left
            )
        self.edges: list[EdgeFacts] = []
        for edge in automaton.edges:
            guard = bind_parameters(edge.guard, params)
            reset = {k: bind_parameters(v, params) for k, v in edge.reset.items()}
            src = self.locations[edge.source]
            live = src.region is not None and satisfiable(
                conjoin(src.closed, guard), src.env, src.region
            )
            self.edges.append(EdgeFacts(edge, guard, MappingProxyType(reset), live))
        self._out: dict[str, list[EdgeFacts]] = {name: [] for name in self.locations}
        self._in: dict[str, list[EdgeFacts]] = {name: [] for name in self.locations}
        for ef in self.edges:
            self._out[ef.edge.source].append(ef)
            self._in[ef.edge.target].append(ef)
        self._covered: dict[tuple[str, frozenset[int]], bool] = {}
        self._overlap: dict[tuple[int, int], bool] = {}

    def outgoing(self, location: str) -> list[EdgeFacts]:
        """Facts of the edges leaving ``location``, in file order."""
        return self._out[location]

    def incoming(self, location: str) -> list[EdgeFacts]:
        """Facts of the edges entering ``location``, in file order."""
        return self._in[location]

    def overlap(self, first: int, second: int) -> bool:
        """Whether edges ``first`` and ``second`` (same source) can be enabled at once."""
        key = (min(first, second), max(first, second))
        if key not in self._overlap:
            a, b = self.edges[key[0]], self.edges[key[1]]
            src = self.locations[a.edge.source]
            self._overlap[key] = (
                a.live
                and b.live
                and satisfiable(conjoin(src.closed, a.guard, b.guard), src.env, src.region or {})
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
        """Whether every exit point of ``location`` enables one of ``edges``.

        ``True`` also when the location cannot be left at all.
        """
        chosen = frozenset(edges)
        key = (location, chosen)
        if key not in self._covered:
            loc = self.locations[location]
            negated = [negate(self.edges[i].guard) for i in sorted(chosen)]
            self._covered[key] = not loc.can_be_left or not any(
                satisfiable(conjoin(x, *negated), loc.env, self.bounds) for x in loc.exits
            )
        return self._covered[key]

    def post(self, index: int, box: Box) -> dict[str, Interval] | None:
        """Box of the state right after edge ``index`` fires from a state in ``box``."""
        after = self._step(index, Instant(box))
        return None if after is None else dict(after.box)

    def enabled_in(self, index: int, box: Box) -> bool:
        """Whether edge ``index`` may be enabled somewhere in ``box``."""
        return self._enabled(index, Instant(box))

    def _enabled(self, index: int, at: Instant) -> bool:
        facts = self.edges[index]
        src = self.locations[facts.edge.source]
        return satisfiable(conjoin(src.closed, *at.facts, facts.guard), src.env, at.box)

    def _step(self, index: int, at: Instant) -> Instant | None:
        """What is known right after edge ``index`` fires from a state described by ``at``."""
        facts = self.edges[index]
        src = self.locations[facts.edge.source]
        box = contract(conjoin(src.closed, *at.facts), src.env, at.box)
        if box is None:
            return None
        box = contract(facts.guard, src.env, box)
        if box is None:
            return None
        ev = src.env.evaluator(box)
        after = dict(box)
        for var, expr in facts.reset.items():
            after[var] = ev.number(expr)
        for var, bound in self.bounds.items():
            current = after.get(var)
            narrowed = bound if current is None else current.intersect(bound)
            if narrowed is None:
                return None
            after[var] = narrowed
        # conditions on variables the reset leaves alone still hold after the jump
        kept = [c for c in at.facts if not (ir.names_in(c, ir.STATE) & facts.reset.keys())]
        for cond in (*_conjuncts(src.closed), *_conjuncts(facts.guard)):
            inlined = inline_signals(cond, src.env.signals)
            if inlined is not None and not (ir.names_in(inlined, ir.STATE) & facts.reset.keys()):
                kept.append(inlined)
        dst = self.locations[facts.edge.target]
        narrowed_box = contract(conjoin(dst.closed, *kept), dst.env, after)
        if narrowed_box is None:
            return None
        return Instant(narrowed_box, tuple(kept[-FACTS_CAP:]))

    def zero_time_cycles(self, cap: int = CYCLE_CAP) -> list[tuple[int, ...]]:
        """Cycles of live edges that may be taken again and again at one instant.

        Each edge of such a cycle can be enabled right after the previous one's
        reset: the state then lies in the box the reset produces, and still
        satisfies the conditions (guards, invariants) on the variables the
        reset left alone. The check goes twice around each candidate cycle.
        Cycles start at their lowest edge index; at most ``cap`` candidates are
        examined.
        """
        graph = nx.DiGraph()
        start = Instant(self.bounds)
        for facts in self.edges:
            if not facts.live:
                continue
            after = self._step(facts.edge.index, start)
            if after is None:
                continue
            for nxt in self.outgoing(facts.edge.target):
                if nxt.live and self._enabled(nxt.edge.index, after):
                    graph.add_edge(facts.edge.index, nxt.edge.index)
        found: list[tuple[int, ...]] = []
        for cycle in itertools.islice(nx.simple_cycles(graph), cap):
            if self._survives(cycle):
                first = cycle.index(min(cycle))
                found.append(tuple(cycle[first:] + cycle[:first]))
        return sorted(found)

    def _survives(self, cycle: Sequence[int]) -> bool:
        at: Instant | None = Instant(self.bounds)
        for index in list(cycle) * 2:
            if at is None or not self._enabled(index, at):
                return False
            at = self._step(index, at)
        return at is not None


@dataclass(frozen=True)
class Instant:
    """What is known of the state at one instant: a box and conditions (signals inlined)."""

    box: Box
    facts: tuple[ir.Expr, ...] = ()


def _conjuncts(cond: ir.Expr) -> list[ir.Expr]:
    if isinstance(cond, ir.BoolOp) and cond.op == "and":
        return [c for v in cond.values for c in _conjuncts(v)]
    if isinstance(cond, ir.BoolConst):
        return []
    return [cond]


def inline_signals(
    node: ir.Expr, signals: Mapping[str, ir.Expr], budget: int = INLINE_BUDGET
) -> ir.Expr | None:
    """``node`` with every signal replaced by its definition, or ``None``.

    ``None`` when the result would read inputs or vector signals (whose values
    another component or a library decides) or exceed ``budget`` nodes.

    Examples
    --------
    >>> from hybrid.expr.printer import to_source
    >>> s = {"g": ir.Bin("*", ir.Num(2.0), ir.Var("x", "state"))}
    >>> to_source(inline_signals(ir.Var("g", "signal"), s), {"x": "x"})
    '2.0 * x'
    """
    count = 0

    def go(n: ir.Expr) -> ir.Expr | None:
        nonlocal count
        count += 1
        if count > budget:
            return None
        if isinstance(n, ir.Var):
            if n.kind == ir.SIGNAL:
                definition = signals.get(n.name)
                return None if definition is None else go(definition)
            return None if n.kind == ir.INPUT else n
        if isinstance(n, ir.Index):
            return None
        kids = ir.children(n)
        if not kids:
            return n
        new = [go(k) for k in kids]
        if any(k is None for k in new):
            return None
        done = [k for k in new if k is not None]
        if isinstance(n, ir.Call):
            return ir.Call(n.func, tuple(done), n.col)
        if isinstance(n, ir.Unary):
            return ir.Unary(n.op, done[0], n.col)
        if isinstance(n, ir.Bin):
            return ir.Bin(n.op, done[0], done[1], n.col)
        if isinstance(n, ir.Cmp):
            return ir.Cmp(n.ops, tuple(done), n.col)
        if isinstance(n, ir.BoolOp):
            return ir.BoolOp(n.op, tuple(done), n.col)
        if isinstance(n, ir.Not):
            return ir.Not(done[0], n.col)
        return n  # pragma: no cover - leaves are handled above

    return go(node)
