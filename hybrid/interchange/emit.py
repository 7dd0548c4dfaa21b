"""The automaton file of one SpaceEx base component, as YAML text with comments.

The file says, in comments, what was translated and how: the SpaceEx guard of
each edge and the target invariant added to it, input ranges taken out of
invariants, renamed variables, and the semantics the translation keeps.
"""

from __future__ import annotations

from typing import Any

from hybrid.interchange import sxexpr as sx
from hybrid.interchange.flatten import Leaf
from hybrid.interchange.template import Template
from hybrid.interchange.translate import condition_text
from hybrid.interchange.yamltext import dump

__all__ = ["SEMANTICS", "automaton_text"]

Path_ = tuple[str | int, ...]

SEMANTICS = """\
SpaceEx semantics, and how they are kept here:
- a SpaceEx transition MAY fire whenever its guard holds and the target's invariant
  holds after the jump; ours fire as soon as possible. Each guard below is SpaceEx's
  guard and the target's invariant after the jump, so every run of this spec is a
  run SpaceEx allows (the one that jumps at the first chance); SpaceEx allows more.
- no urgency, no priorities in SpaceEx: all edges have priority 0.
- a variable no location gives a derivative for, and no jump sets, is an input."""


def _state_entry(value: Any) -> dict[str, Any]:
    """``{initial: ...}`` (and ``nominal``) of a state variable from a start value."""
    if isinstance(value, dict):
        return dict(value)
    return {"initial": value}


CHECKS_COMMENT = "time-horizon and iter-max of the .cfg: the horizon and jump bound of reach"


def automaton_text(
    t: Template,
    leaf: Leaf,
    start: dict[str, Any] | None,
    forbidden: list[dict[str, Any]],
    source: str,
    *,
    top: bool,
    checks: dict[str, Any] | None = None,
) -> str:
    """YAML of ``t``; ``start`` (the initial set), ``forbidden`` and ``checks`` (the spec's
    ``checks:``) for a top-level automaton."""
    comp = t.component
    data: dict[str, Any] = {"automaton": t.name}
    data["description"] = comp.note or f"SpaceEx base component '{comp.id}'"
    comments: dict[Path_, str] = {}
    if t.constants:
        data["parameters"] = {
            t.names[c]: (leaf.constants.get(c) if leaf.constants.get(c) is not None else 0.0)
            for c in t.constants
        }
        if not top:
            comments[("parameters",)] = "values of the first instance; the system file sets each"
    state: dict[str, Any] = {}
    start_state = start["state"] if start else {}
    for s in t.states:
        ours = t.names[s]
        state[ours] = _state_entry(start_state.get(ours, 0.0))
    if state:
        data["state"] = state
        if start and start.get("exact_comment"):
            comments[("state",)] = start["exact_comment"]
        if not top:
            comments[("state",)] = "initial values: set per instance by the system file"
    if t.signals:
        data["signals"] = {t.names[y]: next(iter(d.values())) for y, d in t.signals.items()}
        comments[("signals",)] = (
            "outputs: variables every location's invariant defines by an equation y == e"
        )
    inputs = [t.names[i] for i in t.inputs]
    if inputs:
        if t.ranges:
            data["inputs"] = {
                t.names[i]: ({"range": list(t.ranges[i])} if i in t.ranges else {})
                for i in t.inputs
            }
            comments[("inputs",)] = (
                "ranges: the bounds every location's invariant put on these free variables"
            )
        else:
            data["inputs"] = inputs
            comments[("inputs",)] = "variables this component reads and never changes"
    if t.labels:
        data["labels"] = [t.names[lab] for lab in t.labels]
    locations: dict[str, Any] = {}
    for loc in t.locations:
        entry: dict[str, Any] = {}
        if loc.urgent:
            entry["urgent"] = True
        if loc.flow:
            entry["flow"] = {t.names[k]: v for k, v in loc.flow.items()}
        own = {
            t.names[y]: d[loc.name]
            for y, d in t.signals.items()
            if d[loc.name] != data["signals"][t.names[y]]
        }
        if own:
            entry["signals"] = own
        if loc.invariant:
            entry["invariant"] = condition_text(
                sx.And(tuple(loc.invariant), comp.position), t.names.__getitem__
            )
        locations[loc.name] = entry
        remarks = []
        if loc.name != loc.spaceex_name:
            remarks.append(f"SpaceEx location '{loc.spaceex_name}' (id {loc.id})")
        if loc.urgent:
            remarks.append("SpaceEx flow: false (no time may pass here)")
        if loc.removed:
            remarks.append(
                f"SpaceEx invariant: {loc.invariant_text}; taken out: {', '.join(dict.fromkeys(loc.removed))}"
            )
        if remarks:
            comments[("locations", loc.name)] = "\n".join(remarks)
    data["locations"] = locations
    if start is not None:
        data["initial"] = {"location": start["location"]}
        if isinstance(start["location"], list):
            comments[("initial",)] = start.get(
                "locations_comment",
                "every location whose invariant the initial set can meet (SpaceEx starts in all)",
            )
    edges = []
    for i, edge in enumerate(t.edges):
        item: dict[str, Any] = {"from": edge.source, "to": edge.target}
        if edge.label is not None:
            item["label"] = t.names[edge.label]
        item["guard"] = edge.guard
        if edge.reset:
            item["reset"] = {t.names[k]: v for k, v in edge.reset.items()}
        edges.append(item)
        comments[("edges", i)] = edge.comment
    if edges:
        data["edges"] = edges
    if forbidden:
        data["properties"] = {"forbidden": forbidden}
        if start and start.get("forbidden_comment"):
            comments[("properties",)] = start["forbidden_comment"]
    if checks:
        data["checks"] = checks
        comments[("checks",)] = CHECKS_COMMENT
    header = (
        f"Imported by `hybrid import spaceex`. {source}, base component '{comp.id}'.\n"
        + "".join(f"{note}\n" for note in t.notes)
        + SEMANTICS
    )
    return dump(data, comments, header)
