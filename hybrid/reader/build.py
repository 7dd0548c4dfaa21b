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
    vector_call,
)
from hybrid.model import Automaton, Edge, Location
from hybrid.reader.characters import ascii_only
from hybrid.reader.messages import closest, derivative_hint
from hybrid.reader.problems import Problems
from hybrid.reader.requirements import build_requirements
from hybrid.reader.schema import AutomatonSpec, SignalSpec
from hybrid.reader.sets import (
    build_initial,
    build_properties,
    build_states,
    input_entries,
    input_ranges,
)
from hybrid.reader.yamlpos import PositionMap

__all__ = ["build_automaton", "build_properties"]  # build_properties: see sets.py

COLUMNS = {"j": "a run's column of hybrid time", "location": "a run's column of locations"}
"""Names a run's table gives its own columns (with ``t``): a state called so made two."""
RESERVED = {"t", "pi", "true", "false", *COLUMNS, *BUILTINS, *keyword.kwlist, *keyword.softkwlist}
_KIND_TEXT = {"param": "parameter", "state": "state variable", "signal": "signal", "input": "input"}


def build_automaton(spec: AutomatonSpec, positions: PositionMap) -> Automaton:
    """Check cross-references and expressions of ``spec``; raise one :class:`SpecError`."""
    problems = Problems(positions)
    functions = _libraries(spec, problems)
    if problems.items:  # every expression reading the library would be one more error
        raise SpecError.many(problems.items)
    kinds = _declare_names(spec, problems, functions)
    sizes = _vector_sizes(spec, functions)
    scope = Scope(variables=kinds, functions=functions, vectors=sizes)

    sources, paths, units = _signal_definitions(spec)
    signals = _signals(sources, ("signals",), scope, problems, sizes, paths)
    states = build_states(spec, positions, problems)
    state_names = [s.name for s in states]

    locations: dict[str, Location] = {}
    for lname, loc in spec.locations.items():
        base = ("locations", lname)
        flow: dict[str, ir.Expr] = {}
        for var, source in loc.flow.items():
            if var not in spec.state:
                problems.at_key(
                    (*base, "flow", var),
                    f"flow of '{var}': not a state variable"
                    + (
                        derivative_hint(var, state_names)
                        or _other_kind(var, spec, "a flow gives the rates of state variables")
                        or closest(var, state_names)
                    ),
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
            urgent=loc.urgent,
            flow_positions=MappingProxyType(
                {var: positions.value((*base, "flow", var)) for var in flow}
            ),
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
    initial_locations, initial_state, initial_ranges = build_initial(spec, problems, states)
    properties = build_properties(
        spec.properties, positions, problems.items, list(spec.locations), scope=scope
    )
    if spec.checks is not None:
        properties = replace(properties, ignore=tuple(spec.checks.ignore))
        if spec.checks.reach is not None:
            properties = replace(
                properties,
                reach_t_end=spec.checks.reach.t_end,
                reach_max_jumps=spec.checks.reach.max_jumps,
                reach_step=spec.checks.reach.step,
            )
    ranges = input_ranges(spec, problems)
    locs = list(spec.locations)
    requirements = build_requirements(spec.requirements, positions, scope, locs, problems.items)

    if problems.items:
        raise SpecError.many(problems.items)
    return Automaton(
        name=spec.automaton,
        parameters=MappingProxyType(dict(spec.parameters)),
        states=tuple(states),
        signals=MappingProxyType(signals),
        signal_units=MappingProxyType(units),
        vector_sizes=MappingProxyType(sizes),
        signal_names=tuple(spec.signals),
        inputs=tuple(name for name, _, _ in input_entries(spec)),
        labels=tuple(spec.labels),
        locations=MappingProxyType(locations),
        edges=tuple(edges),
        initial_location=initial_locations[0],
        initial_state=MappingProxyType(initial_state),
        initial_locations=initial_locations,
        initial_ranges=MappingProxyType(initial_ranges),
        ranges=MappingProxyType(ranges),
        properties=properties,
        functions=MappingProxyType(functions),
        description=spec.description,
        file=positions.file,
        position=positions.value(()),
        parameter_positions={k: positions.key(("parameters", k)) for k in spec.parameters},
        signal_positions={k: positions.key(("signals", k)) for k in spec.signals},
        input_positions={
            k: positions.key(path) if at_key else positions.value(path)
            for k, path, at_key in input_entries(spec)
        },
        label_positions={k: positions.value(("labels", i)) for i, k in enumerate(spec.labels)},
        requirements=requirements,
    )


def _other_kind(name: str, spec: AutomatonSpec, rule: str) -> str:
    """``: 'e' is a parameter (RULE)`` when ``name`` is declared as another kind, else ``""``."""
    for kind, names in (("a parameter", spec.parameters), ("a signal", spec.signals)):
        if name in names:
            return f": '{name}' is {kind} ({rule})"
    if name in {entry for entry, _, _ in input_entries(spec)}:
        return f": '{name}' is an input ({rule})"
    return ""


_LIBRARY_HINTS = {
    "uvms_model": "in the hybrid repository, pip install ./uvms_model (the UVMS case study's library)"
}
"""What to install for the function libraries our own specs use."""


def _libraries(spec: AutomatonSpec, problems: Problems) -> dict[str, Function]:
    functions: dict[str, Function] = {}
    for i, lib in enumerate(spec.uses):
        try:
            table = load_library(lib)
        except LookupError:
            installed = available_libraries()
            problems.at_value(
                ("uses", i),
                f"no installed package registers the function library '{lib}' "
                f"(entry-point group hybrid.functions; installed: {', '.join(installed) or 'none'})"
                f": {_LIBRARY_HINTS.get(lib, 'install the package that provides it')}",
            )
            continue
        except Exception as exc:  # a broken third-party package must not crash loading
            problems.at_value(("uses", i), f"function library '{lib}' failed to load: {exc}")
            continue
        functions.update(table)
    return functions


def _declare_names(
    spec: AutomatonSpec, problems: Problems, functions: Mapping[str, Function]
) -> dict[str, str]:
    kinds: dict[str, str] = {}
    first: dict[str, Position] = {}
    groups: list[tuple[str, list[tuple[str, tuple[Any, ...]]]]] = [
        ("param", [(n, ("parameters", n)) for n in spec.parameters]),
        ("state", [(n, ("state", n)) for n in spec.state]),
        ("signal", [(n, ("signals", n)) for n in spec.signals]),
        ("input", [(n, path) for n, path, _ in input_entries(spec)]),
    ]
    for kind, names in groups:
        for name, path in names:
            if name in RESERVED or name in functions:
                why = f" ({COLUMNS[name]})" if name in COLUMNS else ""
                problems.at_key(path, f"'{name}' is a reserved name{why}; choose another")
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


def _signal_definitions(
    spec: AutomatonSpec,
) -> tuple[dict[str, str], dict[str, tuple[Any, ...]], dict[str, str]]:
    """Each signal's expression source, the path of that source, and the declared units.

    A signal is ``name: expression`` or ``name: {expr: expression, unit: unit}``.
    """
    sources: dict[str, str] = {}
    paths: dict[str, tuple[Any, ...]] = {}
    units: dict[str, str] = {}
    for name, definition in spec.signals.items():
        if isinstance(definition, SignalSpec):
            sources[name], paths[name] = definition.expr, ("signals", name, "expr")
            if definition.unit:
                units[name] = definition.unit
        else:
            sources[name], paths[name] = definition, ("signals", name)
    return sources, paths, units


def _vector_sizes(spec: AutomatonSpec, functions: Mapping[str, Function]) -> dict[str, int]:
    sizes: dict[str, int] = {}
    for name, source in _signal_definitions(spec)[0].items():
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
    problems: Problems,
    sizes: Mapping[str, int],
    paths: Mapping[str, tuple[Any, ...]] | None = None,
) -> dict[str, ir.Expr]:
    """Parsed signal definitions; a vector signal's keeps the shape of its declaration."""
    definitions: dict[str, ir.Expr] = {}
    for name, source in sources.items():
        path = (paths or {}).get(name, (*base, name))
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


def _edges(
    spec: AutomatonSpec,
    positions: PositionMap,
    problems: Problems,
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
                    f"reset of '{var}': not a state variable"
                    + (
                        _other_kind(var, spec, "a reset sets state variables")
                        or closest(var, state_names)
                    ),
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
                reset_positions=MappingProxyType(
                    {var: positions.value((*base, "reset", var)) for var in reset}
                ),
            )
        )
    return edges
