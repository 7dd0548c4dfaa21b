"""The compiled, frozen hybrid automaton M = (L, X, A, W, E, Inv, Act).

Built from a validated spec by :mod:`hybrid.reader.build`; read (never changed)
by the simulator and the analysis. Expressions are held as checked IR;
parameters stay symbolic in the IR and are inlined when code is generated, so
overriding a parameter is cheap (:meth:`Automaton.with_parameters`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType

from hybrid.errors import Position, SpecError, did_you_mean
from hybrid.expr import ir
from hybrid.expr.functions import Function

__all__ = ["Automaton", "Edge", "Location", "Properties", "Requirement", "StateVar"]


def _frozen(mapping: Mapping[str, object] | None = None) -> Mapping[str, object]:
    return MappingProxyType(dict(mapping or {}))


@dataclass(frozen=True)
class StateVar:
    """A continuous state variable with its initial value and declared bounds."""

    name: str
    initial: float
    lower: float = -math.inf
    upper: float = math.inf
    unit: str | None = None
    position: Position = field(default_factory=lambda: Position("<spec>"))


@dataclass(frozen=True)
class Location:
    """A location: its flow (x' per state), local signal overrides and invariant."""

    name: str
    flow: Mapping[str, ir.Expr]
    signals: Mapping[str, ir.Expr]
    """Signal definitions that override the automaton's here (vector ones included)."""
    invariant: ir.Expr
    invariant_source: str = "true"
    position: Position = field(default_factory=lambda: Position("<spec>"))
    invariant_position: Position = field(default_factory=lambda: Position("<spec>"))


@dataclass(frozen=True)
class Edge:
    """A discrete transition with its guard, sparse reset and priority."""

    name: str
    source: str
    target: str
    label: str | None
    guard: ir.Expr
    reset: Mapping[str, ir.Expr]
    priority: int
    index: int
    guard_source: str = "true"
    position: Position = field(default_factory=lambda: Position("<spec>"))
    guard_position: Position = field(default_factory=lambda: Position("<spec>"))


@dataclass(frozen=True)
class Properties:
    """What `hybrid check` must prove about the automaton or system."""

    reachable: tuple[str, ...] = ()
    unreachable: tuple[str, ...] = ()
    deadlock_free: bool | None = None
    deterministic: bool | None = None
    positions: Mapping[str, Position] = field(default_factory=dict)
    ignore: tuple[str, ...] = ()
    """Rules `hybrid check` does not report for this file (its ``checks: {ignore: [...]}``)."""


@dataclass(frozen=True)
class Requirement:
    """A requirement on every simulated trajectory (monitored; it never changes the run).

    ``kind`` is ``always`` (the predicate holds at every point in scope) or
    ``eventually`` (at some point in scope). The scope is the run, cut to the
    time window ``within`` (absolute times, ends included) and, with
    ``location``, to the time spent there (qualified ``comp.loc`` in a system
    file's own requirements). Semantics: docs/semantics.md, "Requirements".
    """

    name: str
    kind: str
    predicate: ir.Expr
    source: str
    within: tuple[float, float] | None = None
    location: str | None = None
    position: Position = field(default_factory=lambda: Position("<spec>"))
    predicate_position: Position = field(default_factory=lambda: Position("<spec>"))


@dataclass(frozen=True)
class Automaton:
    """A hybrid automaton, frozen.

    Examples
    --------
    >>> import hybrid
    >>> ball = hybrid.load_text('''
    ... automaton: ball
    ... parameters: {g: 9.81}
    ... state: {h: {initial: 1.0}, v: {}}
    ... locations: {falling: {flow: {h: v, v: -g}}}
    ... ''')
    >>> ball.state_names, ball.initial_location
    (('h', 'v'), 'falling')
    >>> ball.with_parameters({"g": 1.62}).parameters["g"]
    1.62
    """

    name: str
    parameters: Mapping[str, float]
    states: tuple[StateVar, ...]
    signals: Mapping[str, ir.Expr]
    """Every signal's definition; a vector signal's is a call of a multi-output function."""
    vector_sizes: Mapping[str, int]
    """The number of values of each vector-valued signal (``name[k]``)."""
    signal_names: tuple[str, ...]
    inputs: tuple[str, ...]
    labels: tuple[str, ...]
    locations: Mapping[str, Location]
    edges: tuple[Edge, ...]
    initial_location: str
    initial_state: Mapping[str, float]
    properties: Properties = field(default_factory=Properties)
    functions: Mapping[str, Function] = field(default_factory=dict)
    description: str = ""
    file: str = "<spec>"
    position: Position = field(default_factory=lambda: Position("<spec>"))
    parameter_positions: Mapping[str, Position] = field(default_factory=dict)
    signal_positions: Mapping[str, Position] = field(default_factory=dict)
    input_positions: Mapping[str, Position] = field(default_factory=dict)
    label_positions: Mapping[str, Position] = field(default_factory=dict)
    requirements: tuple[Requirement, ...] = ()
    """Requirements on its trajectories (``requirements:``), in file order."""

    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.states)

    def outgoing(self, location: str) -> tuple[Edge, ...]:
        """Edges leaving ``location``, in file order."""
        return tuple(e for e in self.edges if e.source == location)

    def initial_vector(self) -> list[float]:
        """The initial state, in state order."""
        return [float(self.initial_state.get(s.name, s.initial)) for s in self.states]

    def with_parameters(self, overrides: Mapping[str, float] | None) -> Automaton:
        """A copy with some parameters replaced; unknown names are a :class:`SpecError`."""
        if not overrides:
            return self
        unknown = [k for k in overrides if k not in self.parameters]
        if unknown:
            name = unknown[0]
            raise SpecError(
                f"unknown parameter '{name}' for automaton '{self.name}'"
                f"{did_you_mean(name, self.parameters, 0.5)}",
                self.position,
            )
        merged = dict(self.parameters)
        for key, value in overrides.items():
            merged[key] = _as_float(key, value, self.position)
        return replace(self, parameters=_frozen(merged))  # type: ignore[arg-type]

    def with_initial(
        self, location: str | None = None, state: Mapping[str, float] | None = None
    ) -> Automaton:
        """A copy starting elsewhere: another location and/or some initial values."""
        result = self
        if location is not None:
            if location not in self.locations:
                raise SpecError(
                    f"unknown initial location '{location}'{did_you_mean(location, self.locations, 0.5)}",
                    self.position,
                )
            result = replace(result, initial_location=location)
        if state:
            names = set(self.state_names)
            merged = dict(result.initial_state)
            for key, value in state.items():
                if key not in names:
                    raise SpecError(
                        f"unknown state variable '{key}'{did_you_mean(key, names, 0.5)}",
                        self.position,
                    )
                merged[key] = _as_float(key, value, self.position)
            result = replace(result, initial_state=_frozen(merged))  # type: ignore[arg-type]
        return result


def _as_float(name: str, value: object, position: Position) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | str):
        raise SpecError(f"value of '{name}' must be a number, got {value!r}", position)
    try:
        return float(value)
    except ValueError:
        raise SpecError(f"value of '{name}' must be a number, got {value!r}", position) from None
