"""Parallel composition of automata into a system.

A :class:`System` puts automata side by side: state spaces concatenated (a name
used by two components is an error naming both places), each input bound to
the one other component that defines a signal of that name. What is in force in
each combination of locations is :mod:`hybrid.modes`.

Examples
--------
>>> import hybrid
>>> a = hybrid.load_text("automaton: a\\nstate: {x: {}}\\nlocations: {l: {flow: {x: 1}}}\\n")
>>> b = hybrid.load_text("automaton: b\\nstate: {y: {}}\\nlocations: {m: {flow: {y: 2}}}\\n")
>>> compose(a, b).state_names
('x', 'y')
"""

from __future__ import annotations

import re
import threading
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import PurePath
from types import MappingProxyType
from typing import Protocol

from hybrid.binding import input_problems, signal_cycle_problems
from hybrid.errors import Position, SpecError, UsageError, brief, did_you_mean
from hybrid.expr.functions import Function
from hybrid.model import (
    NAME,
    Automaton,
    Properties,
    Range,
    Requirement,
    StateVar,
    check_overrides,
)

__all__ = [
    "Component",
    "Model",
    "System",
    "as_system",
    "check_system",
    "compose",
    "expect_model",
]


class Model(Protocol):
    """What an :class:`~hybrid.model.Automaton` and a :class:`System` both are, stated once.

    A public entry point takes either (the type ``Automaton | System``), turns it
    into a system once with :func:`as_system` (an automaton is a system of one,
    whose locations keep their plain names), and everything below it takes a
    :class:`System`. Code that needs only these members reads them off either
    model as it is, without converting it.

    Examples
    --------
    >>> import hybrid
    >>> ball = hybrid.load("specs/bouncing_ball.yaml")
    >>> def start(model: Model) -> dict[str, float]:
    ...     return dict(zip(model.state_names, model.initial_vector()))
    >>> start(ball) == start(as_system(ball)) == {"h": 10.0, "v": 0.0}
    True
    """

    @property
    def name(self) -> str: ...
    @property
    def file(self) -> str: ...
    @property
    def position(self) -> Position: ...
    @property
    def description(self) -> str: ...
    @property
    def properties(self) -> Properties: ...
    @property
    def requirements(self) -> tuple[Requirement, ...]: ...
    @property
    def states(self) -> tuple[StateVar, ...]: ...
    @property
    def state_names(self) -> tuple[str, ...]: ...
    @property
    def signal_names(self) -> tuple[str, ...]: ...
    @property
    def labels(self) -> tuple[str, ...]: ...
    def initial_vector(self) -> list[float]:
        """The initial state, in the order of ``state_names``."""
    def initial_set(self) -> dict[str, Range]:
        """The initial set of every state variable."""
    def input_ranges(self) -> dict[str, Range]:
        """The declared range of every bounded free input."""
    def with_parameters(self, overrides: Mapping[str, float] | None) -> Model:
        """A copy with parameters replaced."""


@dataclass(frozen=True)
class Component:
    """One automaton inside a system, under its component name."""

    name: str
    automaton: Automaton
    position: Position = field(default_factory=lambda: Position("<spec>"))


@dataclass(frozen=True)
class System:
    """Automata composed in parallel (frozen).

    ``single`` marks the one-component system that stands for a plain
    automaton: its locations are shown unqualified.
    """

    name: str
    components: tuple[Component, ...]
    properties: Properties = field(default_factory=Properties)
    description: str = ""
    file: str = "<spec>"
    position: Position = field(default_factory=lambda: Position("<spec>"))
    single: bool = False
    requirements: tuple[Requirement, ...] = ()
    """The system file's own requirements (locations qualified); components keep theirs."""

    # --- facts of the composition, computed once -----------------------------------------

    @cached_property
    def states(self) -> tuple[StateVar, ...]:
        """Every state variable, component by component (the order of the state vector)."""
        return tuple(s for c in self.components for s in c.automaton.states)

    @cached_property
    def state_names(self) -> tuple[str, ...]:
        return tuple(s.name for s in self.states)

    @cached_property
    def signal_names(self) -> tuple[str, ...]:
        return tuple(n for c in self.components for n in c.automaton.signal_names)

    @cached_property
    def labels(self) -> tuple[str, ...]:
        """Every label, in order of first declaration."""
        return tuple(self.label_owners)

    @cached_property
    def label_owners(self) -> Mapping[str, tuple[int, ...]]:
        """Label -> indices of the components that declare it."""
        owners: dict[str, list[int]] = {}
        for i, c in enumerate(self.components):
            for label in c.automaton.labels:
                owners.setdefault(label, []).append(i)
        return MappingProxyType({k: tuple(v) for k, v in owners.items()})

    @cached_property
    def shared_labels(self) -> Mapping[str, tuple[int, ...]]:
        """Labels declared by several components (their edges fire together)."""
        return MappingProxyType({k: v for k, v in self.label_owners.items() if len(v) > 1})

    @cached_property
    def functions(self) -> Mapping[str, Function]:
        """The library functions the components use."""
        merged: dict[str, Function] = {}
        for c in self.components:
            merged.update(c.automaton.functions)
        return MappingProxyType(merged)

    @cached_property
    def signal_columns(self) -> tuple[str, ...]:
        """Trajectory columns of the signals: ``name``, or ``name[k]`` per value of a vector."""
        columns: list[str] = []
        for c in self.components:
            sizes = c.automaton.vector_sizes
            for name in c.automaton.signal_names:
                if name in sizes:
                    columns.extend(f"{name}[{k}]" for k in range(sizes[name]))
                else:
                    columns.append(name)
        return tuple(columns)

    @cached_property
    def initial_mode(self) -> tuple[str, ...]:
        """The initial location of each component (where a run starts)."""
        return tuple(c.automaton.initial_location for c in self.components)

    @cached_property
    def providers(self) -> Mapping[str, int]:
        """Signal and state variable names -> the index of the component that defines them."""
        found: dict[str, int] = {}
        for i, c in enumerate(self.components):
            for name in (*c.automaton.signal_names, *c.automaton.state_names):
                found.setdefault(name, i)
        return MappingProxyType(found)

    @cached_property
    def free_inputs(self) -> tuple[str, ...]:
        """Inputs no component provides (the system's own inputs), in order of declaration."""
        names = (n for c in self.components for n in c.automaton.inputs)
        return tuple(dict.fromkeys(n for n in names if n not in self.providers))

    @cached_property
    def state_vars(self) -> Mapping[str, StateVar]:
        """Every state variable by name."""
        return MappingProxyType({s.name: s for s in self.states})

    @cached_property
    def _input_ranges(self) -> Mapping[str, Range]:
        found: dict[str, Range] = {}
        free = set(self.free_inputs)
        for c in self.components:
            for name, r in c.automaton.input_ranges().items():
                if name in free:
                    found.setdefault(name, r)
        return MappingProxyType(found)

    def input_position(self, name: str) -> Position | None:
        """Where the free input ``name`` is declared (its first declaring component), if known."""
        for c in self.components:
            if name in c.automaton.inputs:
                return c.automaton.input_positions.get(name)
        return None

    def input_ranges(self) -> dict[str, Range]:
        """The declared range of every bounded free input (see :meth:`Automaton.input_ranges`)."""
        return dict(self._input_ranges)

    def initial_set(self) -> dict[str, Range]:
        """The initial set of every state variable, in state order (see :meth:`Automaton.initial_set`)."""
        return {k: r for c in self.components for k, r in c.automaton.initial_set().items()}

    def qualified(self, component: int, name: str) -> str:
        """A location, edge or parameter name as a user writes it: ``comp.name`` in a system.

        Examples
        --------
        >>> import hybrid
        >>> a = hybrid.load_text("automaton: a\\nlocations: {l: {}}\\n")
        >>> as_system(a).qualified(0, "l"), compose(a, names=["left"]).qualified(0, "l")
        ('l', 'left.l')
        """
        return name if self.single else f"{self.components[component].name}.{name}"

    def mode_name(self, mode: Sequence[str]) -> str:
        """``loc`` for a plain automaton, ``comp.loc|comp.loc`` for a system."""
        return "|".join(self.qualified(i, loc) for i, loc in enumerate(mode))

    def component(self, name: str) -> Component:
        for c in self.components:
            if c.name == name:
                return c
        raise KeyError(name)

    def initial_vector(self) -> list[float]:
        return [x for c in self.components for x in c.automaton.initial_vector()]

    def with_parameters(self, overrides: Mapping[str, float] | None) -> System:
        """A copy with parameters replaced: ``comp.name``, or ``name`` if only one has it.

        The system of one automaton (``single``) takes the names its automaton
        takes, with the automaton's messages: it stands for that automaton.
        """
        if not overrides:
            return self
        check_overrides(overrides, self.position)
        if self.single:
            (c,) = self.components
            return _replace_components(
                self, (Component(c.name, c.automaton.with_parameters(overrides), c.position),)
            )
        per: dict[str, dict[str, float]] = {c.name: {} for c in self.components}
        for key, value in overrides.items():
            comp, pname = _resolve_parameter(self, key)
            per[comp][pname] = value
        parts = tuple(
            Component(c.name, c.automaton.with_parameters(per[c.name]), c.position)
            for c in self.components
        )
        return _replace_components(self, parts)


def _replace_components(system: System, parts: tuple[Component, ...]) -> System:
    return replace(system, components=parts)


def _resolve_parameter(system: System, key: str) -> tuple[str, str]:
    if "." in key:
        comp, pname = key.split(".", 1)
        names = [c.name for c in system.components]
        if comp not in names:
            raise SpecError(
                f"unknown component '{comp}' in parameter '{key}'{did_you_mean(comp, names, 0.5)}",
                system.position,
            )
        if pname not in system.component(comp).automaton.parameters:
            params = list(system.component(comp).automaton.parameters)
            others = [f"{c.name}.{pname}" for c in system.components
                      if c.name != comp and pname in c.automaton.parameters]  # fmt: skip
            hint = (f"; did you mean '{others[0]}'?" if others
                    else did_you_mean(pname, params, 0.5) or f" (its parameters: {', '.join(params) or 'none'})")  # fmt: skip
            raise SpecError(f"component '{comp}' has no parameter '{pname}'{hint}", system.position)
        return comp, pname
    owners = [c.name for c in system.components if key in c.automaton.parameters]
    if len(owners) == 1:
        return owners[0], key
    if not owners:
        known = [
            system.qualified(i, p)
            for i, c in enumerate(system.components)
            for p in c.automaton.parameters
        ]
        known += [p for c in system.components for p in c.automaton.parameters]
        raise SpecError(
            f"no component has a parameter '{key}'{did_you_mean(key, known, 0.5)}",
            system.position,
        )
    raise SpecError(
        f"parameter '{key}' is ambiguous: write one of {', '.join(f'{o}.{key}' for o in owners)}",
        system.position,
    )


def expect_model(value: object, caller: str) -> None:
    """Raise a :class:`~hybrid.errors.UsageError` unless ``value`` is a model from :func:`hybrid.load`.

    ``caller`` names the public function (``"simulate"``): the message shows how
    to call it with a file's model.

    Examples
    --------
    >>> import hybrid
    >>> try:
    ...     expect_model("ball.yaml", "simulate")
    ... except hybrid.UsageError as error:
    ...     print(error)
    simulate() takes a model from hybrid.load(), not a file name: hybrid.simulate(hybrid.load('ball.yaml'), ...)
    """
    if isinstance(value, Automaton | System):
        return
    if isinstance(value, str | PurePath):
        raise UsageError(
            f"{caller}() takes a model from hybrid.load(), not a file name: "
            f"hybrid.{caller}(hybrid.load({str(value)!r}), ...)"
        )
    raise UsageError(
        f"{caller}() takes a model from hybrid.load() or hybrid.load_text(), "
        f"got {type(value).__name__}: {brief(value)}"
    )


def as_system(model: Automaton | System) -> System:
    """The system view of a model (an automaton is a system of one).

    Called once where a model enters (:func:`hybrid.simulate`, :func:`hybrid.sweep`
    and the other public functions); the same automaton gives the same system
    object, so the caches keyed by a model's identity (its compiled forms) keep
    working for runs of one automaton.

    Examples
    --------
    >>> import hybrid
    >>> ball = hybrid.load("specs/bouncing_ball.yaml")
    >>> system = as_system(ball)
    >>> system.single, system.mode_name(("falling",)), as_system(ball) is system
    (True, 'falling', True)
    """
    if isinstance(model, System):
        return model
    hit = _SYSTEMS.get(id(model))  # one lookup needs no lock; the updates below hold it
    if hit is not None and hit[0] is model:
        return hit[1]
    system = System(
        model.name,
        (Component(model.name, model, model.position),),
        model.properties,
        model.description,
        model.file,
        model.position,
        single=True,
    )
    with _SYSTEMS_LOCK:
        _SYSTEMS[id(model)] = (model, system)  # holds the automaton: no other object takes its id
        if len(_SYSTEMS) > _SYSTEMS_KEPT:
            _SYSTEMS.pop(next(iter(_SYSTEMS)))
    return system


_SYSTEMS: dict[int, tuple[Automaton, System]] = {}
_SYSTEMS_KEPT = 64
_SYSTEMS_LOCK = threading.Lock()


def compose(
    *automata: Automaton, name: str | None = None, names: Sequence[str] | None = None
) -> System:
    """Compose automata in parallel into a :class:`System`.

    Parameters
    ----------
    *automata : Automaton
        The components, in order (their order is the file order of their edges).
    name : str, optional
        The system's name (default: the component names joined by ``_``).
    names : sequence of str, optional
        Component names (default: each automaton's name).

    Raises
    ------
    SpecError
        If state variables or signals clash, or an input is bound to no signal
        or to several.

    Examples
    --------
    >>> import hybrid
    >>> a = hybrid.load_text("automaton: a\\nstate: {x: {}}\\nlocations: {l: {}}\\n")
    >>> b = hybrid.load_text("automaton: b\\nstate: {y: {}}\\nlocations: {m: {}}\\n")
    >>> hybrid.compose(a, b, names=["left", "right"]).state_names
    ('x', 'y')
    """
    for automaton in automata:
        if isinstance(automaton, System):
            raise UsageError(
                f"compose() takes automata; '{automaton.name}' is a system: compose the "
                "automata of its components"
            )
        expect_model(automaton, "compose")
    if not automata:
        raise SpecError("compose() needs at least one automaton")
    comp_names = _names_given(names, len(automata)) if names is not None else [a.name for a in automata]
    if name is not None:
        _check_name(name, "name")
    parts = tuple(Component(n, a, a.position) for n, a in zip(comp_names, automata, strict=True))
    system = System(name or "_".join(comp_names), parts)
    check_system(system)
    return system


_NAME = re.compile(NAME)


def _check_name(value: object, what: str) -> None:
    if not isinstance(value, str) or not _NAME.fullmatch(value):
        raise UsageError(
            f"{what} must be a name (an ASCII letter or _, then letters, digits or _), "
            f"got {value!r}"
        )


def _names_given(names: object, count: int) -> list[str]:
    """``compose``'s component names: one name per automaton."""
    if isinstance(names, str) or not isinstance(names, Sequence):
        raise UsageError(f"names must be a list of {count} names, got {names!r}")
    if len(names) != count:
        raise UsageError(f"names must give one name per automaton ({count}), got {len(names)}")
    for given in names:
        _check_name(given, "a component's name")
    return list(names)


def check_system(system: System) -> None:
    """Clashing names, unbound or ambiguous inputs: one :class:`SpecError` naming the places."""
    problems: list[tuple[Position, str]] = []
    seen_comp: dict[str, Position] = {}
    twice: set[str] = set()
    for c in system.components:
        if c.name in seen_comp:
            twice.add(c.name)
            first = seen_comp[c.name]
            also = f"line {first.line}" if first.file == c.position.file else str(first)
            problems.append(
                (
                    c.position,
                    f"component name '{c.name}' is used twice (also at {also}): give each "
                    "its own name (as: in a system file, names= in compose(); the "
                    "automaton's name is the default)",
                )
            )
        seen_comp[c.name] = c.position
    owner: dict[str, tuple[str, str, Position]] = {}
    for c in system.components:
        if c.name in twice:  # its names clash because it is there twice: said above
            continue
        a = c.automaton
        declared = [(s.name, "state variable", s.position) for s in a.states]
        declared += [(n, "signal", a.signal_positions.get(n, a.position)) for n in a.signal_names]
        for name, kind, pos in declared:
            if name in owner:
                other_comp, other_kind, other_pos = owner[name]
                problems.append(
                    (
                        pos,
                        f"'{name}' ({kind} of component '{c.name}') clashes with the {other_kind} "
                        f"of component '{other_comp}' at {other_pos}",
                    )
                )
            else:
                owner[name] = (c.name, kind, pos)
    problems.extend(signal_cycle_problems([(c.name, c.automaton) for c in system.components]))
    problems.extend(input_problems([(c.name, c.automaton) for c in system.components]))
    if problems:
        raise SpecError.many(problems)
