"""``check`` and ``system_graph``: the analysis as the API and the command line call it.

Examples
--------
>>> import hybrid
>>> report = check(hybrid.load("specs/bouncing_ball.yaml"))
>>> report.ok, report.findings
(True, ())
"""

from __future__ import annotations

import networkx as nx

from hybrid.allocation import gc_paused
from hybrid.analysis.checks import run_checks
from hybrid.analysis.context import analyse
from hybrid.analysis.explore import DEFAULT_MAX_STATES
from hybrid.analysis.findings import Report
from hybrid.analysis.graph import location_graph, product_graph
from hybrid.analysis.product import ProductTables
from hybrid.compose import System
from hybrid.model import Automaton

__all__ = ["check", "system_graph"]


def check(model: Automaton | System, *, max_states: int = DEFAULT_MAX_STATES) -> Report:
    """Run every check on ``model``; the report is ``ok`` when no finding is an error.

    Parameters
    ----------
    model
        An automaton or a system, as :func:`hybrid.load` returns it.
    max_states
        Stop exploring the product of a system after this many modes (a note says so).

    Examples
    --------
    >>> import hybrid
    >>> m = hybrid.load_text('''
    ... automaton: a
    ... state: {x: {bounds: [0, 1]}}
    ... locations: {l: {}, m: {}}
    ... edges: [{from: l, to: m, guard: x > 2}]
    ... ''')
    >>> [f.rule for f in check(m).findings]
    ['unreachable-location', 'dead-edge']
    """
    with gc_paused():  # many small acyclic objects: the collector only costs time here
        analysis = analyse(model, max_states=max_states)
        return Report(tuple(run_checks(analysis)), analysis.system.name, analysis.system.file)


def system_graph(model: Automaton | System, *, max_states: int = 10_000) -> nx.MultiDiGraph:
    """The graph `hybrid graph` draws: the location graph, or the reachable product of a system."""
    if isinstance(model, Automaton):
        return location_graph(model)
    return product_graph(ProductTables(model), max_states=max_states)
