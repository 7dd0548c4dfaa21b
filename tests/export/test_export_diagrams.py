"""`hybrid graph`: DOT read back by pydot, Mermaid checked for stateDiagram-v2 structure."""

from __future__ import annotations

import re
from collections import Counter

import pydot
import pytest

import hybrid
from hybrid.analysis import location_graph, product_graph
from hybrid.analysis.product import ProductTables
from hybrid.export.diagrams import edge_text, mermaid_escape, to_dot, to_mermaid

# pydot's parser uses pyparsing names that newer pyparsing deprecates
pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")

# guards and resets full of characters both languages treat specially
TRICKY = """
automaton: tricky
parameters: {k: 2.0}
state: {x: {initial: 0, bounds: [0, 10]}, y: {bounds: [-5, 5]}}
labels: [go]
locations:
  start: {flow: {x: 1}, invariant: "x <= 4 or y > 3"}
  "next": {flow: {x: -1}}
  sink_: {}
edges:
  - {name: e1, from: start, to: "next", label: go, guard: "x >= 2 and (y < 1 or y != 0)", reset: {x: "-k*x", y: "max(x, y)"}}
  - {name: e2, from: "next", to: start, guard: "x <= 0.5", priority: 2}
  - {name: e3, from: start, to: start, guard: "x >= 4", reset: {x: 0}}
  - {name: never, from: "next", to: sink_, guard: "x > 11"}
"""


def graphs():
    tricky = hybrid.load_text(TRICKY)
    yield "tricky", location_graph(tricky)
    yield "thermostat", location_graph(hybrid.load("specs/thermostat.yaml"))
    yield "ball", location_graph(hybrid.load("specs/bouncing_ball.yaml"))
    a = hybrid.load_text(
        "automaton: a\nlabels: [s]\nlocations: {p: {}, q: {}}\n"
        "edges: [{from: p, to: q, label: s}, {from: q, to: p}]\n"
    )
    b = hybrid.load_text(
        "automaton: b\nlabels: [s]\nlocations: {u: {}, v: {}}\n"
        "edges: [{from: u, to: v, label: s}, {from: v, to: u}]\n"
    )
    yield "product", product_graph(ProductTables(hybrid.compose(a, b)))


@pytest.mark.parametrize(
    ("name", "graph"), list(graphs()), ids=lambda v: v if isinstance(v, str) else ""
)
def test_dot_reads_back_with_the_same_nodes_and_edges(name, graph):
    (parsed,) = pydot.graph_from_dot_data(to_dot(graph))
    nodes = {n.get_name().strip('"') for n in parsed.get_nodes()} - {"node", "edge", "graph"}
    assert nodes == set(graph.nodes) | {"__start__"}
    edges = Counter(
        (e.get_source().strip('"'), e.get_destination().strip('"'))
        for e in parsed.get_edges()
        if e.get_source().strip('"') != "__start__"
    )
    assert edges == Counter((u, v) for u, v in graph.edges())
    starts = [
        e.get_destination().strip('"')
        for e in parsed.get_edges()
        if e.get_source().strip('"') == "__start__"
    ]
    assert starts == [n for n, d in graph.nodes(data=True) if d.get("initial")]
    # labels survive escaping: the first line of each edge label is the edge name
    names = Counter(
        e.get_label().strip('"').split("\\n")[0].split(" (")[0]
        for e in parsed.get_edges()
        if e.get_label()
    )
    assert names == Counter(d["name"] for _, _, d in graph.edges(data=True))


def test_dot_escapes_quotes_and_backslashes():
    graph = location_graph(hybrid.load_text(TRICKY))
    text = to_dot(graph)
    (parsed,) = pydot.graph_from_dot_data(text)
    labels = [e.get_label() for e in parsed.get_edges() if e.get_label()]
    assert any("x >= 2 and (y < 1 or y != 0)" in label for label in labels)
    dead = [e for e in parsed.get_edges() if "never" in (e.get_label() or "")]
    assert dead and dead[0].get_style() == "dashed"


_STATE = re.compile(r'^    state "([^"]*)" as (s\d+)$')
_DESCRIPTION = re.compile(r"^    (s\d+) : (.+)$")
_TRANSITION = re.compile(r"^    (\[\*\]|s\d+) --> (s\d+)(?: : (.+))?$")


def _parse_mermaid(text: str):
    lines = text.splitlines()
    assert lines[0] == "stateDiagram-v2"
    states, transitions = {}, []
    for line in lines[1:]:
        if line == "    direction LR":
            continue
        if m := _STATE.match(line):
            states[m.group(2)] = m.group(1)
        elif m := _TRANSITION.match(line):
            transitions.append((m.group(1), m.group(2), m.group(3)))
        elif m := _DESCRIPTION.match(line):
            assert m.group(1) in states
        else:
            raise AssertionError(f"not stateDiagram-v2 syntax: {line!r}")
    return states, transitions


@pytest.mark.parametrize(
    ("name", "graph"), list(graphs()), ids=lambda v: v if isinstance(v, str) else ""
)
def test_mermaid_has_every_location_and_edge(name, graph):
    text = to_mermaid(graph)
    states, transitions = _parse_mermaid(text)
    assert {s.replace("#124;", "|") for s in states.values()} == set(graph.nodes)
    ids = {v.replace("#124;", "|"): k for k, v in states.items()}
    got = Counter((src, dst) for src, dst, _ in transitions if src != "[*]")
    assert got == Counter((ids[u], ids[v]) for u, v in graph.edges())
    assert [dst for src, dst, _ in transitions if src == "[*]"] == [
        ids[n] for n, d in graph.nodes(data=True) if d.get("initial")
    ]
    for _, _, label in transitions:
        if label is None:
            continue
        stripped = re.sub(r"#\d+;", "", label)
        assert not set(stripped) & set('<>:;#"{}|%'), label


def test_mermaid_escapes_guards():
    text = to_mermaid(location_graph(hybrid.load_text(TRICKY)))
    assert "x #62;= 2 and (y #60; 1 or y != 0)" in text
    assert "x #58;= -k * x" in text  # the reset arrow's colon is escaped too
    assert "(dead)" in text and "(unreachable)" in text
    assert mermaid_escape('a"b#c') == "a#34;b#35;c"


def test_edge_text_parts():
    assert edge_text({"name": "e", "guard": "true", "live": True}) == ["e"]
    assert edge_text({"name": "e", "label": "e", "priority": 2, "live": False}) == [
        "e",
        "priority 2",
        "(dead)",
    ]
