"""Cycles of edges that may fire again and again without time passing.

The *zero-time graph* of an automaton has one node per live edge and an arc
``e -> f`` when ``f`` leaves the target of ``e`` and may be enabled right after
``e`` fired: in the box of states ``e``'s reset produces from the box where
``e`` may fire, with the conditions of ``e``'s guard on the variables the
reset leaves alone still holding (their closure), and whether or not the
target's invariant holds there (the simulator tests the edges of a location
on entry before its invariant). A run that jumps forever at one instant
follows an infinite path of this graph, so it stays, from some jump on, in
one of its strongly connected components with at least one arc. Those
components are found in linear time (Tarjan, through networkx), and each one
found is reported with a shortest cycle through its first edge as witness.
The search is complete: no cycle of the graph is missed, however many simple
cycles there are.

In a system an edge on a shared label fires only together with an edge of
the same label of every other owner, so a zero-time cycle through it needs
each owner to be able to fire that label again and again at one instant too:
:func:`system_components` keeps a label only while every owner has an edge
with it inside a component, and recomputes until nothing changes.

Examples
--------
>>> import hybrid
>>> ping = hybrid.load_text('''
... automaton: ping
... state: {x: {bounds: [0, 10]}}
... locations: {a: {flow: {x: 1}}, b: {flow: {x: 1}}}
... edges:
...   - {name: go, from: a, to: b, guard: x >= 1}
...   - {name: back, from: b, to: a, guard: x >= 1}
... ''')
>>> from hybrid.analysis.static import AutomatonFacts
>>> [(c.edges, c.cycle) for c in ZeroTimeGraph(AutomatonFacts(ping)).components()]
[((0, 1), (0, 1))]
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import networkx as nx

from hybrid.analysis.inline import inline_signals
from hybrid.analysis.solve import closure, conjoin, nnf, satisfiable
from hybrid.analysis.static import AutomatonFacts
from hybrid.expr import ir

__all__ = ["ZeroTimeComponent", "ZeroTimeGraph", "system_components"]


@dataclass(frozen=True)
class ZeroTimeComponent:
    """A strongly connected component of the zero-time graph (edge indices, sorted).

    ``cycle`` is a shortest cycle through its first edge, in firing order.
    """

    edges: tuple[int, ...]
    cycle: tuple[int, ...]


class ZeroTimeGraph:
    """The zero-time graph of one automaton (built once; queries are cheap)."""

    def __init__(self, facts: AutomatonFacts) -> None:
        self.facts = facts
        self.graph = nx.DiGraph()
        for ef in facts.edges:
            if ef.live:
                self.graph.add_node(ef.edge.index)
        for ef in facts.edges:
            if not ef.live or ef.fires is None:
                continue
            # inputs another component provides change only when it jumps too: a cycle
            # forever at one instant ends with them fixed (or that component cycles too)
            after = facts.reset_box(ef.edge.source, ef.reset, ef.fires, keep=True)
            if after is None:
                continue
            dst = facts.locations[ef.edge.target]
            kept = _kept_conditions(ef.guard, ef.reset, facts.locations[ef.edge.source].env.signals)
            for nxt in facts.outgoing(ef.edge.target):
                if nxt.live and satisfiable(conjoin(nxt.entry_enabled, *kept), dst.env, after):
                    self.graph.add_edge(ef.edge.index, nxt.edge.index)

    def components(self, allowed: Callable[[int], bool] | None = None) -> list[ZeroTimeComponent]:
        """The components with a cycle, among the edges ``allowed`` keeps (all by default)."""
        graph = self.graph
        if allowed is not None:
            graph = nx.subgraph_view(graph, filter_node=allowed)
        found: list[ZeroTimeComponent] = []
        for nodes in nx.strongly_connected_components(graph):
            first = min(nodes)
            if len(nodes) == 1 and not graph.has_edge(first, first):
                continue
            found.append(
                ZeroTimeComponent(tuple(sorted(nodes)), _shortest_cycle(graph, first, nodes))
            )
        return sorted(found, key=lambda c: c.edges)


def _kept_conditions(
    guard: ir.Expr, reset: Mapping[str, ir.Expr], signals: Mapping[str, ir.Expr]
) -> list[ir.Expr]:
    """Conjuncts of ``guard`` (closed, signals inlined) on variables the reset leaves alone."""
    kept: list[ir.Expr] = []
    for cond in _conjuncts(nnf(guard)):
        inlined = inline_signals(cond, signals)
        if inlined is not None and not (ir.names_in(inlined, ir.STATE) & reset.keys()):
            kept.append(closure(inlined))
    return kept


def _conjuncts(cond: ir.Expr) -> list[ir.Expr]:
    if isinstance(cond, ir.BoolOp) and cond.op == "and":
        return [c for v in cond.values for c in _conjuncts(v)]
    if isinstance(cond, ir.BoolConst):
        return []
    return [cond]


def _shortest_cycle(graph: nx.DiGraph, start: int, nodes: set[int]) -> tuple[int, ...]:
    """A shortest cycle through ``start`` inside ``nodes`` (breadth first)."""
    if graph.has_edge(start, start):
        return (start,)
    parent: dict[int, int] = {start: start}
    queue = deque([start])
    while queue:
        node = queue.popleft()
        for nxt in graph.successors(node):
            if nxt == start:
                path = [node]
                while path[-1] != start:
                    path.append(parent[path[-1]])
                return tuple(reversed(path))
            if nxt in nodes and nxt not in parent:
                parent[nxt] = node
                queue.append(nxt)
    return (start,)  # pragma: no cover - a component with a cycle always closes one


def system_components(
    graphs: Sequence[ZeroTimeGraph],
    shared: Mapping[str, Sequence[int]],
    allowed: Callable[[int, int], bool] | None = None,
) -> list[list[ZeroTimeComponent]]:
    """Per component, the zero-time components once shared labels are accounted for.

    ``shared`` maps each shared label to its owners; ``allowed(component,
    edge)`` may exclude edges (for instance those whose source is never
    reached). A label stays only while every owner has an edge with it in a
    component; edges with a label that is gone are dropped, and the
    components recomputed, until nothing changes (the greatest fixpoint).
    """
    capable = set(shared)

    def keeps(i: int) -> Callable[[int], bool]:
        edges = graphs[i].facts.automaton.edges

        def keep(e: int) -> bool:
            label = edges[e].label
            if label is not None and label in shared and label not in capable:
                return False
            return allowed is None or allowed(i, e)

        return keep

    while True:
        found = [g.components(keeps(i)) for i, g in enumerate(graphs)]
        still: set[str] = set()
        for label in capable:
            if all(
                any(
                    graphs[o].facts.automaton.edges[e].label == label
                    for c in found[o]
                    for e in c.edges
                )
                for o in shared[label]
            ):
                still.add(label)
        if still == capable:
            return found
        capable = still
