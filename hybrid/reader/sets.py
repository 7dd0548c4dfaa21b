"""The field's sets, read from a spec: initial sets, input ranges, initial locations,
and the properties (forbidden states included).

- ``state: {x: {initial: [lo, hi], nominal: v}}`` and ``initial: {state: {x: [lo, hi]}}``
  give initial sets (:class:`~hybrid.model.Range`); a run starts at ``nominal``,
  else at the midpoint;
- ``inputs: {u: {range: [lo, hi], nominal: v}}`` bounds a free input (the list
  form ``inputs: [u]`` declares unbounded ones);
- ``initial: {location: [a, b]}`` gives several initial locations;
- ``properties: {forbidden: [{location: a, when: "x >= 5"}, ...]}`` forbidden states.

Every problem is placed at its key or value in the file.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

from hybrid.errors import Position
from hybrid.expr.parse import Scope
from hybrid.model import Forbidden, Properties, Range, StateVar
from hybrid.reader.messages import closest
from hybrid.reader.problems import Problems
from hybrid.reader.schema import (
    AutomatonSpec,
    InitialSetSpec,
    InputSpec,
    PropertiesSpec,
)
from hybrid.reader.yamlpos import PositionMap

__all__ = [
    "build_initial",
    "build_properties",
    "build_states",
    "input_entries",
    "input_ranges",
    "start_value",
]

Path = tuple[Any, ...]


def _range(
    problems: Problems,
    path: Path,
    what: str,
    pair: tuple[float, float],
    nominal: float | None,
    nominal_path: Path | None,
) -> Range | None:
    lo, hi = float(pair[0]), float(pair[1])
    if not (math.isfinite(lo) and math.isfinite(hi)):
        problems.at_value(path, f"{what} [{lo}, {hi}] must be finite")
        return None
    if lo > hi:
        problems.at_value(path, f"{what} [{lo:g}, {hi:g}] is empty: low > high")
        return None
    if nominal is not None and not lo <= nominal <= hi:
        problems.at_value(
            nominal_path or path, f"nominal {nominal:g} is outside the {what} [{lo:g}, {hi:g}]"
        )
        return None
    return Range.of(lo, hi, nominal)


def start_value(
    problems: Problems,
    path: Path,
    name: str,
    value: float | tuple[float, float] | InitialSetSpec,
    lower: float = -math.inf,
    upper: float = math.inf,
) -> float | Range | None:
    """An initial value (a number) or set (a :class:`Range`), checked against the bounds."""
    what = f"initial set of '{name}'"
    if isinstance(value, InitialSetSpec):
        found = _range(
            problems, (*path, "initial"), what, value.initial, value.nominal, (*path, "nominal")
        )
    elif isinstance(value, tuple):
        found = _range(problems, path, what, value, None, None)
    else:
        number = float(value)
        if not math.isfinite(number):
            problems.at_value(path, f"initial value of '{name}' must be finite")
            return None
        if not lower <= number <= upper:
            problems.at_value(
                path,
                f"initial value {number} of '{name}' is outside its bounds [{lower}, {upper}]",
            )
            return None
        return number
    if found is not None and not (lower <= found.lo and found.hi <= upper):
        problems.at_value(
            path if not isinstance(value, InitialSetSpec) else (*path, "initial"),
            f"{what} {found.text()} is not inside its bounds [{lower}, {upper}]",
        )
        return None
    return found


def build_states(spec: AutomatonSpec, positions: PositionMap, problems: Problems) -> list[StateVar]:
    """The state variables, each with its start value and initial set."""
    states: list[StateVar] = []
    for name, var in spec.state.items():
        lower, upper = var.bounds if var.bounds is not None else (-math.inf, math.inf)
        path: Path = ("state", name, "initial")
        if var.bounds is not None and lower > upper:
            problems.at_value(
                ("state", name, "bounds"), f"bounds of '{name}': low {lower} > high {upper}"
            )
            lower, upper = -math.inf, math.inf
        found: float | Range | None
        if var.nominal is not None and not isinstance(var.initial, tuple):
            problems.at_key(
                ("state", name, "nominal"),
                f"'{name}' starts at one value: `nominal` goes with an initial set [low, high]",
            )
            found = None
        elif isinstance(var.initial, tuple):
            what = f"initial set of '{name}'"
            nominal_path = ("state", name, "nominal")
            found = _range(problems, path, what, var.initial, var.nominal, nominal_path)
            if found is not None and not (lower <= found.lo and found.hi <= upper):
                problems.at_value(
                    path, f"{what} {found.text()} is not inside its bounds [{lower}, {upper}]"
                )
                found = None
        else:
            found = start_value(problems, path, name, var.initial, lower, upper)
        start = found.nominal if isinstance(found, Range) else (found or 0.0)
        states.append(
            StateVar(
                name,
                start,
                lower,
                upper,
                var.unit,
                positions.key(("state", name)),
                found if isinstance(found, Range) and not found.is_point else None,
            )
        )
    return states


def input_entries(spec: AutomatonSpec) -> list[tuple[str, Path, bool]]:
    """``(name, path, at the key)`` of every declared input (the list form or the mapping)."""
    if isinstance(spec.inputs, dict):
        return [(name, ("inputs", name), True) for name in spec.inputs]
    return [(name, ("inputs", i), False) for i, name in enumerate(spec.inputs)]


def input_ranges(spec: AutomatonSpec, problems: Problems) -> dict[str, Range]:
    """The range of each bounded input (``inputs: {u: {range: [lo, hi]}}``)."""
    ranges: dict[str, Range] = {}
    if not isinstance(spec.inputs, dict):
        return ranges
    for name, entry in spec.inputs.items():
        assert isinstance(entry, InputSpec)
        if entry.range is None:
            if entry.nominal is not None:
                problems.at_key(
                    ("inputs", name, "nominal"),
                    f"input '{name}' has no range: give `range: [low, high]` with its nominal",
                )
            continue
        found = _range(
            problems,
            ("inputs", name, "range"),
            f"range of '{name}'",
            entry.range,
            entry.nominal,
            ("inputs", name, "nominal"),
        )
        if found is not None:
            ranges[name] = found
    return ranges


def build_initial(
    spec: AutomatonSpec, problems: Problems, states: Sequence[StateVar]
) -> tuple[tuple[str, ...], dict[str, float], dict[str, Range]]:
    """The initial locations, start values and initial sets that ``initial:`` overrides."""
    if spec.initial is None:
        return (next(iter(spec.locations)),), {}, {}
    chosen = initial_locations(
        spec.initial.location or next(iter(spec.locations)),
        ("initial", "location"),
        list(spec.locations),
        problems,
    )
    points: dict[str, float] = {}
    sets: dict[str, Range] = {}
    by_name = {s.name: s for s in states}
    for var, value in spec.initial.state.items():
        path: Path = ("initial", "state", var)
        if var not in by_name:
            problems.at_key(
                path,
                f"initial value for '{var}': not a state variable{closest(var, list(by_name))}",
            )
            continue
        s = by_name[var]
        found = start_value(problems, path, var, value, s.lower, s.upper)
        if isinstance(found, Range):
            points[var] = found.nominal
            sets[var] = found
        elif found is not None:
            points[var] = found
    return chosen, points, sets


def initial_locations(
    value: str | list[str], path: Path, locations: list[str], problems: Problems
) -> tuple[str, ...]:
    """The initial location(s), each checked to exist and named once."""
    names = [value] if isinstance(value, str) else list(value)
    seen: set[str] = set()
    for k, name in enumerate(names):
        where = path if isinstance(value, str) else (*path, k)
        if name not in locations:
            problems.at_value(
                where, f"initial location '{name}' is not a location{closest(name, locations)}"
            )
        elif name in seen:
            problems.at_value(where, f"initial location '{name}' is listed twice")
        seen.add(name)
    return tuple(names)


def build_properties(
    spec: PropertiesSpec | None,
    positions: PositionMap,
    problems: list[tuple[Position, str]],
    locations: list[str],
    *,
    scope: Scope | None = None,
    components: Mapping[str, list[str]] | None = None,
) -> Properties:
    """Check that properties name existing locations (qualified in a system).

    ``components`` (in a system) maps each component to its locations; ``scope``
    is where the ``when`` conditions of forbidden states are read (without it
    they are not parsed: the caller has no names to read them in).
    """
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
        positions=where,
        forbidden=_forbidden(spec, positions, problems, locations, scope, components),
    )


def _forbidden(
    spec: PropertiesSpec,
    positions: PositionMap,
    found: list[tuple[Position, str]],
    locations: list[str],
    scope: Scope | None,
    components: Mapping[str, list[str]] | None,
) -> tuple[Forbidden, ...]:
    problems = Problems(positions)
    entries: list[Forbidden] = []
    for i, entry in enumerate(spec.forbidden):
        base: Path = ("properties", "forbidden", i)
        chosen: dict[str, str] = {}
        if entry.location is not None and entry.locations is not None:
            problems.at_key((*base, "locations"), "give `location` or `locations`, not both")
        elif entry.location is not None:
            path = (*base, "location")
            if entry.location not in locations:
                qualified = [
                    f"{c}.{entry.location}"
                    for c, names in (components or {}).items()
                    if entry.location in names
                ]
                hint = (
                    f"; in a system write it qualified: '{qualified[0]}'"
                    if qualified
                    else closest(entry.location, locations)
                )
                problems.at_value(path, f"forbidden: unknown location '{entry.location}'{hint}")
            elif components is None:
                chosen[""] = entry.location
            else:
                comp, _, loc = entry.location.partition(".")
                chosen[comp] = loc
        elif entry.locations is not None:
            if components is None:
                problems.at_key(
                    (*base, "locations"),
                    "`locations` names a location per component of a system; in an automaton "
                    "write `location: name`",
                )
            else:
                for comp, loc in entry.locations.items():
                    if comp not in components:
                        problems.at_key(
                            (*base, "locations", comp),
                            f"forbidden: unknown component '{comp}'"
                            f"{closest(comp, list(components))}",
                        )
                    elif loc not in components[comp]:
                        problems.at_value(
                            (*base, "locations", comp),
                            f"forbidden: component '{comp}' has no location '{loc}'"
                            f"{closest(loc, components[comp])}",
                        )
                    else:
                        chosen[comp] = loc
        if entry.location is None and entry.locations is None and entry.when is None:
            problems.at_value(
                base, "a forbidden entry needs `location`, `locations` or a condition `when`"
            )
        when = None
        if entry.when is not None and scope is not None:
            when = problems.expression((*base, "when"), entry.when, scope, "bool")
        entries.append(Forbidden(chosen, when, entry.when or "", positions.value(base)))
    found.extend(problems.items)
    return tuple(entries)
