"""How the components of a system are bound: renames, and what each input reads.

One automaton may be bound several times in a system under other names (the
SpaceEx *bind*).

A system component may give ``rename: {old: new}``: the component is the
automaton with its state variables, signals, inputs and labels renamed, all at
once (``{x: y, y: x}`` swaps them). Parameters are not renamed (they are
qualified by the component, ``comp.name``, and set with ``parameters:``), nor
locations and edges (qualified by the component too). Renaming an input to the
name of another component's signal or state variable binds it there: that is
how one filter template reads a different variable in each instance.

:func:`rename_problems` lists what is wrong with a mapping (an unknown name, a
clash, a reserved name), for the reader to place; :func:`rename` applies a
valid one. :func:`input_problems` checks what each input of a system reads: the
signal or state variable of exactly one other component, or nothing (a *free*
input of the system, which then needs a range, the same in every component
that reads it). :func:`signal_cycle_problems` finds signals defined through each
other across components, in a combination of locations the components can be in.

Examples
--------
>>> import hybrid
>>> lag = hybrid.load_text('''
... automaton: lag
... parameters: {k: 2.0}
... state: {x: {}}
... inputs: [u]
... locations: {l: {flow: {x: k * (u - x)}}}
... ''')
>>> second = rename(lag, {"x": "x2", "u": "x1"})
>>> second.state_names, second.inputs
(('x2',), ('x1',))
>>> rename_problems(lag, {"k": "gain", "y": "z"})
[('k', 'key', "'k' is a parameter of 'lag': set it with `parameters:`; only state variables, signals, inputs and labels are renamed"), ('y', 'key', "rename: 'y' is not a state variable, signal, input or label of 'lag'")]
"""

from __future__ import annotations

import itertools
import keyword
import math
from collections.abc import Mapping, Sequence
from dataclasses import replace
from difflib import get_close_matches
from types import MappingProxyType
from typing import TypeVar

from hybrid.errors import Position, did_you_mean
from hybrid.expr import ir
from hybrid.expr.dependencies import find_dependency_cycle
from hybrid.expr.functions import BUILTINS
from hybrid.expr.transform import rename_names
from hybrid.model import Automaton

__all__ = ["input_problems", "rename", "rename_problems", "signal_cycle_problems"]

T = TypeVar("T")

_RESERVED = {"t", "pi", "true", "false", *BUILTINS, *keyword.kwlist, *keyword.softkwlist}


def _kinds(automaton: Automaton) -> dict[str, str]:
    kinds = {p: "parameter" for p in automaton.parameters}
    kinds.update({s: "state variable" for s in automaton.state_names})
    kinds.update({s: "signal" for s in automaton.signal_names})
    kinds.update({s: "input" for s in automaton.inputs})
    return kinds


def rename_problems(automaton: Automaton, mapping: Mapping[str, str]) -> list[tuple[str, str, str]]:
    """What is wrong with renaming ``automaton`` by ``mapping``.

    Each problem is ``(old name, "key" or "value", message)``: the place to
    show it is that key of the mapping or its value.
    """
    problems: list[tuple[str, str, str]] = []
    kinds = _kinds(automaton)
    labels = set(automaton.labels)
    for old, new in mapping.items():
        kind = kinds.get(old)
        if kind == "parameter":
            problems.append(
                (
                    old,
                    "key",
                    f"'{old}' is a parameter of '{automaton.name}': set it with `parameters:`; "
                    "only state variables, signals, inputs and labels are renamed",
                )
            )
        elif kind is None and old not in labels:
            known = [*automaton.state_names, *automaton.signal_names, *automaton.inputs, *labels]
            close = get_close_matches(old, known, n=1, cutoff=0.6)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            problems.append(
                (
                    old,
                    "key",
                    f"rename: '{old}' is not a state variable, signal, input or label of "
                    f"'{automaton.name}'{hint}",
                )
            )
        elif kind is not None and (new in _RESERVED or new in automaton.functions):
            problems.append((old, "value", f"rename: '{new}' is a reserved name; choose another"))
    if problems:
        return problems
    # after renaming, every name of each namespace must still be unique
    for namespace, names in (("", list(kinds)), ("label", sorted(labels))):
        seen: dict[str, str] = {}
        for name in names:
            new = mapping.get(name, name)
            if new in seen:
                first, second = seen[new], name
                old = second if second in mapping else first
                what = f"label '{first}'" if namespace else f"{kinds[first]} '{first}'"
                other = f"label '{second}'" if namespace else f"{kinds[second]} '{second}'"
                problems.append(
                    (
                        old,
                        "value",
                        f"rename: {what} and {other} of '{automaton.name}' would both be "
                        f"named '{new}'",
                    )
                )
            seen.setdefault(new, name)
    return problems


def rename(automaton: Automaton, mapping: Mapping[str, str]) -> Automaton:
    """``automaton`` with state variables, signals, inputs and labels renamed.

    Raises
    ------
    ValueError
        If the mapping has problems (see :func:`rename_problems`).
    """
    problems = rename_problems(automaton, mapping)
    if problems:
        raise ValueError(problems[0][2])
    values = {
        k: v for k, v in mapping.items() if k in automaton.state_names or k in automaton.signals
    }
    values.update({k: v for k, v in mapping.items() if k in automaton.inputs})
    labels = {k: v for k, v in mapping.items() if k in automaton.labels}
    if not values and not labels:
        return automaton

    def name(n: str) -> str:
        return values.get(n, n)

    def expr(node: ir.Expr) -> ir.Expr:
        return rename_names(node, values) if values else node

    def keys(table: Mapping[str, T]) -> dict[str, T]:
        return {name(k): v for k, v in table.items()}

    locations = {
        lname: replace(
            loc,
            flow=MappingProxyType({name(k): expr(v) for k, v in loc.flow.items()}),
            signals=MappingProxyType({name(k): expr(v) for k, v in loc.signals.items()}),
            invariant=expr(loc.invariant),
        )
        for lname, loc in automaton.locations.items()
    }
    edges = tuple(
        replace(
            e,
            label=None if e.label is None else labels.get(e.label, e.label),
            guard=expr(e.guard),
            reset=MappingProxyType({name(k): expr(v) for k, v in e.reset.items()}),
        )
        for e in automaton.edges
    )
    forbidden = tuple(
        replace(f, when=None if f.when is None else expr(f.when))
        for f in automaton.properties.forbidden
    )
    return replace(
        automaton,
        states=tuple(replace(s, name=name(s.name)) for s in automaton.states),
        signals=MappingProxyType({name(k): expr(v) for k, v in automaton.signals.items()}),
        vector_sizes=MappingProxyType(keys(automaton.vector_sizes)),
        signal_names=tuple(name(n) for n in automaton.signal_names),
        inputs=tuple(name(n) for n in automaton.inputs),
        labels=tuple(labels.get(n, n) for n in automaton.labels),
        locations=MappingProxyType(locations),
        edges=edges,
        initial_state=MappingProxyType(keys(automaton.initial_state)),
        initial_ranges=MappingProxyType(keys(automaton.initial_ranges)),
        ranges=MappingProxyType(keys(automaton.ranges)),
        properties=replace(automaton.properties, forbidden=forbidden),
        signal_positions=keys(automaton.signal_positions),
        signal_units=keys(automaton.signal_units),
        input_positions=keys(automaton.input_positions),
        label_positions={labels.get(k, k): v for k, v in automaton.label_positions.items()},
    )


def input_problems(components: Sequence[tuple[str, Automaton]]) -> list[tuple[Position, str]]:
    """Inputs of a system's components that read several things, or nothing without a range."""
    problems: list[tuple[Position, str]] = []
    free: dict[str, tuple[str, tuple[float, float, float]]] = {}
    for name, a in components:
        for u in a.inputs:
            pos = a.input_positions.get(u, a.position)
            providers = [
                other
                for other, b in components
                if b is not a and (u in b.signal_names or u in b.state_names)
            ]
            if len(providers) > 1:
                problems.append(
                    (
                        pos,
                        f"input '{u}' of component '{name}' is defined by several components: "
                        f"{', '.join(providers)}",
                    )
                )
            elif providers:
                continue
            elif u not in a.ranges:
                offered = [n for other, b in components if b is not a
                           for n in (*b.signal_names, *b.state_names)]  # fmt: skip
                close = did_you_mean(u, offered, 0.5).removeprefix("; ")
                close = f" ({close})" if close else ""
                problems.append(
                    (
                        pos,
                        f"input '{u}' of component '{name}' is not a signal or state variable of "
                        f"any other component{close}; bind it (rename: {{{u}: other}}), or give "
                        f"it a range to leave it free (inputs: {{{u}: {{range: [low, high]}}}})",
                    )
                )
            else:
                r = a.ranges[u]
                mine = (r.lo, r.hi, r.nominal)
                first = free.setdefault(u, (name, mine))
                if first[1] != mine:
                    problems.append(
                        (
                            pos,
                            f"free input '{u}' of component '{name}' has the range "
                            f"{r.text()} (nominal {r.nominal:g}), but component '{first[0]}' "
                            f"gives it [{first[1][0]:g}, {first[1][1]:g}] (nominal "
                            f"{first[1][2]:g}): one input, one range",
                        )
                    )
    return problems


COMBINATIONS_CHECKED = 4096
"""Above this many combinations of location-specific definitions, the union is checked."""


def signal_cycle_problems(
    components: Sequence[tuple[str, Automaton]],
) -> list[tuple[Position, str]]:
    """Signals of several components defined through each other, where that can happen.

    A signal's definition in force depends on its component's location, and an
    input is a use of the signal of the same name that another component defines.
    A cycle is reported only if some combination of locations (one per component)
    puts all of its definitions in force at once; beyond
    :data:`COMBINATIONS_CHECKED` combinations, a cycle through the union of the
    definitions is reported (saying so).

    Examples
    --------
    >>> import hybrid
    >>> a = hybrid.load_text('''
    ... automaton: a
    ... inputs: [v]
    ... signals: {s: "0"}
    ... locations: {on: {signals: {s: v + 1}}, off: {}}
    ... ''')
    >>> b = hybrid.load_text('''
    ... automaton: b
    ... inputs: [s]
    ... signals: {v: "2 * s"}
    ... locations: {l: {}}
    ... ''')
    >>> [m for _, m in signal_cycle_problems([("a", a), ("b", b)])]
    ['signals of the components form a circular definition when a is in on: s -> v -> s']
    """
    common: dict[str, set[str]] = {}
    where: dict[str, Position] = {}
    variants: list[tuple[str, list[tuple[str, dict[str, set[str]]]]]] = []
    for cname, a in components:
        for name in a.signal_names:
            common[name] = ir.names_in(a.signals[name])
            where[name] = a.signal_positions.get(name, a.position)
        mine = _location_variants(a)
        if mine:
            variants.append((cname, mine))
    union = {n: set(d) for n, d in common.items()}
    for _, mine in variants:
        for _, local in mine:
            for n, d in local.items():
                union[n] |= d
    cycle = find_dependency_cycle(union)
    if cycle is None:
        return []
    if not variants:
        return [(where[cycle[0]], _cycle_message(cycle, ""))]
    if math.prod(len(m) for _, m in variants) > COMBINATIONS_CHECKED:
        return [(where[cycle[0]], _cycle_message(cycle, " (in some location of each)"))]
    automata = dict(components)
    for combination in itertools.product(*(m for _, m in variants)):
        deps = dict(common)
        for _, local in combination:
            deps.update(local)
        cycle = find_dependency_cycle(deps)
        if cycle is not None:
            chosen = [
                f"{cname} is in {lname}"
                for (cname, _), (lname, _) in zip(variants, combination, strict=True)
            ]
            context = f" when {' and '.join(chosen)}" if chosen else ""
            # placed at a location's own definition in the cycle, if one is: the line
            # that makes the loop (the file's own one may not be in it at all)
            place = where[cycle[0]]
            for (cname, _), (lname, local) in zip(variants, combination, strict=True):
                if any(name in local for name in cycle):
                    place = automata[cname].locations[lname].position
                    break
            return [(place, _cycle_message(cycle, context))]
    return []


def _location_variants(a: Automaton) -> list[tuple[str, dict[str, set[str]]]]:
    """The distinct sets of location-specific signal dependencies of ``a``, each with
    the first location that has it (for the file's own definitions alone: the first
    location that overrides none)."""
    seen: set[tuple[tuple[str, tuple[str, ...]], ...]] = set()
    mine: list[tuple[str, dict[str, set[str]]]] = []
    plain = ""
    for lname, loc in a.locations.items():
        local = {n: ir.names_in(e) for n, e in loc.signals.items() if n in a.signal_names}
        key = tuple(sorted((n, tuple(sorted(d))) for n, d in local.items()))
        if not local:
            plain = plain or lname
        elif key not in seen:
            seen.add(key)
            mine.append((lname, local))
    if mine and plain:
        mine.append((plain, {}))
    return mine


def _cycle_message(cycle: list[str], context: str) -> str:
    return f"signals of the components form a circular definition{context}: " + " -> ".join(
        [*cycle, cycle[0]]
    )
