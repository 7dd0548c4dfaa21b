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

import math

import networkx as nx

from hybrid.analysis.static import AutomatonFacts
from hybrid.expr import ir
from hybrid.model import Automaton

__all__ = ["expression_text", "live_subgraph", "location_graph"]

_PREC = {"or": 1, "and": 2, "not": 3, "cmp": 4, "+": 5, "-": 5, "*": 6, "/": 6, "neg": 7, "**": 8}


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


def expression_text(node: ir.Expr) -> str:
    """An expression as a user would write it.

    Examples
    --------
    >>> from hybrid.expr.parse import Scope, parse_expression
    >>> expression_text(parse_expression("-e*v + max(0, v)**2", Scope({"e": "param", "v": "state"})))
    '-e * v + max(0, v) ** 2'
    """
    return _emit(node)[0]


def _number(value: float) -> str:
    if math.isfinite(value) and value == int(value) and abs(value) < 1e15:
        return str(int(value))
    return repr(value)


def _wrap(node: ir.Expr, min_prec: int) -> str:
    text, prec = _emit(node)
    return f"({text})" if prec < min_prec else text


def _emit(node: ir.Expr) -> tuple[str, int]:
    if isinstance(node, ir.Num):
        text = _number(node.value)
        return (text, 9) if not text.startswith("-") else (text, _PREC["neg"])
    if isinstance(node, ir.BoolConst):
        return ("true" if node.value else "false"), 9
    if isinstance(node, ir.Var):
        return node.name, 9
    if isinstance(node, ir.Index):
        return f"{node.name}[{node.index}]", 9
    if isinstance(node, ir.Call):
        return f"{node.func}({', '.join(_emit(a)[0] for a in node.args)})", 9
    if isinstance(node, ir.Unary):
        return f"-{_wrap(node.operand, _PREC['neg'] + 1)}", _PREC["neg"]
    if isinstance(node, ir.Bin):
        p = _PREC[node.op]
        if node.op == "**":  # right-associative
            return f"{_wrap(node.left, p + 1)} ** {_wrap(node.right, p)}", p
        return f"{_wrap(node.left, p)} {node.op} {_wrap(node.right, p + 1)}", p
    if isinstance(node, ir.Cmp):
        parts = [_wrap(node.operands[0], _PREC["cmp"] + 1)]
        for op, operand in zip(node.ops, node.operands[1:], strict=True):
            parts.append(f"{op} {_wrap(operand, _PREC['cmp'] + 1)}")
        return " ".join(parts), _PREC["cmp"]
    if isinstance(node, ir.BoolOp):
        p = _PREC[node.op]
        return f" {node.op} ".join(_wrap(v, p + 1) for v in node.values), p
    return f"not {_wrap(node.operand, _PREC['not'])}", _PREC["not"]
