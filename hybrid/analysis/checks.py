"""The checks of `hybrid check`: small functions from an :class:`Analysis` to findings.

:func:`hybrid.analysis.context.analyse` computes, once, everything the checks
read. Each check in :data:`CHECKS` is then a stateless function of that analysis,
returning findings with positions; tests run every check against one table of
small automata.

Examples
--------
>>> import hybrid
>>> from hybrid.analysis.context import analyse
>>> analysis = analyse(hybrid.load("specs/thermostat.yaml"))
>>> [check(analysis) for check in CHECKS] == [[]] * len(CHECKS)
True
"""

from __future__ import annotations

from collections.abc import Callable

from hybrid.analysis.context import Analysis, path_text
from hybrid.analysis.findings import Finding
from hybrid.analysis.static import AutomatonFacts
from hybrid.errors import Position
from hybrid.expr import ir
from hybrid.model import Automaton, Edge

__all__ = [
    "CHECKS",
    "dead_edges",
    "incomplete_analysis",
    "nondeterminism",
    "property_violations",
    "run_checks",
    "sink_locations",
    "unreachable_locations",
    "unused_declarations",
    "zero_time_cycles",
]


def _edge_position(edge: Edge) -> Position:
    return edge.guard_position if edge.guard_source.strip() != "true" else edge.position


# --- the checks --------------------------------------------------------------------------


def unreachable_locations(analysis: Analysis) -> list[Finding]:
    """Locations no path of live (and synchronisable) edges reaches from the initial one."""
    if not analysis.exploration.complete:
        return []
    props = analysis.system.properties
    declared = set(props.reachable) | set(props.unreachable)
    found: list[Finding] = []
    for i, comp in enumerate(analysis.system.components):
        for name, loc in comp.automaton.locations.items():
            qualified = analysis.qualified(i, name)
            if analysis.reached(i, name) or qualified in declared:
                continue
            found.append(
                Finding.at(
                    "unreachable-location",
                    loc.position,
                    f"location '{qualified}' is unreachable from '{analysis.qualified(i, comp.automaton.initial_location)}'"
                    f"{_blocked_entries(analysis, i, name)}",
                    where=qualified,
                )
            )
    return found


def _blocked_entries(analysis: Analysis, component: int, location: str) -> str:
    """Why nothing leads into ``location``: its incoming edges that can never fire."""
    facts = analysis.facts[component]
    into = [f for f in facts.incoming(location) if f.edge.source != location]
    dead = [f.edge.name for f in into if not f.live]
    if dead:
        names = ", ".join(f"'{n}'" for n in dead)
        return f": the guard of {names} into it can never hold within the declared bounds"
    if not into:
        return ": no edge leads into it"
    return ": no reachable location has an edge into it that can fire"


def sink_locations(analysis: Analysis) -> list[Finding]:
    """Locations whose invariant the flow can leave but that no edge can leave."""
    found: list[Finding] = []
    for i, (comp, facts) in enumerate(zip(analysis.system.components, analysis.facts, strict=True)):
        for name, loc in comp.automaton.locations.items():
            lf = facts.locations[name]
            if not lf.can_be_left or not analysis.reached(i, name):
                continue
            if any(f.live for f in facts.outgoing(name)):
                continue
            qualified = analysis.qualified(i, name)
            edges = facts.outgoing(name)
            why = "no edge leaves it" if not edges else "none of its edges can ever fire"
            found.append(
                Finding.at(
                    "sink-location",
                    loc.position,
                    f"location '{qualified}' is a sink: the flow can leave its invariant "
                    f"'{loc.invariant_source}' but {why}; a run that gets there ends blocked",
                    where=qualified,
                )
            )
    return found


def dead_edges(analysis: Analysis) -> list[Finding]:
    """Edges whose guard cannot hold within the bounds, or whose label never synchronises."""
    found: list[Finding] = []
    exploration = analysis.exploration
    tables = analysis.tables
    for i, facts in enumerate(analysis.facts):
        for ef in facts.edges:
            edge = ef.edge
            qualified = analysis.qualified(i, edge.name)
            if not ef.live:
                found.append(
                    Finding.at(
                        "dead-edge",
                        _edge_position(edge),
                        f"edge '{qualified}' can never fire: its guard '{edge.guard_source}' "
                        f"cannot hold within the declared bounds" + _invariant_note(facts, edge),
                        where=qualified,
                    )
                )
                continue
            owners = tables.owners.get(edge.label or "")
            if (
                owners
                and exploration.complete
                and analysis.reached(i, edge.source)
                and (i, edge.index) not in exploration.fired
            ):
                others = ", ".join(tables.components[o].name for o in owners if o != i)
                found.append(
                    Finding.at(
                        "dead-edge",
                        edge.position,
                        f"edge '{qualified}' can never fire: it synchronises on label "
                        f"'{edge.label}' with {others}, and no reachable mode with "
                        f"'{analysis.qualified(i, edge.source)}' has all of them able to take it",
                        where=qualified,
                    )
                )
    return found


def _invariant_note(facts: AutomatonFacts, edge: Edge) -> str:
    inv = facts.automaton.locations[edge.source].invariant_source
    if inv.strip() == "true":
        return ""
    return f" and the invariant '{inv}' of '{edge.source}'"


def nondeterminism(analysis: Analysis) -> list[Finding]:
    """Same-priority edges of one location whose guards can hold at the same point."""
    exploration = analysis.exploration
    found: list[Finding] = []
    for i, facts in enumerate(analysis.facts):
        comp = analysis.tables.components[i]
        for k, name in enumerate(comp.locations):
            if exploration.complete and (i, k) not in exploration.conflicted_at:
                continue
            for a, b in comp.conflicts[k]:
                first, second = facts.automaton.edges[a], facts.automaton.edges[b]
                found.append(
                    Finding.at(
                        "nondeterminism",
                        second.position,
                        f"edges '{analysis.qualified(i, first.name)}' and "
                        f"'{analysis.qualified(i, second.name)}' leave "
                        f"'{analysis.qualified(i, name)}' with the same priority "
                        f"{first.priority} and their guards can hold at once; the simulator "
                        f"takes '{first.name}' (file order). Give one a higher priority or "
                        "make the guards disjoint",
                        where=analysis.qualified(i, second.name),
                    )
                )
    return found


def zero_time_cycles(analysis: Analysis) -> list[Finding]:
    """Cycles of edges that can be taken again and again without time passing."""
    found: list[Finding] = []
    for i, facts in enumerate(analysis.facts):
        edges = facts.automaton.edges
        for cycle in facts.zero_time_cycles():
            if not all(analysis.reached(i, edges[e].source) for e in cycle):
                continue
            names = [analysis.qualified(i, edges[e].name) for e in cycle]
            loop = " -> ".join([*names, names[0]])
            found.append(
                Finding.at(
                    "zero-time-cycle",
                    edges[cycle[0]].position,
                    f"edges {loop} can fire again and again without time passing (each guard "
                    "can hold right after the previous reset): a Zeno candidate",
                    where=names[0],
                )
            )
    return found


def unused_declarations(analysis: Analysis) -> list[Finding]:
    """Parameters and inputs no expression reads, labels no edge carries.

    Signals are never reported: they are outputs (written to the trajectory),
    and a signal a location overrides must be declared even when every
    location overrides it.
    """
    found: list[Finding] = []
    for index, comp in enumerate(analysis.system.components):
        a = comp.automaton
        exprs = _expressions(a)
        params: set[str] = set()
        inputs: set[str] = set()
        for e in exprs:
            params |= ir.names_in(e, ir.PARAM)
            inputs |= ir.names_in(e, ir.INPUT)
        for name in a.parameters:
            if name not in params:
                found.append(
                    Finding.at(
                        "unused-declaration",
                        a.parameter_positions.get(name, a.position),
                        f"parameter '{analysis.qualified(index, name)}' is never used",
                        where=analysis.qualified(index, name),
                    )
                )
        for name in a.inputs:
            if name not in inputs:
                found.append(
                    Finding.at(
                        "unused-declaration",
                        a.input_positions.get(name, a.position),
                        f"input '{analysis.qualified(index, name)}' is never used",
                        where=analysis.qualified(index, name),
                    )
                )
        carried = {e.label for e in a.edges}
        for name in a.labels:
            if name not in carried:
                found.append(
                    Finding.at(
                        "unused-declaration",
                        a.label_positions.get(name, a.position),
                        f"label '{analysis.qualified(index, name)}' is on no edge"
                        + (
                            " (so edges of other components with this label can never fire)"
                            if name in analysis.tables.owners
                            else ""
                        ),
                        where=analysis.qualified(index, name),
                    )
                )
    return found


def _expressions(a: Automaton) -> list[ir.Expr]:
    exprs: list[ir.Expr] = [*a.signals.values()]
    for loc in a.locations.values():
        exprs += [*loc.flow.values(), *loc.signals.values(), loc.invariant]
    for edge in a.edges:
        exprs += [edge.guard, *edge.reset.values()]
    return exprs


def property_violations(analysis: Analysis) -> list[Finding]:
    """The declared properties refuted, each with a witness path where there is one."""
    props = analysis.system.properties
    exploration = analysis.exploration
    tables = analysis.tables
    where = props.positions
    position = analysis.system.position
    index = {
        tables.location_name(i, k): (i, k)
        for i, c in enumerate(tables.components)
        for k in range(len(c.locations))
    }
    found: list[Finding] = []
    for name in (*props.reachable, *props.unreachable):
        if name not in index:
            found.append(
                Finding.at(
                    "property-violated",
                    position,
                    f"property names an unknown location '{name}'",
                    where=name,
                )
            )
    for name in props.reachable:
        if name not in index:
            continue
        i, k = index[name]
        if exploration.complete and not exploration.reached[i][k]:
            loc = tables.components[i].locations[k]
            found.append(
                Finding.at(
                    "property-violated",
                    where.get(f"reachable:{name}", position),
                    f"location '{name}' is declared reachable but is not"
                    f"{_blocked_entries(analysis, i, loc)}",
                    where=f"reachable: {name}",
                )
            )
    for name in props.unreachable:
        if name not in index:
            continue
        i, k = index[name]
        if exploration.reached[i][k]:
            witness = analysis.witness(exploration.first_reach[(i, k)])
            found.append(
                Finding.at(
                    "property-violated",
                    where.get(f"unreachable:{name}", position),
                    f"location '{name}' is declared unreachable but may be reached: "
                    f"{path_text(witness)}",
                    where=f"unreachable: {name}",
                    witness=witness,
                )
            )
    if props.deadlock_free and exploration.first_deadlock is not None:
        witness = analysis.witness(exploration.first_deadlock)
        stuck = ", ".join(
            sorted(f"'{tables.location_name(i, k)}'" for i, k in exploration.stuck_at)
        )
        found.append(
            Finding.at(
                "property-violated",
                where.get("deadlock_free", position),
                f"deadlock_free: the flow may leave the invariant of {stuck} at a point where "
                f"no transition is enabled ({exploration.deadlocks} reachable mode(s)); "
                f"witness: {path_text(witness)}",
                where="deadlock_free",
                witness=witness,
            )
        )
    if props.deterministic and exploration.first_conflict is not None:
        witness = analysis.witness(exploration.first_conflict)
        places = ", ".join(
            sorted(f"'{tables.location_name(i, k)}'" for i, k in exploration.conflicted_at)
        )
        found.append(
            Finding.at(
                "property-violated",
                where.get("deterministic", position),
                f"deterministic: edges of the same priority can be enabled at once in {places} "
                f"({exploration.conflicts} reachable mode(s)); witness: {path_text(witness)}",
                where="deterministic",
                witness=witness,
            )
        )
    return found


def incomplete_analysis(analysis: Analysis) -> list[Finding]:
    """A note when the product was too large to explore whole."""
    exploration = analysis.exploration
    if exploration.complete:
        return []
    return [
        Finding.at(
            "analysis-incomplete",
            analysis.system.position,
            f"exploration of the product stopped after {exploration.states} modes; "
            "unreachable-location, never-synchronising edges and reachable properties are "
            "not reported",
            where=analysis.system.name,
        )
    ]


CHECKS: tuple[Callable[[Analysis], list[Finding]], ...] = (
    unreachable_locations,
    sink_locations,
    dead_edges,
    nondeterminism,
    zero_time_cycles,
    unused_declarations,
    property_violations,
    incomplete_analysis,
)


def run_checks(analysis: Analysis) -> list[Finding]:
    """Every check's findings, duplicates removed, sorted by place."""
    unique: dict[tuple[object, ...], Finding] = {}
    for check in CHECKS:
        for f in check(analysis):
            unique.setdefault((f.rule, f.file, f.line, f.column, f.message), f)
    return sorted(unique.values(), key=Finding.sort_key)
