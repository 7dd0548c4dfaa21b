"""Diagrams of location and product graphs: Graphviz DOT and Mermaid ``stateDiagram-v2``.

Hand-written writers (no pydot or pygraphviz at runtime). They read the
attributes :func:`hybrid.analysis.location_graph` and
:func:`hybrid.analysis.product_graph` set: node ``initial``, ``invariant`` and
``reachable``; edge ``name``, ``label``, ``guard``, ``reset``, ``priority`` and
``live``. Edges that can never fire are dashed (DOT) or marked ``(dead)``
(Mermaid); unreachable locations are dashed and grey.

Examples
--------
>>> import hybrid
>>> from hybrid.analysis import location_graph
>>> g = location_graph(hybrid.load("specs/thermostat.yaml"))
>>> print(to_mermaid(g))
stateDiagram-v2
    direction LR
    state "off" as s0
    s0 : inv T #62;= T_low
    state "on" as s1
    s1 : inv T #60;= T_high
    [*] --> s0
    s0 --> s1 : turn_on (switch_on) / [T #60;= T_low]
    s1 --> s0 : turn_off (switch_off) / [T #62;= T_high]
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import networkx as nx

__all__ = ["DIAGRAM_FORMATS", "edge_text", "mermaid_escape", "to_dot", "to_mermaid"]

_MERMAID = {
    "#": "#35;",
    "<": "#60;",
    ">": "#62;",
    ":": "#58;",
    ";": "#59;",
    '"': "#34;",
    "{": "#123;",
    "}": "#125;",
    "|": "#124;",
    "&": "#38;",
    "%": "#37;",
    "\\": "#92;",
    "\n": " ",
    "\r": " ",
}


def edge_text(data: Mapping[str, Any]) -> list[str]:
    """Parts describing an edge: ``name (label)``, ``[guard]``, resets, priority, ``(dead)``.

    Examples
    --------
    >>> edge_text({"name": "up", "label": "go", "guard": "x > 1", "reset": {"x": "0"}})
    ['up (go)', '[x > 1]', 'x := 0']
    """
    name = str(data.get("name", ""))
    label = data.get("label")
    lines = [f"{name} ({label})" if label and label != name else name]
    guard = str(data.get("guard", "true"))
    if guard.strip() != "true":
        lines.append(f"[{guard}]")
    reset = data.get("reset") or {}
    if reset:
        lines.append(", ".join(f"{k} := {v}" for k, v in reset.items()))
    if data.get("priority"):
        lines.append(f"priority {data['priority']}")
    if data.get("live") is False:
        lines.append("(dead)")
    return lines


def _dot_string(text: str) -> str:
    escaped = text.replace("\\", "\\\\").replace('"', '\\"').replace("\r", "")
    return '"' + escaped.replace("\n", "\\n") + '"'


def to_dot(graph: nx.MultiDiGraph) -> str:
    """Graphviz DOT source of ``graph``.

    Examples
    --------
    >>> import networkx as nx
    >>> g = nx.MultiDiGraph(name="demo")
    >>> g.add_node("a", initial=True)
    >>> _ = g.add_edge("a", "a", key="e", name="e", guard='x < "1"')
    >>> print(to_dot(g))
    digraph "demo" {
      rankdir=LR;
      node [shape=box, style=rounded];
      "__start__" [shape=point, label=""];
      "a";
      "__start__" -> "a";
      "a" -> "a" [label="e\\n[x < \\"1\\"]"];
    }
    """
    out = [
        f"digraph {_dot_string(str(graph.graph.get('name', 'hybrid')))} {{",
        "  rankdir=LR;",
        "  node [shape=box, style=rounded];",
        '  "__start__" [shape=point, label=""];',
    ]
    initial = []
    for node, data in graph.nodes(data=True):
        attrs = []
        inv = data.get("invariant")
        lines = [str(node)]
        if data.get("urgent"):
            lines.append("urgent")
            attrs.append("peripheries=2")
        if inv and str(inv).strip() != "true":
            lines.append(f"inv: {inv}")
        if len(lines) > 1:
            attrs.insert(0, f"label={_dot_string(chr(10).join(lines))}")
        if data.get("reachable") is False:
            attrs.append('style="rounded,dashed"')
            attrs.append("color=gray")
        out.append(f"  {_dot_string(str(node))}" + (f" [{', '.join(attrs)}];" if attrs else ";"))
        if data.get("initial"):
            initial.append(node)
    for node in initial:
        out.append(f'  "__start__" -> {_dot_string(str(node))};')
    for src, dst, data in graph.edges(data=True):
        label = _dot_string("\n".join(edge_text(data)))
        attrs = [f"label={label}"]
        if data.get("live") is False:
            attrs.append("style=dashed")
            attrs.append("color=gray")
        out.append(f"  {_dot_string(str(src))} -> {_dot_string(str(dst))} [{', '.join(attrs)}];")
    out.append("}")
    return "\n".join(out)


def mermaid_escape(text: str) -> str:
    """Text safe inside a Mermaid label: special characters as ``#code;`` entities.

    Examples
    --------
    >>> mermaid_escape("x <= 1: a; b")
    'x #60;= 1#58; a#59; b'
    """
    return "".join(_MERMAID.get(ch, ch) for ch in text)


def to_mermaid(graph: nx.MultiDiGraph) -> str:
    """Mermaid ``stateDiagram-v2`` source of ``graph`` (states get ids ``s0``, ``s1``, ...)."""
    ids = {node: f"s{k}" for k, node in enumerate(graph.nodes)}
    out = ["stateDiagram-v2", "    direction LR"]
    for node, data in graph.nodes(data=True):
        sid = ids[node]
        out.append(f'    state "{mermaid_escape(str(node))}" as {sid}')
        notes = []
        if data.get("urgent"):
            notes.append("urgent")
        inv = data.get("invariant")
        if inv and str(inv).strip() != "true":
            notes.append(f"inv {inv}")
        if data.get("reachable") is False:
            notes.append("(unreachable)")
        if notes:
            out.append(f"    {sid} : {mermaid_escape(' '.join(notes))}")
    for node, data in graph.nodes(data=True):
        if data.get("initial"):
            out.append(f"    [*] --> {ids[node]}")
    for src, dst, data in graph.edges(data=True):
        label = mermaid_escape(" / ".join(edge_text(data)))
        out.append(f"    {ids[src]} --> {ids[dst]} : {label}")
    return "\n".join(out)


DIAGRAM_FORMATS: dict[str, Callable[[nx.MultiDiGraph], str]] = {
    "dot": to_dot,
    "mermaid": to_mermaid,
}
"""The writers of ``hybrid graph --format``."""
