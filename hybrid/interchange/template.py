"""A SpaceEx base component as one of our automata: states, inputs, locations, edges.

What each variable becomes:

- a real variable with ``dynamics="const"``: a parameter (its value set per
  instance by the system file);
- a real variable whose derivative a flow gives, or that an assignment sets:
  a state variable; every location must give its derivative (SpaceEx lets a
  variable with no derivative in a location change arbitrarily there, which
  has no counterpart: refused with what to do);
- any other real variable: an input. If the system leaves it free and every
  location's invariant bounds it by numbers (``-0.1 <= w & w <= 0.1``), those
  bounds become the input's ``range`` and leave the invariant;
- a label: a label.

A transition's guard is SpaceEx's guard *and* the target location's invariant
after the assignment (SpaceEx takes a transition only if the target's
invariant holds after the jump). A conjunct of the target's invariant that the
source's invariant also has, over variables the jump leaves alone, already
holds and is not repeated; one that the guard already has is not repeated.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

from hybrid.errors import Position, SpecError
from hybrid.expr.printer import expression_text
from hybrid.interchange import sxexpr as sx
from hybrid.interchange.inputs import input_ranges
from hybrid.interchange.naming import component_name, location_names, ours
from hybrid.interchange.outputs import outputs, read_names, reads, unused
from hybrid.interchange.rectangular import flow_parts, rate_inputs
from hybrid.interchange.safexml import SourceText
from hybrid.interchange.sxmodel import Component
from hybrid.interchange.translate import (
    Rename,
    changed_by,
    condition_ir,
    constant_value,
    flows,
    reset_nodes,
    resets,
    substitute,
)

__all__ = ["EdgeInfo", "LocationInfo", "Template", "analyse"]


@dataclass
class LocationInfo:
    id: str
    name: str
    spaceex_name: str
    flow: dict[str, str]
    invariant: list[sx.Node]
    invariant_text: str
    removed: list[str] = field(default_factory=list)
    urgent: bool = False


@dataclass
class EdgeInfo:
    source: str
    target: str
    label: str | None
    guard: str
    reset: dict[str, str]
    comment: str
    checked_after: frozenset[str] = frozenset()
    """SpaceEx variables the guard reads for the target's invariant after the jump (their
    values before it: the jump of this component leaves them alone)."""


@dataclass
class Template:
    """A base component read as one of our automata (names are ours)."""

    component: Component
    name: str
    names: dict[str, str]
    states: list[str]
    inputs: list[str]
    constants: list[str]
    labels: list[str]
    locations: list[LocationInfo]
    edges: list[EdgeInfo]
    ranges: dict[str, tuple[float, float]]
    notes: list[str]
    signals: dict[str, dict[str, str]] = field(default_factory=dict)
    """Output variable -> {our location name: its definition} (see :mod:`.outputs`)."""
    dropped: list[str] = field(default_factory=list)
    """Inputs nothing reads, left out."""
    rates: dict[str, str] = field(default_factory=dict)
    """Input standing for a rectangular rate -> the variable whose rate it is."""
    origins: dict[tuple[str | int, ...], Position] = field(default_factory=dict)
    """YAML path of the automaton file -> the SpaceEx position it comes from."""

    @property
    def file(self) -> str:
        return f"{self.name}.yaml"

    def location(self, spaceex_name: str) -> LocationInfo | None:
        return next((loc for loc in self.locations if loc.spaceex_name == spaceex_name), None)


def _rename(names: dict[str, str], comp: Component) -> Rename:
    def rename(name: str) -> str:
        if name in names:
            return names[name]
        raise KeyError(
            f"'{name}' is not a parameter of component '{comp.id}' (declare it with <param>)"
        )

    return rename


def analyse(
    comp: Component,
    free: set[str],
    values: Mapping[str, float] | None = None,
    promoted: frozenset[str] = frozenset(),
) -> Template:
    """Read base component ``comp``; ``free`` holds its variables the system leaves free.

    ``values`` are the constants' values every instance agrees on (bounds
    written with constants use them); ``promoted`` are constants the ``.cfg``
    gives a range: state variables with derivative 0 (the SpaceEx meaning).

    Raises
    ------
    SpecError
        At the first construct with no counterpart, with what to do.
    """
    notes: list[str] = []
    reals = [p.name for p in comp.params.values() if p.kind == "real"]
    names = {n: ours(n, comp.params) for n in comp.params}
    for old, new in names.items():
        if old != new:
            notes.append(
                f"component '{comp.id}': variable '{old}' is renamed '{new}' ('{old}' is "
                f"reserved in our expressions{'; t is the time' if old == 't' else ''})"
            )
    rename = _rename(names, comp)
    values = dict(values or {})
    constants = [n for n in reals if comp.params[n].dynamics == "const" and n not in promoted]
    labels = [p.name for p in comp.params.values() if p.kind == "label"]
    loc_names = location_names([(loc.id, loc.name) for loc in comp.locations])
    parsed_flows: dict[str, dict[str, str]] = {}
    urgent: set[str] = set()
    rates: dict[str, dict[str, tuple[float, float]]] = {}
    for loc in comp.locations:
        parts = flow_parts(sx.parse(loc.flow), values)
        parsed_flows[loc.id] = flows(sx.And(tuple(parts.equations), loc.position), rename)
        if parts.urgent:
            urgent.add(loc.id)
        rates[loc.id] = parts.rates
        for var in [*parsed_flows[loc.id], *parts.rates]:
            _check_variable(comp, var, loc.flow.where(0), constants)
        for var in promoted:
            parsed_flows[loc.id].setdefault(var, "0")
    rated = rate_inputs(comp, rates, parsed_flows, names, notes)
    for loc in comp.locations:
        if loc.id in urgent:
            notes.append(
                f"component '{comp.id}': location '{loc.name}' has the flow false (no time may "
                "pass there): it is urgent"
            )
    for var in sorted(promoted):
        notes.append(
            f"component '{comp.id}': constant '{var}' is given a range in the .cfg: it is a "
            f"state variable with {names[var]}' = 0 that starts anywhere in that range"
        )
    parsed_resets: list[dict[str, str]] = []
    single: list[sx.Node] = []
    for tr in comp.transitions:
        parsed = resets(sx.parse(tr.assignment), rename, single)
        for var in parsed:
            _check_variable(comp, var, tr.assignment.where(0), constants)
        parsed_resets.append(parsed)
        if tr.label is not None and tr.label not in labels:
            raise SpecError(
                f"label '{tr.label}' is not declared: add <param name=\"{tr.label}\" "
                'type="label"/> to the component',
                tr.label_position,
            )
    if single:
        first = single[0].position
        others = f" (and {len(single) - 1} more)" if len(single) > 1 else ""
        notes.append(
            f"component '{comp.id}': the assignment at line {first.line}, column {first.column}"
            f"{others} is written x = e: it is read as the reset x := e, as SpaceEx, PHAVer "
            "and HyST read it"
        )
    driven = {v for f in parsed_flows.values() for v in f} | {v for r in parsed_resets for v in r}
    states = [n for n in reals if n in driven]
    inputs = [n for n in reals if n not in driven and n not in constants]
    for loc in comp.locations:
        if loc.id in urgent:
            continue
        missing = [v for v in states if v not in parsed_flows[loc.id]]
        if missing:
            raise SpecError(
                f"location '{loc.name}' gives no derivative for '{missing[0]}': SpaceEx then lets "
                f"it change arbitrarily while here, which has no counterpart; write "
                f"{missing[0]}' == 0 in this flow if it stays constant",
                loc.flow.where(0) if loc.flow.text.strip() else loc.position,
            )
    locations = [
        _location(loc.id, loc_names[loc.id], loc.name, parsed_flows[loc.id], loc.invariant)
        for loc in comp.locations
    ]
    for info in locations:
        info.urgent = info.id in urgent
    candidates = [i for i in inputs if i in free and comp.params[i].controlled is not False]
    origins: dict[tuple[str | int, ...], Position] = {(): comp.position}
    signals = outputs(comp, candidates, locations, rename, notes, origins)
    inputs = [i for i in inputs if i not in signals]
    ranges = input_ranges(comp, [i for i in inputs if i in free], locations, notes, values)
    inputs += list(rated)
    ranges.update({name: bounds for name, (_, bounds) in rated.items()})
    edges = [
        _edge(comp, i, locations, rename, parsed_resets[i]) for i in range(len(comp.transitions))
    ]
    for tr, edge in zip(comp.transitions, edges, strict=True):
        if edge.source == edge.target and not edge.reset and tr.label is None:
            notes.append(
                f"component '{comp.id}': the transition {edge.source} -> {edge.target} at line "
                f"{tr.position.line} assigns nothing: ours fire as soon as possible, so while "
                "its guard holds it fires again at once, without time passing (hybrid check "
                "reports the zero-time cycle; SpaceEx may also not take it)"
            )
    read = read_names(locations, edges, signals, names)
    dropped, idle = unused(comp, inputs, constants, read, names, notes)
    inputs = [i for i in inputs if i not in dropped]
    constants = [c for c in constants if c not in idle]
    if component_name(comp.id) != comp.id:
        notes.append(
            f"component id '{comp.id}' is not one of our names: it is "
            f"'{component_name(comp.id)}' here"
        )
    return Template(
        comp,
        component_name(comp.id),
        names,
        states,
        inputs,
        constants,
        labels,
        locations,
        edges,
        ranges,
        notes,
        signals,
        dropped,
        {name: var for name, (var, _) in rated.items()},
        _origins(comp, names, locations, origins),
    )


def _origins(
    comp: Component,
    names: dict[str, str],
    locations: list[LocationInfo],
    origins: dict[tuple[str | int, ...], Position],
) -> dict[tuple[str | int, ...], Position]:
    """Where each part of the automaton file comes from (see :mod:`.selfcheck`)."""
    for name, param in comp.params.items():
        for section in ("state", "inputs", "parameters", "labels"):
            origins[(section, names[name])] = param.position
    by_id = {loc.id: loc for loc in comp.locations}
    for info in locations:
        loc = by_id[info.id]
        origins[("locations", info.name)] = loc.position
        origins[("locations", info.name, "flow")] = loc.flow.where(0)
        origins[("locations", info.name, "invariant")] = loc.invariant.where(0)
    for i, tr in enumerate(comp.transitions):
        origins[("edges", i)] = tr.position
        origins[("edges", i, "guard")] = tr.guard.where(0) if tr.guard.text.strip() else tr.position
        origins[("edges", i, "reset")] = tr.assignment.where(0)
    return origins


def _check_variable(comp: Component, var: str, where: Position, constants: list[str]) -> None:
    param = comp.params.get(var)
    if param is None or param.kind != "real":
        raise SpecError(
            f"'{var}' is not a real variable of component '{comp.id}' (declare it with <param>)",
            where,
        )
    if var in constants:
        raise SpecError(f"'{var}' is a constant (dynamics=\"const\"): it cannot change", where)


def _location(
    lid: str, name: str, spaceex_name: str, flow: dict[str, str], invariant: SourceText
) -> LocationInfo:
    items = sx.conjuncts(sx.parse(invariant))
    return LocationInfo(lid, name, spaceex_name, flow, items, invariant.text.strip())


def _edge(
    comp: Component,
    index: int,
    locations: list[LocationInfo],
    rename: Rename,
    reset: dict[str, str],
) -> EdgeInfo:
    tr = comp.transitions[index]
    by_id = {loc.id: loc for loc in locations}
    source, target = by_id[tr.source], by_id[tr.target]
    guard_node = sx.parse(tr.guard)
    guard_items = sx.conjuncts(guard_node)
    values = reset_nodes(sx.parse(tr.assignment))
    changed = changed_by(values)

    def text(node: sx.Node) -> str:
        return expression_text(condition_ir(node, rename))

    guard_texts = {text(g) for g in guard_items}
    source_texts = {text(c) for c in source.invariant}
    added: list[sx.Node] = []
    implied: list[str] = []
    repeated: list[str] = []
    implied_by_reset: list[str] = []
    for c in target.invariant:
        after = substitute(c, values)
        after_text = text(after)
        known = _constant_truth(after) if isinstance(after, sx.Cmp) else None
        if text(c) in source_texts and not (reads(c, primed=True) & changed):
            implied.append(after_text)
        elif known is True:
            implied_by_reset.append(after_text)
        elif after_text in guard_texts or after_text in {text(a) for a in added}:
            repeated.append(after_text)
        else:
            added.append(after)
    items = [*guard_items, *added]
    guard = text(sx.And(tuple(items), tr.position)) if items else "true"
    comment = f"SpaceEx guard: {tr.guard.text.strip() or 'true'}"
    if added:
        comment += f"; and {target.name}'s invariant after the jump: " + " and ".join(
            text(a) for a in added
        )
    if implied:
        comment += f"; {' and '.join(implied)} (of {target.name}'s invariant) holds already: "
        comment += f"{source.name}'s invariant has it and the jump keeps its variables"
    if implied_by_reset:
        comment += f"; {' and '.join(implied_by_reset)} (of {target.name}'s invariant after the jump) holds"
    if repeated:
        comment += f"; {' and '.join(repeated)} (of {target.name}'s invariant) is in the guard"
    checked_after = frozenset(v for a in added for v in reads(a))
    return EdgeInfo(source.name, target.name, tr.label, guard, reset, comment, checked_after)


def _constant_truth(node: sx.Cmp) -> bool | None:
    """Whether a comparison of numbers holds (``None`` if it has variables)."""
    values = [constant_value(o, {}) for o in node.operands]
    if any(v is None for v in values):
        return None
    checks = {"<": float.__lt__, "<=": float.__le__, ">": float.__gt__, ">=": float.__ge__}
    for op, a, b in zip(node.ops, values, values[1:], strict=False):
        assert a is not None and b is not None
        holds = checks[op](a, b) if op in checks else (a == b) == (op == "==")
        if not holds:
            return False
    return True
