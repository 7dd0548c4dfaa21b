"""From the ``requirements:`` of a spec (automaton or system) to :class:`~hybrid.model.Requirement`.

Each requirement is checked with its position: one of ``always`` or
``eventually`` (not both), a boolean predicate in the scope of the file (in a
system file: every component's state variables and signals, by their plain
names), a window ``within: [a, b]`` with ``a`` finite and ``a <= b`` (``b`` may
be ``.inf``), an ``in:`` location that exists (``comp.loc`` in a system file),
and a name used once.

Examples
--------
>>> import hybrid
>>> heater = hybrid.load_text('''
... automaton: heater
... state: {x: {initial: 20.0}}
... locations: {cooling: {flow: {x: -0.1*x}}}
... requirements:
...   - {name: warm, always: "x >= 15", within: [0, 5]}
... ''')
>>> r = heater.requirements[0]
>>> r.name, r.kind, r.source, r.within, r.position.line
('warm', 'always', 'x >= 15', (0.0, 5.0), 6)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from hybrid.errors import Position
from hybrid.expr import ir
from hybrid.expr.parse import ExprError, Scope, parse_expression
from hybrid.model import Requirement
from hybrid.reader.characters import ascii_only
from hybrid.reader.messages import closest
from hybrid.reader.schema import RequirementSpec
from hybrid.reader.yamlpos import PositionMap

__all__ = ["KINDS", "build_requirements"]

KINDS = ("always", "eventually")
"""The temporal operators a requirement may use."""


def build_requirements(
    specs: Sequence[RequirementSpec],
    positions: PositionMap,
    scope: Scope,
    locations: Sequence[str],
    problems: list[tuple[Position, str]],
) -> tuple[Requirement, ...]:
    """The requirements of ``specs``; every problem is appended to ``problems``, with its place."""
    result: list[Requirement] = []
    first: dict[str, int] = {}
    for i, spec in enumerate(specs):
        base: tuple[Any, ...] = ("requirements", i)
        if spec.name in first:
            problems.append(
                (
                    positions.value((*base, "name")),
                    f"requirement name '{spec.name}' is used twice (first by requirement "
                    f"{first[spec.name]})",
                )
            )
        first.setdefault(spec.name, i)
        given = [k for k in KINDS if getattr(spec, k) is not None]
        if not given:
            problems.append(
                (
                    positions.value(base),
                    f"requirement '{spec.name}' needs `always:` or `eventually:` (a condition)",
                )
            )
            continue
        if len(given) > 1:
            problems.append(
                (
                    positions.key((*base, given[1])),
                    f"requirement '{spec.name}': give `always:` or `eventually:`, not both",
                )
            )
            continue
        kind = given[0]
        source: str = getattr(spec, kind)
        predicate = _predicate((*base, kind), source, scope, positions, problems)
        within = _window(spec, (*base, "within"), positions, problems)
        if spec.location is not None and spec.location not in locations:
            problems.append(
                (
                    positions.value((*base, "in")),
                    f"requirement '{spec.name}': unknown location '{spec.location}'"
                    f"{closest(spec.location, list(locations))}",
                )
            )
        result.append(
            Requirement(
                name=spec.name,
                kind=kind,
                predicate=predicate,
                source=source,
                within=within,
                location=spec.location,
                position=positions.value(base),
            )
        )
    return tuple(result)


def _predicate(
    path: tuple[Any, ...],
    source: str,
    scope: Scope,
    positions: PositionMap,
    problems: list[tuple[Position, str]],
) -> ir.Expr:
    try:
        ascii_only(source)
        return parse_expression(source, scope, want="bool")
    except ExprError as exc:
        problems.append((positions.value(path).shifted(exc.col), exc.message))
        return ir.BoolConst(True)


def _window(
    spec: RequirementSpec,
    path: tuple[Any, ...],
    positions: PositionMap,
    problems: list[tuple[Position, str]],
) -> tuple[float, float] | None:
    if spec.within is None:
        return None
    start, end = (float(v) for v in spec.within)
    if not math.isfinite(start) or math.isnan(end) or end == -math.inf:
        problems.append(
            (
                positions.value(path),
                f"requirement '{spec.name}': within [{start}, {end}] needs a finite start "
                "and an end that is a number or .inf",
            )
        )
        return None
    if start > end:
        problems.append(
            (
                positions.value(path),
                f"requirement '{spec.name}': within [{start}, {end}] starts after it ends",
            )
        )
        return None
    return (start, end)
