"""Checks of the declared properties, the note of an incomplete exploration, and the
texts that say what a finding proved and under which assumptions.

Examples
--------
>>> import hybrid
>>> from hybrid.analysis.context import analyse
>>> analysis = analyse(hybrid.load("specs/thermostat.yaml"))
>>> property_violations(analysis), incomplete_analysis(analysis)
([], [])
>>> assumptions(analysis.facts[0])
'proved for every run that stays within the declared bounds (T in [0, 40])'
"""

from __future__ import annotations

import math

from hybrid.analysis.context import Analysis, path_text
from hybrid.analysis.findings import Finding
from hybrid.analysis.forbidden import forbidden_states
from hybrid.analysis.product import MAX_INITIAL_MODES
from hybrid.analysis.static import AutomatonFacts

__all__ = ["assumptions", "blocked_entries", "incomplete_analysis", "property_violations"]


def assumptions(facts: AutomatonFacts) -> str:
    """What a "never" finding of this automaton assumes: its declared bounds, its inputs."""
    states = set(facts.automaton.state_names)
    bounded = [
        f"{name} in [{_number(b.lo)}, {_number(b.hi)}]"
        for name, b in facts.bounds.items()
        if name in states and (math.isfinite(b.lo) or math.isfinite(b.hi))
    ]
    text = "proved for every run"
    if bounded:
        shown = ", ".join(bounded[:4]) + (", ..." if len(bounded) > 4 else "")
        text += f" that stays within the declared bounds ({shown})"
    inputs = facts.automaton.inputs
    ranged = [
        f"{n} in [{_number(facts.inputs[n].lo)}, {_number(facts.inputs[n].hi)}]"
        for n in inputs
        if n in facts.inputs
    ]
    if ranged:
        shown = ", ".join(ranged[:4]) + (", ..." if len(ranged) > 4 else "")
        text += f", with inputs within their ranges ({shown})"
        if len(ranged) < len(inputs):
            text += " and the other inputs anything"
    elif inputs:
        text += ", whatever the inputs"
    sets = [
        f"{n} in {r.text()}" for n, r in facts.automaton.initial_set().items() if not r.is_point
    ]
    if sets:
        shown = ", ".join(sets[:4]) + (", ..." if len(sets) > 4 else "")
        text += f", from every point of the initial set ({shown})"
    return text


def _number(value: float) -> str:
    if math.isinf(value):
        return "inf" if value > 0 else "-inf"
    return f"{value:g}"


def blocked_entries(analysis: Analysis, component: int, location: str) -> str:
    """Why nothing leads into ``location``: its incoming edges that can never fire."""
    facts = analysis.facts[component]
    into = [f for f in facts.incoming(location) if f.edge.source != location]
    dead = [f.edge.name for f in into if not f.live]
    if dead:
        names = ", ".join(f"'{n}'" for n in dead)
        return f": {names} into it can never fire"
    if not into:
        return ": no edge leads into it"
    return ": no reachable location has an edge into it that can fire"


def property_violations(analysis: Analysis) -> list[Finding]:
    """The declared properties disproved (``property-disproved``: a location declared
    reachable that is proved unreachable) or not proved (``property-unproved``, with a
    candidate path: the over-approximation meets them, no run was simulated); forbidden
    states: :func:`hybrid.analysis.forbidden.forbidden_states`. A property naming an
    unknown location is ``invalid-spec`` (the reader rejects it in a file; a model built
    in code may still carry one)."""
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
                    "invalid-spec",
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
                    "property-disproved",
                    where.get(f"reachable:{name}", position),
                    f"location '{name}' is declared reachable but is not"
                    f"{blocked_entries(analysis, i, loc)}; {assumptions(analysis.facts[i])}",
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
                    "property-unproved",
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
                "property-unproved",
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
                "property-unproved",
                where.get("deterministic", position),
                f"deterministic: edges of the same priority can be enabled at once in {places} "
                f"({exploration.conflicts} reachable mode(s)); witness: {path_text(witness)}",
                where="deterministic",
                witness=witness,
            )
        )
    found.extend(forbidden_states(analysis))
    return found


def incomplete_analysis(analysis: Analysis) -> list[Finding]:
    """A note when the product was too large to explore whole."""
    exploration = analysis.exploration
    if exploration.complete:
        return []
    if not all(tables.initials_complete for _, tables, _ in exploration.parts):
        text = (
            f"a group of interacting components has more than {MAX_INITIAL_MODES:,} initial modes "
            "(each component in one of its initial locations): the exploration started from "
            f"the first {MAX_INITIAL_MODES:,}; "
        )
    else:
        text = (
            f"exploration of the product stopped at its bound of {exploration.bound:,} modes "
            f"(in a group of {exploration.largest_group} interacting component(s); the bound "
            "keeps the explorer's memory under control); "
        )
    return [
        Finding.at(
            "analysis-incomplete",
            analysis.system.position,
            text + "unreachable-location, never-synchronising edges and reachable properties "
            "are not reported, and deadlock_free and deterministic hold only for the modes "
            "explored",
            where=analysis.system.name,
        )
    ]
