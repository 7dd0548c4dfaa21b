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

from hybrid.analysis.static import AutomatonFacts
from hybrid.expr.printer import expression_text
from hybrid.model import Automaton

__all__ = ["live_subgraph", "location_graph"]


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
        name=automaton.name, initial=automaton.initial_location, file=automaton.file
    )
    for name, loc in automaton.locations.items():
        graph.add_node(
            name,
            invariant=loc.invariant_source,
            position=loc.position,
            initial=name == automaton.initial_location,
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
    reachable = nx.descendants(live, automaton.initial_location) | {automaton.initial_location}
    nx.set_node_attributes(graph, {n: n in reachable for n in graph.nodes}, "reachable")
    return graph


def live_subgraph(graph: nx.MultiDiGraph) -> nx.MultiDiGraph:
    """A view of ``graph`` keeping only the edges whose guard can hold."""
    return nx.subgraph_view(graph, filter_edge=lambda u, v, k: graph.edges[u, v, k]["live"])
