"""Guard-aware reachability: bounds prune an edge that plain graph reachability follows."""

from __future__ import annotations

import networkx as nx

import hybrid
from hybrid.analysis import analyse, check, location_graph
from hybrid.analysis.graph import live_subgraph

GATE = """
automaton: gate
state: {{x: {{initial: 0, bounds: [0, {upper}]}}}}
locations:
  closed: {{flow: {{x: 1}}, invariant: x <= {upper}}}
  open: {{}}
initial: {{location: closed}}
edges:
  - {{name: wrap, from: closed, to: closed, guard: x >= {upper}, reset: {{x: 0}}}}
  - {{name: opening, from: closed, to: open, guard: x >= 8, priority: 1}}
properties: {{{prop}: [open]}}
"""


def load(upper: float, prop: str = "reachable") -> hybrid.Automaton:
    model = hybrid.load_text(GATE.format(upper=upper, prop=prop), file="gate.yaml")
    assert isinstance(model, hybrid.Automaton)
    return model


def test_plain_graph_reachability_would_follow_the_edge():
    graph = location_graph(load(5))
    assert nx.has_path(graph, "closed", "open")
    assert not nx.has_path(live_subgraph(graph), "closed", "open")
    assert graph.edges["closed", "open", "opening"]["live"] is False
    assert graph.nodes["open"]["reachable"] is False


def test_narrow_bounds_prune_the_edge_and_the_location_behind_it():
    report = check(load(5, prop="unreachable"))
    found = {(f.rule, f.where) for f in report.findings}
    assert ("dead-edge", "opening") in found
    assert report.ok  # declared unreachable, and it is: no unreachable-location warning either
    assert not any(f.rule == "unreachable-location" for f in report.findings)

    report = check(load(5, prop="reachable"))
    (violation,) = report.by_rule("property-disproved")
    assert violation.where == "reachable: open" and violation.severity == "error"
    assert "'opening'" in violation.message
    assert not report.ok


def test_without_properties_the_location_is_reported_unreachable():
    model = hybrid.load_text(GATE.format(upper=5, prop="reachable").split("properties")[0])
    report = check(model)
    assert {(f.rule, f.where) for f in report.findings} == {
        ("dead-edge", "opening"),
        ("unreachable-location", "open"),
    }
    (unreachable,) = report.by_rule("unreachable-location")
    assert "x >= 8" not in unreachable.message and "'opening'" in unreachable.message


def test_wider_bounds_make_it_reachable_with_a_witness():
    report = check(load(10, prop="reachable"))
    assert report.ok and report.findings == ()

    analysis = analyse(load(10))
    assert analysis.witness_to("open") == ((None, "closed"), ("opening", "open"))

    report = check(load(10, prop="unreachable"))
    # not proved, with the candidate path (the analysis does not simulate it)
    (violation,) = report.by_rule("property-unproved")
    assert violation.severity == "warning"
    assert violation.witness == ((None, "closed"), ("opening", "open"))
    assert "closed -[opening]-> open" in violation.message


def test_witness_to_an_unreachable_location_is_none():
    assert analyse(load(5)).witness_to("open") is None
