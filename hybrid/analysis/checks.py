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

from hybrid.analysis.context import Analysis
from hybrid.analysis.findings import Finding, WitnessStep
from hybrid.analysis.property_checks import (
    assumptions,
    blocked_entries,
    incomplete_analysis,
    property_violations,
)
from hybrid.analysis.solve import contract
from hybrid.analysis.static import AutomatonFacts, initial_box
from hybrid.analysis.zerotime import system_components
from hybrid.errors import Position
from hybrid.expr import ir
from hybrid.expr.rho import BAND, guard_to_rho
from hybrid.model import Automaton, Edge

__all__ = [
    "CHECKS",
    "blocked_starts",
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
            initial = "', '".join(
                analysis.qualified(i, n) for n in comp.automaton.initial_locations
            )
            found.append(
                Finding.at(
                    "unreachable-location",
                    loc.position,
                    f"location '{qualified}' is unreachable from '{initial}'"
                    f"{blocked_entries(analysis, i, name)}; {assumptions(analysis.facts[i])}",
                    where=qualified,
                )
            )
    return found


def sink_locations(analysis: Analysis) -> list[Finding]:
    """Locations whose invariant the flow can leave but that no edge can leave.

    An error when the location has edges and none of them can ever fire (a
    run that gets there ends blocked, surely not what the edges were for); a
    note when it has no edge at all: a location that ends every run when its
    invariant runs out (a global clock ``clk <= T``, a time horizon) is a
    standard idiom.
    """
    found: list[Finding] = []
    for i, (comp, facts) in enumerate(zip(analysis.system.components, analysis.facts, strict=True)):
        for name, loc in comp.automaton.locations.items():
            lf = facts.locations[name]
            if not lf.can_be_left or not analysis.reached(i, name):
                continue
            if any(f.live for f in facts.outgoing(name)):
                continue
            qualified = analysis.qualified(i, name)
            if loc.urgent:
                found.append(
                    Finding.at(
                        "sink-location",
                        loc.position,
                        f"urgent location '{qualified}' is a sink: no time may pass there and "
                        + (
                            "none of its edges can ever fire"
                            if facts.outgoing(name)
                            else "it has no edge out"
                        )
                        + f"; a run that gets there ends blocked at once ({assumptions(facts)})",
                        where=qualified,
                    )
                )
                continue
            if not facts.outgoing(name):
                found.append(
                    Finding.at(
                        "sink-location",
                        loc.position,
                        f"location '{qualified}' has no edge out: a run ends blocked there when "
                        f"its invariant '{loc.invariant_source}' runs out (fine for a time "
                        "horizon or a final location)",
                        where=qualified,
                        severity="note",
                    )
                )
                continue
            found.append(
                Finding.at(
                    "sink-location",
                    loc.position,
                    f"location '{qualified}' is a sink: the flow can leave its invariant "
                    f"'{loc.invariant_source}' but none of its edges can ever fire; a run that "
                    f"gets there ends blocked ({assumptions(facts)})",
                    where=qualified,
                )
            )
    return found


def blocked_starts(analysis: Analysis) -> list[Finding]:
    """Initial locations no run gets out of, nor flows in: every run ends at ``t = 0``.

    The invariant is broken at every initial state, beyond the band within
    which the simulator counts it as on its boundary, and no edge out of the
    location can be enabled there (a jump at once would leave it). A lone
    automaton's run ends ``blocked``; in a system the other components may
    still jump at that instant (a zero-time cycle ends it ``zeno``).

    Examples
    --------
    >>> import hybrid
    >>> from hybrid.analysis.context import analyse
    >>> tank = hybrid.load("specs/thermostat.yaml", parameters={"T_low": 21.0})
    >>> blocked_starts(analyse(tank)) == []  # T = 20 < T_low: turn_on fires at t = 0
    True
    """
    found: list[Finding] = []
    ending = ("a run ends blocked at t = 0" if analysis.system.single else
              "a run ends at t = 0: blocked, or as the other components' jumps there end it")  # fmt: skip
    for i, (comp, facts) in enumerate(zip(analysis.system.components, analysis.facts, strict=True)):
        automaton = comp.automaton
        box = {**initial_box(automaton), **facts.inputs}
        states = [box[name] for name in automaton.state_names if name in box]
        width = BAND * (1.0 + max((max(abs(v.lo), abs(v.hi)) for v in states), default=0.0))
        for name in automaton.initial_locations:
            lf = facts.locations[name]
            rho = lf.env.evaluator(box).number(guard_to_rho(lf.invariant))
            if not rho.lo > width:  # holds, or may, somewhere in the initial set
                continue
            if any(contract(ef.entry_enabled, lf.env, box) is not None
                   for ef in facts.outgoing(name)):  # fmt: skip
                continue
            loc = automaton.locations[name]
            qualified = analysis.qualified(i, name)
            start = ", ".join(f"{k} in [{v.lo:g}, {v.hi:g}]" if v.lo != v.hi else f"{k} = {v.lo:g}"
                              for k, v in zip(automaton.state_names, states, strict=False))  # fmt: skip
            found.append(
                Finding.at(
                    "blocked-start",
                    loc.invariant_position,
                    f"no run gets past its start: the initial state ({start}) breaks the "
                    f"invariant '{loc.invariant_source}' of initial location '{qualified}' and "
                    f"no edge out of it can fire there ({ending}); fix the initial values or "
                    "the invariant",
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
                        "cannot hold where a run may be in its source, neither while flowing"
                        + _invariant_note(facts, edge)
                        + f" nor on entry; {assumptions(facts)}",
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
    return f" (within the invariant '{inv}' of '{edge.source}')"


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
    """Strongly connected components of edges that may fire again and again at one instant.

    One finding per component (:mod:`hybrid.analysis.zerotime`), with a
    shortest cycle through it as witness; only edges whose source may be
    reached count, and in a system a shared label counts only while every
    owner of it can take it again and again at one instant too.
    """

    def allowed(i: int, e: int) -> bool:
        return analysis.reached(i, analysis.facts[i].automaton.edges[e].source)

    per_component = system_components(analysis.zero_time, analysis.system.shared_labels, allowed)
    found: list[Finding] = []
    for i, components in enumerate(per_component):
        edges = analysis.facts[i].automaton.edges
        for comp in components:
            names = [analysis.qualified(i, edges[e].name) for e in comp.cycle]
            loop = " -> ".join([*names, names[0]])
            steps: list[WitnessStep] = [(None, analysis.qualified(i, edges[comp.cycle[0]].source))]
            steps += [
                (n, analysis.qualified(i, edges[e].target))
                for n, e in zip(names, comp.cycle, strict=True)
            ]
            more = len(comp.edges) - len(set(comp.cycle))
            found.append(
                Finding.at(
                    "zero-time-cycle",
                    edges[comp.cycle[0]].position,
                    f"edges {loop} may fire again and again without time passing (each guard "
                    "can hold right after the previous reset): a Zeno candidate"
                    + (f"; {more} more edge(s) can join such cycles" if more else ""),
                    where=names[0],
                    witness=steps,
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
    exprs += [r.predicate for r in a.requirements]
    return exprs


CHECKS: tuple[Callable[[Analysis], list[Finding]], ...] = (
    unreachable_locations,
    blocked_starts,
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
