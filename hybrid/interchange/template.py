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

from dataclasses import dataclass, field

from hybrid.errors import Position, SpecError
from hybrid.expr.printer import expression_text
from hybrid.interchange import sxexpr as sx
from hybrid.interchange.naming import location_names, ours
from hybrid.interchange.outputs import identifiers, output_equations
from hybrid.interchange.safexml import SourceText
from hybrid.interchange.sxmodel import Component
from hybrid.interchange.translate import (
    Rename,
    condition_ir,
    condition_text,
    constant_value,
    flows,
    number_text,
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


@dataclass
class EdgeInfo:
    source: str
    target: str
    label: str | None
    guard: str
    reset: dict[str, str]
    comment: str


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


def analyse(comp: Component, free: set[str]) -> Template:
    """Read base component ``comp``; ``free`` holds its variables the system leaves free.

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
    constants = [n for n in reals if comp.params[n].dynamics == "const"]
    labels = [p.name for p in comp.params.values() if p.kind == "label"]
    loc_names = location_names([(loc.id, loc.name) for loc in comp.locations])
    parsed_flows: dict[str, dict[str, str]] = {}
    for loc in comp.locations:
        parsed_flows[loc.id] = flows(sx.parse(loc.flow), rename)
        for var in parsed_flows[loc.id]:
            _check_variable(comp, var, loc.flow.where(0), constants)
    parsed_resets: list[dict[str, str]] = []
    for tr in comp.transitions:
        parsed = resets(sx.parse(tr.assignment), rename)
        for var in parsed:
            _check_variable(comp, var, tr.assignment.where(0), constants)
        parsed_resets.append(parsed)
        if tr.label is not None and tr.label not in labels:
            raise SpecError(
                f"label '{tr.label}' is not declared: add <param name=\"{tr.label}\" "
                'type="label"/> to the component',
                tr.label_position,
            )
    driven = {v for f in parsed_flows.values() for v in f} | {v for r in parsed_resets for v in r}
    states = [n for n in reals if n in driven]
    inputs = [n for n in reals if n not in driven and n not in constants]
    for loc in comp.locations:
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
    signals = _outputs(comp, inputs, locations, rename, notes)
    inputs = [i for i in inputs if i not in signals]
    ranges = _input_ranges(comp, [i for i in inputs if i in free], locations, notes)
    edges = [
        _edge(comp, i, locations, rename, parsed_resets[i]) for i in range(len(comp.transitions))
    ]
    dropped = _unused(comp, inputs, locations, edges, signals, names, notes)
    inputs = [i for i in inputs if i not in dropped]
    return Template(
        comp,
        ours(comp.id),
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
    )


def _outputs(
    comp: Component,
    inputs: list[str],
    locations: list[LocationInfo],
    rename: Rename,
    notes: list[str],
) -> dict[str, dict[str, str]]:
    """The output variables (see :mod:`.outputs`), their equations taken out of the invariants."""
    found = output_equations(inputs, {loc.id: loc.invariant for loc in locations})
    signals: dict[str, dict[str, str]] = {}
    for var, per_location in found.items():
        signals[var] = {}
        for loc in locations:
            item, value = per_location[loc.id]
            loc.invariant = [c for c in loc.invariant if c is not item]
            loc.removed.append(f"the definition of the output {var}")
            signals[var][loc.name] = number_text(value, rename)
        shown = next(iter(signals[var].values()))
        notes.append(
            f"component '{comp.id}': variable '{var}' is an output: every location's invariant "
            f"defines it ({var} == {shown}{', ...' if len(set(signals[var].values())) > 1 else ''}),"
            f" so it is the signal {rename(var)}"
        )
    return signals


def _unused(
    comp: Component,
    inputs: list[str],
    locations: list[LocationInfo],
    edges: list[EdgeInfo],
    signals: dict[str, dict[str, str]],
    names: dict[str, str],
    notes: list[str],
) -> list[str]:
    """The inputs nothing of the component reads (once their bounds became ranges)."""
    texts: list[str] = []
    for loc in locations:
        texts.extend(loc.flow.values())
        texts.extend(condition_text(c, names.__getitem__) for c in loc.invariant)
    for edge in edges:
        texts.append(edge.guard)
        texts.extend(edge.reset.values())
    for per_location in signals.values():
        texts.extend(per_location.values())
    used = identifiers(texts)
    dropped = [i for i in inputs if names[i] not in used]
    for var in dropped:
        notes.append(
            f"component '{comp.id}': variable '{var}' is declared but nothing reads it (no flow, "
            "invariant, guard, assignment or output): left out"
        )
    return dropped


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


def _bound(item: sx.Node, var: str) -> tuple[float, float] | None:
    """The interval a conjunct puts on ``var`` if it is a bound by numbers, else ``None``."""
    if not isinstance(item, sx.Cmp):
        return None
    lo, hi = -float("inf"), float("inf")
    found = False
    for op, a, b in zip(item.ops, item.operands, item.operands[1:], strict=False):
        a_is = isinstance(a, sx.Name) and a.name == var and not a.primed
        b_is = isinstance(b, sx.Name) and b.name == var and not b.primed
        a_val = constant_value(a, {})
        b_val = constant_value(b, {})
        if a_is and b_val is not None:
            value, side = b_val, op
        elif b_is and a_val is not None:
            value, side = (
                a_val,
                {"<=": ">=", "<": ">", ">=": "<=", ">": "<", "==": "=="}.get(op, op),
            )
        else:
            return None
        found = True
        if side in ("<=", "<"):
            hi = min(hi, value)
        elif side in (">=", ">"):
            lo = max(lo, value)
        elif side == "==":
            lo, hi = max(lo, value), min(hi, value)
        else:
            return None
    return (lo, hi) if found else None


def _input_ranges(
    comp: Component, free: list[str], locations: list[LocationInfo], notes: list[str]
) -> dict[str, tuple[float, float]]:
    ranges: dict[str, tuple[float, float]] = {}
    for var in free:
        per_location: list[tuple[float, float] | None] = []
        for loc in locations:
            bounds = [b for b in (_bound(c, var) for c in loc.invariant) if b is not None]
            if not bounds:
                per_location.append(None)
                continue
            lo = max(b[0] for b in bounds)
            hi = min(b[1] for b in bounds)
            per_location.append((lo, hi))
        if not per_location or any(r is None for r in per_location) or len(set(per_location)) > 1:
            notes.append(
                f"component '{comp.id}': input '{var}' is not bounded by the same numbers in "
                "every location's invariant, so it gets no range"
            )
            continue
        first = per_location[0]
        assert first is not None
        ranges[var] = first
        for loc in locations:
            kept = []
            for c in loc.invariant:
                if _bound(c, var) is not None:
                    loc.removed.append(f"input range of {var}")
                else:
                    kept.append(c)
            loc.invariant = kept
    return ranges


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
    changed = {k for k, v in values.items() if not (isinstance(v, sx.Name) and v.name == k)}

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
        if text(c) in source_texts and not (_variables(c) & changed):
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
    return EdgeInfo(source.name, target.name, tr.label, guard, reset, comment)


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


def _variables(node: sx.Node) -> set[str]:
    found: set[str] = set()
    stack = [node]
    while stack:
        current = stack.pop()
        if isinstance(current, sx.Name):
            found.add(current.name)
        elif isinstance(current, sx.Neg):
            stack.append(current.operand)
        elif isinstance(current, sx.BinOp):
            stack.extend((current.left, current.right))
        elif isinstance(current, sx.Call):
            stack.extend(current.args)
        elif isinstance(current, sx.Cmp):
            stack.extend(current.operands)
        elif isinstance(current, sx.And | sx.Or):
            stack.extend(current.items)
    return found
