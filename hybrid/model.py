"""The compiled, frozen hybrid automaton M = (L, X, A, W, E, Inv, Act).

Built from a validated spec by :mod:`hybrid.reader.build`; read (never changed)
by the simulator and the analysis. Expressions are held as checked IR;
parameters stay symbolic in the IR and are inlined when code is generated, so
overriding a parameter is cheap (:meth:`Automaton.with_parameters`).
"""

from __future__ import annotations

import copyreg
import math
import numbers
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from types import MappingProxyType

from hybrid.errors import Position, SpecError, did_you_mean
from hybrid.expr import ir
from hybrid.expr.functions import Function

__all__ = [
    "NAME",
    "Automaton",
    "Edge",
    "Forbidden",
    "Location",
    "Properties",
    "Range",
    "Requirement",
    "StateVar",
    "check_overrides",
]

NAME = r"[A-Za-z_][A-Za-z0-9_]*"
"""A name in a spec (a state variable, a location, a component...): ASCII, as the
contract fixes it; ``.`` and ``|`` join names into qualified and product ones."""


def _frozen(mapping: Mapping[str, object] | None = None) -> Mapping[str, object]:
    return MappingProxyType(dict(mapping or {}))


def _read_only(items: dict[str, object]) -> MappingProxyType[str, object]:
    """A read-only view of ``items``: how a pickled ``MappingProxyType`` is rebuilt."""
    return MappingProxyType(items)


# Models keep their tables as read-only views, which pickle cannot take: a model could
# not go to another process (multiprocessing, concurrent.futures) nor be deep-copied.
# Pickle them as their contents (only pickling one, which failed before, is affected).
copyreg.pickle(MappingProxyType, lambda proxy: (_read_only, (dict(proxy),)))


@dataclass(frozen=True)
class Range:
    """A closed interval ``[lo, hi]`` and the point of it one run uses (``nominal``).

    An initial set of a state variable, or the range of a free input. ``given``
    says whether the spec wrote the nominal point (else it is the midpoint).

    Examples
    --------
    >>> r = Range.of(0.0, 2.0)
    >>> r.nominal, r.given, r.is_point, r.contains(2.0)
    (1.0, False, False, True)
    >>> Range.point(3.0)
    Range(lo=3.0, hi=3.0, nominal=3.0, given=True)
    """

    lo: float
    hi: float
    nominal: float
    given: bool = False

    @classmethod
    def of(cls, lo: float, hi: float, nominal: float | None = None) -> Range:
        """``[lo, hi]`` with ``nominal`` (default: the midpoint)."""
        if nominal is None:
            return cls(float(lo), float(hi), float(lo) + (float(hi) - float(lo)) / 2, False)
        return cls(float(lo), float(hi), float(nominal), True)

    @classmethod
    def point(cls, value: float) -> Range:
        """The one-point range ``[value, value]``."""
        return cls(float(value), float(value), float(value), True)

    @property
    def is_point(self) -> bool:
        return self.lo == self.hi

    def contains(self, value: float) -> bool:
        return self.lo <= value <= self.hi

    def text(self) -> str:
        """``[lo, hi]`` as a message writes it."""
        return f"[{self.lo:g}, {self.hi:g}]"


@dataclass(frozen=True)
class StateVar:
    """A continuous state variable with its initial value and declared bounds.

    ``initial`` is where a run starts; ``initial_range`` the initial set it is a
    point of (``None``: the single value ``initial``).
    """

    name: str
    initial: float
    lower: float = -math.inf
    upper: float = math.inf
    unit: str | None = None
    position: Position = field(default_factory=lambda: Position("<spec>"))
    initial_range: Range | None = None


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
    urgent: bool = False
    """No time may pass here: an edge must fire at once on entry, else the run is blocked."""
    flow_positions: Mapping[str, Position] = field(default_factory=dict)
    """Where each flow expression starts in the spec (for messages about one flow)."""


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
    reset_positions: Mapping[str, Position] = field(default_factory=dict)
    """Where each reset expression starts in the spec (for messages about one reset)."""


@dataclass(frozen=True)
class Forbidden:
    """A forbidden set of states: locations (per component) and a condition on the state.

    ``locations`` maps a component name to its location (``""`` stands for the
    automaton itself); components not named may be anywhere. ``when`` is the
    condition (``None``: any state there).
    """

    locations: Mapping[str, str]
    when: ir.Expr | None = None
    when_source: str = ""
    position: Position = field(default_factory=lambda: Position("<spec>"))

    def text(self) -> str:
        """The entry as a message names it: ``plant.overflow, ctrl.idle with x >= 5``."""
        where = ", ".join(f"{c}.{loc}" if c else loc for c, loc in self.locations.items())
        if self.when is None:
            return where or "any state"
        return f"{where} with {self.when_source}" if where else self.when_source


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
    forbidden: tuple[Forbidden, ...] = ()
    """States no run may reach (`properties.forbidden`)."""
    reach_t_end: float | None = None
    """The horizon of `hybrid reach` for `hybrid check` (``checks: {reach: {t_end}}``)."""
    reach_max_jumps: int | None = None
    """Its jump bound (``checks: {reach: {max_jumps}}``)."""
    reach_step: float | None = None
    """Its step (``checks: {reach: {step}}``)."""


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
    """Where a run starts (the first of :attr:`initial_locations`)."""
    initial_state: Mapping[str, float]
    """Start values that override the variables' own (``initial.state``)."""
    properties: Properties = field(default_factory=Properties)
    functions: Mapping[str, Function] = field(default_factory=dict)
    description: str = ""
    file: str = "<spec>"
    position: Position = field(default_factory=lambda: Position("<spec>"))
    parameter_positions: Mapping[str, Position] = field(default_factory=dict)
    signal_positions: Mapping[str, Position] = field(default_factory=dict)
    input_positions: Mapping[str, Position] = field(default_factory=dict)
    label_positions: Mapping[str, Position] = field(default_factory=dict)
    initial_locations: tuple[str, ...] = ()
    """Every initial location, :attr:`initial_location` first (filled in when left empty)."""
    initial_ranges: Mapping[str, Range] = field(default_factory=dict)
    """Initial sets that override the variables' own (``initial.state: {x: [lo, hi]}``)."""
    ranges: Mapping[str, Range] = field(default_factory=dict)
    """The declared range of each bounded input (``inputs: {u: {range: [lo, hi]}}``)."""
    requirements: tuple[Requirement, ...] = ()
    """Requirements on its trajectories (``requirements:``), in file order."""
    signal_units: Mapping[str, str] = field(default_factory=dict)
    """The ``unit:`` of each signal that declares one (``{expr: ..., unit: ...}``)."""

    def __post_init__(self) -> None:
        if not self.initial_locations or self.initial_locations[0] != self.initial_location:
            rest = tuple(n for n in self.initial_locations if n != self.initial_location)
            object.__setattr__(self, "initial_locations", (self.initial_location, *rest))

    @property
    def state_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.states)

    def outgoing(self, location: str) -> tuple[Edge, ...]:
        """Edges leaving ``location``, in file order."""
        return tuple(e for e in self.edges if e.source == location)

    def initial_vector(self) -> list[float]:
        """The initial state where a run starts (nominal points of sets), in state order."""
        return [float(self.initial_state.get(s.name, s.initial)) for s in self.states]

    def initial_set(self) -> dict[str, Range]:
        """The initial set: a :class:`Range` per state variable, in state order.

        A variable with a single initial value has a one-point range. ``nominal``
        is where :func:`hybrid.simulate` starts.

        Examples
        --------
        >>> import hybrid
        >>> m = hybrid.load_text('''
        ... automaton: a
        ... state: {x: {initial: [0, 2]}, y: {initial: 1}}
        ... locations: {l: {}}
        ... ''')
        >>> {k: (r.lo, r.hi, r.nominal) for k, r in m.initial_set().items()}
        {'x': (0.0, 2.0, 1.0), 'y': (1.0, 1.0, 1.0)}
        """
        result: dict[str, Range] = {}
        for s in self.states:
            if s.name in self.initial_ranges:
                result[s.name] = self.initial_ranges[s.name]
            elif s.name in self.initial_state:
                result[s.name] = Range.point(self.initial_state[s.name])
            elif s.initial_range is not None:
                result[s.name] = s.initial_range
            else:
                result[s.name] = Range.point(s.initial)
        return result

    def input_ranges(self) -> dict[str, Range]:
        """The declared range of every bounded input, in declaration order.

        Examples
        --------
        >>> import hybrid
        >>> m = hybrid.load_text('''
        ... automaton: a
        ... inputs: {u: {range: [-1, 1]}, w: {}}
        ... locations: {l: {}}
        ... ''')
        >>> m.input_ranges()
        {'u': Range(lo=-1.0, hi=1.0, nominal=0.0, given=False)}
        """
        return {name: self.ranges[name] for name in self.inputs if name in self.ranges}

    def with_parameters(self, overrides: Mapping[str, float] | None) -> Automaton:
        """A copy with some parameters replaced; unknown names are a :class:`SpecError`."""
        if not overrides:
            return self
        check_overrides(overrides, self.position)
        unknown = [k for k in overrides if k not in self.parameters]
        if unknown:
            name = unknown[0]
            raise SpecError(
                f"unknown parameter '{name}' for automaton '{self.name}'"
                f"{did_you_mean(name, self.parameters, 0.5) or _known('parameters', self.parameters)}",
                self.position,
            )
        merged = dict(self.parameters)
        for key, value in overrides.items():
            merged[key] = _as_float(key, value, self.position)
        return replace(self, parameters=_frozen(merged))  # type: ignore[arg-type]

    def with_initial(
        self,
        location: str | Sequence[str] | None = None,
        state: Mapping[str, float | Range] | None = None,
    ) -> Automaton:
        """A copy starting elsewhere: other initial location(s) and/or initial values or sets.

        A number is a single start value; a :class:`Range` an initial set (runs
        start at its nominal point).
        """
        result = self
        if location is not None:
            chosen = (location,) if isinstance(location, str) else tuple(location)
            for name in chosen:
                if name not in self.locations:
                    raise SpecError(
                        f"unknown initial location '{name}'"
                        f"{did_you_mean(name, self.locations, 0.5) or _known('locations', self.locations)}",
                        self.position,
                    )
            if not chosen:
                raise SpecError("at least one initial location is needed", self.position)
            result = replace(result, initial_location=chosen[0], initial_locations=chosen)
        if state:
            names = set(self.state_names)
            points = dict(result.initial_state)
            sets = dict(result.initial_ranges)
            for key, value in state.items():
                if key not in names:
                    raise SpecError(
                        f"unknown state variable '{key}'{did_you_mean(key, names, 0.5)}",
                        self.position,
                    )
                if isinstance(value, Range):
                    points[key] = value.nominal
                    sets[key] = value
                else:
                    points[key] = _as_float(key, value, self.position)
                    sets.pop(key, None)
            result = replace(
                result,
                initial_state=_frozen(points),  # type: ignore[arg-type]
                initial_ranges=_frozen(sets),  # type: ignore[arg-type]
            )
        return result


def check_overrides(overrides: object, position: Position) -> None:
    """Refuse parameter overrides that are not a mapping of names (a :class:`SpecError`, as an
    unknown name is): what :meth:`Automaton.with_parameters` is given."""
    if not isinstance(overrides, Mapping):
        raise SpecError(f"parameters must be a mapping of names to numbers, got {overrides!r}", position)
    for key in overrides:
        if not isinstance(key, str):
            raise SpecError(f"a parameter is named by a string, got {key!r}", position)


def _as_float(name: str, value: object, position: Position) -> float:
    """A parameter's new value: a finite number (NaN or infinite, every expression reading it
    would be), as the spec's own ``parameters:`` must be."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real | str):
        raise SpecError(f"value of '{name}' must be a number, got {value!r}", position)
    try:
        number = float(value)
    except ValueError:
        raise SpecError(f"value of '{name}' must be a number, got {value!r}", position) from None
    if not math.isfinite(number):
        raise SpecError(f"value of '{name}' must be a finite number, got {value!r}", position)
    return number


def _known(what: str, names: Iterable[str]) -> str:
    """`` (parameters: a, b)``, the names to choose from when none is close to the one given."""
    listed = list(names)
    if not listed:
        return f" (it has no {what})"
    shown = ", ".join(listed[:12]) + (f", ... ({len(listed)} in all)" if len(listed) > 12 else "")
    return f" ({what}: {shown})"
