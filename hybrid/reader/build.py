"""From a validated spec to a frozen :class:`~hybrid.model.Automaton`.

Here live the checks pydantic cannot make because they relate parts of the
file to each other: names used twice across kinds, references to locations,
labels and state variables, expressions (parsed in the scope of the spec),
circular signal definitions and function libraries. Every problem is collected
with its position, and all are reported together.
"""

from __future__ import annotations

import ast
import keyword
import math
from collections.abc import Mapping
from dataclasses import replace
from types import MappingProxyType
from typing import Any

from hybrid.errors import Position, SpecError
from hybrid.expr import ir
from hybrid.expr.dependencies import find_cycle
from hybrid.expr.functions import BUILTINS, Function, available_libraries, load_library
from hybrid.expr.parse import (
    MAX_SOURCE_CHARS,
    ExprError,
    Scope,
    _ast_parse,
    parse_expression,
    vector_call,
)
from hybrid.model import Automaton, Edge, Location, Properties, StateVar
from hybrid.reader.characters import ascii_only
from hybrid.reader.messages import closest
from hybrid.reader.requirements import build_requirements
from hybrid.reader.schema import AutomatonSpec, PropertiesSpec
from hybrid.reader.yamlpos import PositionMap

__all__ = ["build_automaton", "build_properties"]

RESERVED = {"t", "pi", "true", "false", *BUILTINS, *keyword.kwlist, *keyword.softkwlist}
_KIND_TEXT = {"param": "parameter", "state": "state variable", "signal": "signal", "input": "input"}


class _Problems:
    def __init__(self, positions: PositionMap) -> None:
        self.positions = positions
        self.items: list[tuple[Position, str]] = []

    def at_key(self, path: tuple[Any, ...], message: str) -> None:
        self.items.append((self.positions.key(path), message))

    def at_value(self, path: tuple[Any, ...], message: str) -> None:
        self.items.append((self.positions.value(path), message))

    def expression(self, path: tuple[Any, ...], source: str, scope: Scope, want: str) -> ir.Expr:
        try:
            ascii_only(source)
            return parse_expression(source, scope, want=want)
        except ExprError as exc:
            self.items.append((self.positions.value(path).shifted(exc.col), exc.message))
            return ir.BoolConst(True) if want == "bool" else ir.Num(0.0)


def build_automaton(spec: AutomatonSpec, positions: PositionMap) -> Automaton:
    """Check cross-references and expressions of ``spec``; raise one :class:`SpecError`."""
    problems = _Problems(positions)
    functions = _libraries(spec, problems)
    kinds = _declare_names(spec, problems, functions)
    sizes = _vector_sizes(spec, functions)
    scope = Scope(variables=kinds, functions=functions, vectors=sizes)

    signals = _signals(spec.signals, ("signals",), scope, problems, sizes)
    states = _states(spec, positions, problems)
    state_names = [s.name for s in states]

    locations: dict[str, Location] = {}
    for lname, loc in spec.locations.items():
        base = ("locations", lname)
        flow: dict[str, ir.Expr] = {}
        for var, source in loc.flow.items():
            if var not in spec.state:
                problems.at_key(
                    (*base, "flow", var),
                    f"flow of '{var}': not a state variable{closest(var, state_names)}",
                )
                continue
            flow[var] = problems.expression((*base, "flow", var), source, scope, "number")
        for var in loc.signals:
            if var not in spec.signals:
                problems.at_key(
                    (*base, "signals", var),
                    f"signal '{var}' is not declared in `signals`; a location can only "
                    f"override declared signals{closest(var, list(spec.signals))}",
                )
        local = {k: v for k, v in loc.signals.items() if k in spec.signals}
        loc_signals = _signals(local, (*base, "signals"), scope, problems, sizes)
        invariant = problems.expression((*base, "invariant"), loc.invariant, scope, "bool")
        locations[lname] = Location(
            name=lname,
            flow=MappingProxyType(flow),
            signals=MappingProxyType(loc_signals),
            invariant=invariant,
            invariant_source=loc.invariant,
            position=positions.key(base),
            invariant_position=positions.value((*base, "invariant")),
        )
        cycle = find_cycle({**signals, **loc_signals})
        if cycle and not find_cycle(signals):
            problems.at_key(
                (*base, "signals", cycle[0]) if cycle[0] in local else ("signals", cycle[0]),
                f"signals form a circular definition in location '{lname}': "
                + " -> ".join([*cycle, cycle[0]]),
            )
    cycle = find_cycle(signals)
    if cycle:
        problems.at_key(
            ("signals", cycle[0]),
            "signals form a circular definition: " + " -> ".join([*cycle, cycle[0]]),
        )

    edges = _edges(spec, positions, problems, scope, state_names)
    initial_location, initial_state = _initial(spec, problems, state_names)
    properties = build_properties(spec.properties, positions, problems.items, list(spec.locations))
    if spec.checks is not None:
        properties = replace(properties, ignore=tuple(spec.checks.ignore))
    locs = list(spec.locations)
    requirements = build_requirements(spec.requirements, positions, scope, locs, problems.items)

    if problems.items:
        raise SpecError.many(problems.items)
    return Automaton(
        name=spec.automaton,
        parameters=MappingProxyType(dict(spec.parameters)),
        states=tuple(states),
        signals=MappingProxyType(signals),
        vector_sizes=MappingProxyType(sizes),
        signal_names=tuple(spec.signals),
        inputs=tuple(spec.inputs),
        labels=tuple(spec.labels),
        locations=MappingProxyType(locations),
        edges=tuple(edges),
        initial_location=initial_location,
        initial_state=MappingProxyType(initial_state),
        properties=properties,
        functions=MappingProxyType(functions),
        description=spec.description,
        file=positions.file,
        position=positions.value(()),
        parameter_positions={k: positions.key(("parameters", k)) for k in spec.parameters},
        signal_positions={k: positions.key(("signals", k)) for k in spec.signals},
        input_positions={k: positions.value(("inputs", i)) for i, k in enumerate(spec.inputs)},
        label_positions={k: positions.value(("labels", i)) for i, k in enumerate(spec.labels)},
        requirements=requirements,
    )


def _libraries(spec: AutomatonSpec, problems: _Problems) -> dict[str, Function]:
    functions: dict[str, Function] = {}
    for i, lib in enumerate(spec.uses):
        try:
            table = load_library(lib)
        except LookupError:
            installed = available_libraries()
            problems.at_value(
                ("uses", i),
                f"no installed package registers the function library '{lib}' "
                f"(entry-point group hybrid.functions; installed: {', '.join(installed) or 'none'})",
            )
            continue
        except Exception as exc:  # a broken third-party package must not crash loading
            problems.at_value(("uses", i), f"function library '{lib}' failed to load: {exc}")
            continue
        functions.update(table)
    return functions


def _declare_names(
    spec: AutomatonSpec, problems: _Problems, functions: Mapping[str, Function]
) -> dict[str, str]:
    kinds: dict[str, str] = {}
    first: dict[str, Position] = {}
    groups: list[tuple[str, list[tuple[str, tuple[Any, ...]]]]] = [
        ("param", [(n, ("parameters", n)) for n in spec.parameters]),
        ("state", [(n, ("state", n)) for n in spec.state]),
        ("signal", [(n, ("signals", n)) for n in spec.signals]),
        ("input", [(n, ("inputs", i)) for i, n in enumerate(spec.inputs)]),
    ]
    for kind, names in groups:
        for name, path in names:
            if name in RESERVED or name in functions:
                problems.at_key(path, f"'{name}' is a reserved name; choose another")
                continue
            if name in kinds:
                prev = first[name]
                problems.at_key(
                    path,
                    f"'{name}' is declared twice: as {_KIND_TEXT[kind]} here and as "
                    f"{_KIND_TEXT[kinds[name]]} at line {prev.line}",
                )
                continue
            kinds[name] = kind
            first[name] = problems.positions.key(path)
    seen_labels: set[str] = set()
    for i, label in enumerate(spec.labels):
        if label in seen_labels:
            problems.at_value(("labels", i), f"label '{label}' is declared twice")
        seen_labels.add(label)
    return kinds


def _vector_sizes(spec: AutomatonSpec, functions: Mapping[str, Function]) -> dict[str, int]:
    sizes: dict[str, int] = {}
    for name, source in spec.signals.items():
        if len(source) > MAX_SOURCE_CHARS:
            continue  # refused with a position when the signal is parsed
        try:
            body = _ast_parse(source.strip()).body
        except (SyntaxError, ValueError, MemoryError, RecursionError):
            continue
        if isinstance(body, ast.Call) and isinstance(body.func, ast.Name):
            func = functions.get(body.func.id)
            if func is not None and func.outputs != 1:
                sizes[name] = func.outputs
    return sizes


def _signals(
    sources: Mapping[str, str],
    base: tuple[Any, ...],
    scope: Scope,
    problems: _Problems,
    sizes: Mapping[str, int],
) -> dict[str, ir.Expr]:
    """Parsed signal definitions; a vector signal's keeps the shape of its declaration."""
    definitions: dict[str, ir.Expr] = {}
    for name, source in sources.items():
        path = (*base, name)
        try:
            ascii_only(source)
            found = vector_call(source, scope)
        except ExprError as exc:
            problems.items.append((problems.positions.value(path).shifted(exc.col), exc.message))
            continue
        if found is not None:
            call, size = found
            if sizes.get(name) != size:
                problems.at_value(
                    path, f"signal '{name}' must keep the shape of its declaration in `signals`"
                )
            definitions[name] = call
        elif name in sizes:
            problems.at_value(
                path,
                f"signal '{name}' is declared as a vector of {sizes[name]} values; "
                "its override must be one too",
            )
        else:
            definitions[name] = problems.expression(path, source, scope, "number")
    return definitions


def _states(spec: AutomatonSpec, positions: PositionMap, problems: _Problems) -> list[StateVar]:
    states: list[StateVar] = []
    for name, var in spec.state.items():
        lower, upper = var.bounds if var.bounds is not None else (-math.inf, math.inf)
        if var.bounds is not None and lower > upper:
            problems.at_value(
                ("state", name, "bounds"), f"bounds of '{name}': low {lower} > high {upper}"
            )
        elif not lower <= var.initial <= upper:
            problems.at_value(
                ("state", name, "initial"),
                f"initial value {var.initial} of '{name}' is outside its bounds [{lower}, {upper}]",
            )
        if not math.isfinite(var.initial):
            problems.at_value(
                ("state", name, "initial"), f"initial value of '{name}' must be finite"
            )
        states.append(
            StateVar(name, var.initial, lower, upper, var.unit, positions.key(("state", name)))
        )
    return states


def _edges(
    spec: AutomatonSpec,
    positions: PositionMap,
    problems: _Problems,
    scope: Scope,
    state_names: list[str],
) -> list[Edge]:
    edges: list[Edge] = []
    locations = list(spec.locations)
    names: dict[str, int] = {}
    for i, edge in enumerate(spec.edges):
        base = ("edges", i)
        for key, loc in (("from", edge.source), ("to", edge.target)):
            if loc not in spec.locations:
                problems.at_value(
                    (*base, key), f"edge {key} unknown location '{loc}'{closest(loc, locations)}"
                )
        if edge.label is not None and edge.label not in spec.labels:
            problems.at_value(
                (*base, "label"),
                f"label '{edge.label}' is not declared in `labels`{closest(edge.label, list(spec.labels))}",
            )
        reset: dict[str, ir.Expr] = {}
        for var, source in edge.reset.items():
            if var not in spec.state:
                problems.at_key(
                    (*base, "reset", var),
                    f"reset of '{var}': not a state variable{closest(var, state_names)}",
                )
                continue
            reset[var] = problems.expression((*base, "reset", var), source, scope, "number")
        guard = problems.expression((*base, "guard"), edge.guard, scope, "bool")
        name = edge.name or f"{edge.source}->{edge.target}#{i}"
        if name in names:
            problems.at_value(
                (*base, "name") if edge.name else base,
                f"edge name '{name}' is used twice (first by edge {names[name]})",
            )
        names[name] = i
        edges.append(
            Edge(
                name=name,
                source=edge.source,
                target=edge.target,
                label=edge.label,
                guard=guard,
                reset=MappingProxyType(reset),
                priority=edge.priority,
                index=i,
                guard_source=edge.guard,
                position=positions.value(base),
                guard_position=positions.value((*base, "guard")),
            )
        )
    return edges


def _initial(
    spec: AutomatonSpec, problems: _Problems, state_names: list[str]
) -> tuple[str, dict[str, float]]:
    if spec.initial is None:
        return next(iter(spec.locations)), {}
    location = spec.initial.location
    if location not in spec.locations:
        problems.at_value(
            ("initial", "location"),
            f"initial location '{location}' is not a location{closest(location, list(spec.locations))}",
        )
    state: dict[str, float] = {}
    for var, value in spec.initial.state.items():
        if var not in spec.state:
            problems.at_key(
                ("initial", "state", var),
                f"initial value for '{var}': not a state variable{closest(var, state_names)}",
            )
        elif not math.isfinite(value):
            problems.at_value(("initial", "state", var), f"initial value of '{var}' must be finite")
        else:
            state[var] = value
    return location, state


def build_properties(
    spec: PropertiesSpec | None,
    positions: PositionMap,
    problems: list[tuple[Position, str]],
    locations: list[str],
) -> Properties:
    """Check that properties name existing locations (qualified in a system)."""
    if spec is None:
        return Properties()
    where: dict[str, Position] = {}
    for key in ("reachable", "unreachable"):
        for i, name in enumerate(getattr(spec, key)):
            path = ("properties", key, i)
            where[f"{key}:{name}"] = positions.value(path)
            if name not in locations:
                problems.append(
                    (
                        positions.value(path),
                        f"{key}: unknown location '{name}'{closest(name, locations)}",
                    )
                )
    for key in ("deadlock_free", "deterministic"):
        where[key] = positions.key(("properties", key))
    return Properties(
        reachable=tuple(spec.reachable),
        unreachable=tuple(spec.unreachable),
        deadlock_free=spec.deadlock_free,
        deterministic=spec.deterministic,
        positions=MappingProxyType(where),
    )
