"""From a validated system spec and its loaded components to a :class:`~hybrid.compose.System`.

The component files are read by :mod:`hybrid.reader.loader`; this module
applies each component's overrides (parameters and initial location and state,
in the names of the component's own file), then its ``rename`` map
(:mod:`hybrid.binding`), checks the properties against the qualified location
names and composes the result. It reads no file.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

from hybrid.binding import rename, rename_problems
from hybrid.compose import Component, System, check_system
from hybrid.errors import SpecError
from hybrid.expr.parse import Scope
from hybrid.model import Automaton, Range
from hybrid.reader.problems import Problems
from hybrid.reader.requirements import build_requirements
from hybrid.reader.schema import ComponentSpec, SystemSpec
from hybrid.reader.sets import build_properties, initial_locations, start_value
from hybrid.reader.yamlpos import PositionMap

__all__ = ["build_system"]


def build_system(
    spec: SystemSpec, positions: PositionMap, automata: Sequence[Automaton | None]
) -> System:
    """Compose ``automata`` (one per component of ``spec``; ``None`` where loading failed).

    Raises one :class:`SpecError` with every problem found.
    """
    parts: list[Component] = []
    problems = Problems(positions)
    for i, (comp, model) in enumerate(zip(spec.components, automata, strict=True)):
        if model is None:
            continue
        where = positions.value(("components", i))
        base = ("components", i)
        try:
            model = model.with_parameters(comp.parameters)
        except SpecError as exc:
            problems.items.append((where, exc.message))
            continue
        model = _initial(comp, model, base, problems)
        if comp.rename:
            found = rename_problems(model, comp.rename)
            for old, part, message in found:
                path = (*base, "rename", old)
                (problems.at_key if part == "key" else problems.at_value)(path, message)
            if found:
                continue
            model = rename(model, comp.rename)
        parts.append(Component(comp.name or model.name, model, where))
    if problems.items:
        raise SpecError.many(problems.items)
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
    components = {c.name: list(c.automaton.locations) for c in parts}
    properties = build_properties(
        spec.properties,
        positions,
        problems.items,
        qualified,
        scope=_scope(system),
        components=components,
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
    requirements = build_requirements(
        spec.requirements, positions, _scope(system), qualified, problems.items
    )
    if problems.items:
        raise SpecError.many(problems.items)
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


def _initial(
    comp: ComponentSpec, model: Automaton, base: tuple[Any, ...], problems: Problems
) -> Automaton:
    """``model`` with the component's ``initial`` applied (its problems placed in the file)."""
    if comp.initial is None:
        return model
    before = len(problems.items)
    path = (*base, "initial")
    chosen = initial_locations(
        comp.initial.location or list(model.initial_locations),
        (*path, "location"),
        list(model.locations),
        problems,
    )
    state: dict[str, float | Range] = {}
    bounds = {s.name: s for s in model.states}
    for var, value in comp.initial.state.items():
        where = (*path, "state", var)
        s = bounds.get(var)
        if s is None:
            problems.at_key(
                where,
                f"initial value for '{var}': component '{comp.name or model.name}' has no "
                f"state variable '{var}' (in the names of its file: {', '.join(bounds)})",
            )
            continue
        found = start_value(problems, where, var, value, s.lower, s.upper)
        if found is not None:
            state[var] = found
    if len(problems.items) > before:
        return model
    return model.with_initial(chosen, state)


def _scope(system: System) -> Scope:
    """The names a system file's forbidden states and requirements may read: every
    state variable and signal, and the system's free inputs."""
    kinds: dict[str, str] = {}
    sizes: dict[str, int] = {}
    for c in system.components:
        a = c.automaton
        kinds.update(dict.fromkeys(a.state_names, "state"))
        kinds.update(dict.fromkeys(a.signal_names, "signal"))
        sizes.update(a.vector_sizes)
    kinds.update({n: "input" for n in system.free_inputs if n not in kinds})
    return Scope(variables=kinds, functions=system.functions, vectors=sizes)
