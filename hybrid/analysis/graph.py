"""The location graph of an automaton, as a networkx MultiDiGraph.

Nodes are location names; each edge of the automaton is a graph edge keyed by
its name, so parallel edges and self-loops stay distinct. Attributes keep what
a check or a diagram needs: the guard and reset as the user wrote them, the
label, the priority, the source position, and ``live`` (whether the guard can
ever hold within the declared bounds, see :mod:`hybrid.analysis.static`).

Examples
--------
>>> import hybrid
>>> g = location_graph(hybrid.load("specs/thermostat.yaml"))
>>> sorted(g.nodes), [(u, v, k) for u, v, k in g.edges(keys=True)]
(['off', 'on'], [('off', 'on', 'turn_on'), ('on', 'off', 'turn_off')])
>>> g.edges["off", "on", "turn_on"]["guard"], g.graph["initial"]
('T <= T_low', 'off')
"""

from __future__ import annotations

import networkx as nx

from hybrid.analysis.explore import explore
from hybrid.analysis.product import ProductTables, Transition
from hybrid.analysis.static import AutomatonFacts
from hybrid.expr.printer import expression_text
from hybrid.model import Automaton

__all__ = ["live_subgraph", "location_graph", "product_graph"]


def location_graph(automaton: Automaton, facts: AutomatonFacts | None = None) -> nx.MultiDiGraph:
    """The location graph of ``automaton``, every edge included (dead ones with ``live=False``).

    Parameters
    ----------
    automaton
        The automaton.
    facts
        Its static facts, if already computed (they decide ``live``).
    """
    facts = facts or AutomatonFacts(automaton)
    graph = nx.MultiDiGraph(
        name=automaton.name,
        initial=automaton.initial_location,
        initials=automaton.initial_locations,
        file=automaton.file,
    )
    for name, loc in automaton.locations.items():
        graph.add_node(
            name,
            invariant=loc.invariant_source,
            position=loc.position,
            initial=name in automaton.initial_locations,
            urgent=loc.urgent,
        )
    for edge, ef in zip(automaton.edges, facts.edges, strict=True):
        graph.add_edge(
            edge.source,
            edge.target,
            key=edge.name,
            name=edge.name,
            label=edge.label,
            guard=edge.guard_source,
            reset={k: expression_text(v) for k, v in edge.reset.items()},
            priority=edge.priority,
            index=edge.index,
            position=edge.position,
            live=ef.live,
        )
    live = live_subgraph(graph)
    reachable = set(automaton.initial_locations).union(
        *(nx.descendants(live, start) for start in automaton.initial_locations)
    )
    nx.set_node_attributes(graph, {n: n in reachable for n in graph.nodes}, "reachable")
    return graph


def live_subgraph(graph: nx.MultiDiGraph) -> nx.MultiDiGraph:
    """A view of ``graph`` keeping only the edges whose guard can hold."""
    return nx.subgraph_view(graph, filter_edge=lambda u, v, k: graph.edges[u, v, k]["live"])


def product_graph(tables: ProductTables, max_states: int = 10_000) -> nx.MultiDiGraph:
    """The reachable product as a :class:`networkx.MultiDiGraph` (live transitions only).

    Nodes are the modes the explorer (:func:`hybrid.analysis.explore.explore`)
    reaches, named ``comp.loc|comp.loc``, with an ``initial`` attribute; edges are keyed by transition name and carry
    ``label``, ``guard``, ``reset``, ``priority`` and ``parts`` (the
    component edges). Exploration stops after ``max_states`` modes; the graph's
    ``complete`` attribute says whether it did.
    """
    exploration = explore(tables, max_states)
    graph = nx.MultiDiGraph(name=tables.system.name, complete=exploration.complete)
    modes = list(exploration.modes())
    for mode in modes:
        urgent = any(
            c.facts.automaton.locations[c.locations[k]].urgent
            for c, k in zip(tables.components, mode, strict=True)
        )
        graph.add_node(tables.name(mode), initial=mode in tables.initials, urgent=urgent)
    for mode in modes:
        src = tables.name(mode)
        for tr in tables.successors(mode):
            if tables.name(tr.target) in graph:
                _add_transition(graph, tables, src, tr)
    return graph


def _add_transition(
    graph: nx.MultiDiGraph, tables: ProductTables, src: str, tr: Transition
) -> None:
    edges = [tables.components[i].facts.automaton.edges[e] for i, e in tr.parts]
    guards = [e.guard_source for e in edges if e.guard_source.strip() != "true"]
    reset: dict[str, str] = {}
    for e in edges:
        reset.update({k: expression_text(v) for k, v in e.reset.items()})
    name = tables.transition_name(tr)
    graph.add_edge(
        src,
        tables.name(tr.target),
        key=name,
        name=name,
        label=tr.label,
        guard=" and ".join(f"({g})" if len(guards) > 1 else g for g in guards) or "true",
        reset=reset,
        priority=max(e.priority for e in edges),
        parts=tuple(tables.edge_name(i, e) for i, e in tr.parts),
        position=edges[0].position,
        live=True,
    )
