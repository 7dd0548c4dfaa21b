"""``check`` and ``system_graph``: the analysis as the API and the command line call it.

Examples
--------
>>> import hybrid
>>> report = check(hybrid.load("specs/bouncing_ball.yaml"))
>>> report.ok, report.findings
(True, ())
"""

from __future__ import annotations

from collections.abc import Iterable

import networkx as nx

from hybrid.allocation import gc_paused
from hybrid.analysis.checks import run_checks
from hybrid.analysis.context import analyse
from hybrid.analysis.explore import DEFAULT_MAX_BYTES, DEFAULT_MAX_STATES, Progress
from hybrid.analysis.findings import Report
from hybrid.analysis.graph import location_graph, product_graph
from hybrid.analysis.ignore import silenced
from hybrid.analysis.product import ProductTables
from hybrid.compose import System
from hybrid.model import Automaton

__all__ = ["check", "system_graph"]


def check(
    model: Automaton | System,
    *,
    max_states: int = DEFAULT_MAX_STATES,
    max_bytes: int = DEFAULT_MAX_BYTES,
    ignore: Iterable[str] = (),
    progress: Progress | None = None,
) -> Report:
    """Run every check on ``model``; the report is ``ok`` when no finding is an error.

    Parameters
    ----------
    model
        An automaton or a system, as :func:`hybrid.load` returns it.
    max_states
        Stop exploring the product of a group of interacting components after
        this many modes (a note says so).
    max_bytes
        Stop exploring earlier when the modes kept would take more memory than this.
    ignore
        Rule ids not to report (on top of the ``checks: {ignore: [...]}`` of the
        spec files, which apply to the findings placed in them).
    progress
        Called as ``progress(modes, frontier)`` while exploring a large product.

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
        analysis = analyse(model, max_states=max_states, max_bytes=max_bytes, progress=progress)
        findings = silenced(run_checks(analysis), analysis.system, ignore)
        return Report(tuple(findings), analysis.system.name, analysis.system.file)


def system_graph(model: Automaton | System, *, max_states: int = 10_000) -> nx.MultiDiGraph:
    """The graph `hybrid graph` draws: the location graph, or the reachable product of a system."""
    if isinstance(model, Automaton):
        return location_graph(model)
    return product_graph(ProductTables(model), max_states=max_states)
