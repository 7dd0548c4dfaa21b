"""From a validated system spec and its loaded components to a :class:`~hybrid.compose.System`.

The component files are read by :mod:`hybrid.reader.loader`; this module
applies each component's overrides, checks the properties against the
qualified location names and composes the result. It reads no file.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace

from hybrid.compose import Component, System, check_system
from hybrid.errors import Position, SpecError
from hybrid.expr.functions import Function
from hybrid.expr.parse import Scope
from hybrid.model import Automaton
from hybrid.reader.build import build_properties
from hybrid.reader.requirements import build_requirements
from hybrid.reader.schema import SystemSpec
from hybrid.reader.yamlpos import PositionMap

__all__ = ["build_system"]


def build_system(
    spec: SystemSpec, positions: PositionMap, automata: Sequence[Automaton | None]
) -> System:
    """Compose ``automata`` (one per component of ``spec``; ``None`` where loading failed).

    Raises one :class:`SpecError` with every problem found.
    """
    parts: list[Component] = []
    problems: list[tuple[Position, str]] = []
    for i, (comp, model) in enumerate(zip(spec.components, automata, strict=True)):
        if model is None:
            continue
        where = positions.value(("components", i))
        try:
            model = model.with_parameters(comp.parameters)
            if comp.initial is not None:
                model = model.with_initial(comp.initial.location, comp.initial.state)
        except SpecError as exc:
            problems.append((where, exc.message))
            continue
        parts.append(Component(comp.name or model.name, model, where))
    if problems:
        raise SpecError.many(problems)
    system = System(
        spec.system,
        tuple(parts),
        description=spec.description,
        file=positions.file,
        position=positions.value(()),
    )
    qualified = [
        system.qualified(i, loc) for i, c in enumerate(parts) for loc in c.automaton.locations
    ]
    properties = build_properties(spec.properties, positions, problems, qualified)
    if spec.checks is not None:
        properties = replace(properties, ignore=tuple(spec.checks.ignore))
    requirements = build_requirements(
        spec.requirements, positions, _system_scope(parts), qualified, problems
    )
    if problems:
        raise SpecError.many(problems)
    system = System(
        spec.system,
        tuple(parts),
        properties,
        spec.description,
        positions.file,
        positions.value(()),
        requirements=requirements,
    )
    check_system(system)
    return system


def _system_scope(parts: Sequence[Component]) -> Scope:
    """What a system file's requirements may read: every state variable and signal, by name."""
    kinds: dict[str, str] = {}
    functions: dict[str, Function] = {}
    vectors: dict[str, int] = {}
    for c in parts:
        a = c.automaton
        kinds.update(dict.fromkeys(a.state_names, "state"))
        kinds.update(dict.fromkeys(a.signal_names, "signal"))
        functions.update(a.functions)
        vectors.update(a.vector_sizes)
    return Scope(variables=kinds, functions=functions, vectors=vectors)
