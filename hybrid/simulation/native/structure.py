"""What the compiled backend compiles: a model's structure, with parameters left as slots.

The counterpart of :class:`hybrid.simulation.compiled.CompiledModel` and of
:func:`hybrid.modes.mode_of`, except that parameters are *not* inlined: each
parameter of each component becomes a slot of the parameter vector ``p``
(``Var("#p3")`` in the IR, printed ``p[3]``), so the generated source depends
on the model's structure only, and a sweep over parameters or initial values
compiles once. A free input with a range, which the scipy backend holds at
its nominal value, is a slot too, after the parameters (:attr:`NativeModel.held`),
set to that value for each run.

Modes: every location of a plain automaton (so ``initial_location`` is a
run-time choice too); for a system, the modes reachable from its initial mode
through the transition graph (guards ignored), at most :data:`~hybrid.simulation.native.features.MAX_MODES`.

Guards keep the reference's equality rule (docs/semantics.md, "Equality
guards"): the atoms of each guard are :func:`hybrid.expr.rho.levels`' (the same
walk, so the same numbering), and the two rewritten forms the reference compiles
per pattern of signs or truths are generated once here with the pattern as
run-time slots: the *oriented* rho reads atom ``i`` as ``S_i * (a - b) <= 0``
and the *snapped* guard as ``Z_i <= 0``, with ``S_i = +-1`` and ``Z_i = -1`` (at
the level) or ``+1`` set by the compiled loop in slots after the parameters
(:func:`sign_name`, :func:`snap_name`; numbered per mode).

Examples
--------
>>> import hybrid
>>> from hybrid.compose import as_system
>>> model = NativeModel(as_system(hybrid.load("specs/bouncing_ball.yaml")))
>>> model.slot_names, [m.name for m in model.modes]
(('g', 'e'), ['falling'])
>>> from hybrid.expr.printer import expression_text
>>> expression_text(model.modes[0].transitions[0].reset["v"])
'-#p1 * v'
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, replace
from types import MappingProxyType
from typing import Any

from hybrid.compose import Component, System
from hybrid.expr import ir
from hybrid.expr.functions import BUILTINS, Function
from hybrid.expr.rho import _rewrite, guard_to_rho, levels
from hybrid.model import Automaton, Location
from hybrid.modes import Mode, TransitionView, mode_of, transitions_of
from hybrid.simulation.native.features import (
    MAX_MODES,
    no_compiled_form,
    refuse_unsupported,
    too_many_modes,
)

__all__ = [
    "COMPILED_FORM",
    "LEVEL_SIDE",
    "NativeMode",
    "NativeModel",
    "NativeTransition",
    "replace_levels",
    "sign_name",
    "slot_name",
    "snap_name",
    "structure_key",
]


COMPILED_FORM = "hybrid_compiled"
"""The attribute of a library function that holds its numba-compilable implementation."""


LEVEL_SIDE = "#level_side"
"""The internal function of an oriented atom: ``S * d``, or ``|d|`` where ``S`` is 0
(:func:`hybrid.simulation.native.mathlib.h_level_side`; ``#`` keeps it from any user's name)."""


def slot_name(k: int) -> str:
    """The IR name of parameter slot ``k`` (``#`` cannot start a user's name)."""
    return f"#p{k}"


def replace_levels(guard: ir.Expr, replacement: Callable[[int, ir.Expr, int], ir.Expr]) -> ir.Expr:
    """``guard`` with equality atom ``i`` replaced by ``replacement(i, a - b, column)``.

    The reference's own walk (:func:`hybrid.expr.rho.levels` numbers the atoms
    the same way), so a change of what counts as an atom reaches both backends.
    """
    return _rewrite(guard, replacement, True, [0])


def sign_name(a: int) -> str:
    """The IR name of the sign slot of level ``a`` of a mode (its oriented reading)."""
    return f"#s{a}"


def snap_name(a: int) -> str:
    """The IR name of the snap slot of level ``a`` of a mode (-1: at the level, +1: not)."""
    return f"#z{a}"


BAND_NAME = "#w"
"""The IR name of the band slot: the width a boolean form is decided within
(:func:`hybrid.expr.rho.within_band`; the kernel sets it before each call)."""


@dataclass(frozen=True)
class NativeTransition:
    """An outgoing transition: the reference view (names, target), its guard and levels.

    ``levels`` are the differences ``a - b`` of the guard's equality atoms, in
    :func:`hybrid.expr.rho.levels`' order.
    """

    view: TransitionView
    guard: ir.Expr
    reset: Mapping[str, ir.Expr]
    levels: tuple[ir.Expr, ...]

    def oriented_rho(self, first: int) -> ir.Expr:
        """Rho with atom ``i`` read as ``S_(first+i) * (a - b) <= 0``, or as ``a == b`` where
        ``S_(first+i)`` is 0 (``level_side``); the plain rho without levels (or all ``S`` 0)."""
        if not self.levels:
            return guard_to_rho(self.guard)

        def one_sided(index: int, difference: ir.Expr, col: int) -> ir.Expr:
            sign = ir.Var(sign_name(first + index), ir.PARAM, col)
            side = ir.Call(LEVEL_SIDE, (sign, difference), col)
            return ir.Cmp(("<=",), (side, ir.Num(0.0, col)), col)

        return guard_to_rho(replace_levels(self.guard, one_sided))

    def snapped(self, first: int) -> ir.Expr:
        """The guard with atom ``i`` read as ``Z_(first+i) <= 0`` (the guard itself without levels)."""
        if not self.levels:
            return self.guard

        def constant(index: int, difference: ir.Expr, col: int) -> ir.Expr:
            return ir.Cmp(("<=",), (ir.Var(snap_name(first + index), ir.PARAM, col), ir.Num(0.0, col)), col)

        return replace_levels(self.guard, constant)


@dataclass(frozen=True)
class NativeMode:
    """What is in force in one mode, parameters as slots."""

    key: Mode
    name: str
    flow: Mapping[str, ir.Expr]
    signals: Mapping[str, ir.Expr]
    invariants: tuple[tuple[str, ir.Expr], ...]
    transitions: tuple[NativeTransition, ...]
    urgent: tuple[str, ...] = ()
    """The urgent locations of the mode (qualified): no time may pass in it."""


class NativeModel:
    """The modes of ``model`` with parameter slots, and the slots' current values."""

    def __init__(self, model: System) -> None:
        self.system = model
        refuse_unsupported(self.system)
        slots: dict[tuple[int, str], int] = {}
        labels: list[str] = []
        values: list[float] = []
        for i, c in enumerate(self.system.components):
            for name, value in c.automaton.parameters.items():
                slots[(i, name)] = len(labels)
                labels.append(self.system.qualified(i, name))
                values.append(float(value))
        self.slots = slots
        self.slot_names = tuple(labels)
        """The parameters' slots, in order (``comp.name`` in a system)."""
        self.values = tuple(values)
        self.held = tuple(self.system.input_ranges())
        """The free inputs with a range, held at their nominal values: slots after the parameters."""
        self.n_slots = len(labels) + len(self.held)
        held = {name: slot_name(len(labels) + k) for k, name in enumerate(self.held)}
        self.renamed = _renamed_system(self.system, slots, held)
        self.state_names = self.system.state_names
        self.columns = self.system.signal_columns
        self.modes = [self._mode(key) for key in self._mode_keys()]
        self.index = {mode.key: i for i, mode in enumerate(self.modes)}
        self.functions = self._library_functions()

    def _mode_keys(self) -> list[Mode]:
        system = self.renamed
        if system.single:
            return [(name,) for name in system.components[0].automaton.locations]
        keys, seen = [system.initial_mode], {system.initial_mode}
        for key in keys:
            for tr in transitions_of(system, key, bind=False):
                if tr.target not in seen:
                    if len(keys) >= MAX_MODES:
                        raise too_many_modes(system.name)
                    seen.add(tr.target)
                    keys.append(tr.target)
        return keys

    def _mode(self, key: Mode) -> NativeMode:
        """:func:`hybrid.modes.mode_of` without binding parameters (slots stay names)."""
        view = mode_of(self.renamed, key, bind=False)
        return NativeMode(
            key=key,
            name=view.name,
            flow=view.flow,
            signals=view.signals,
            invariants=view.invariants,
            transitions=tuple(
                NativeTransition(tr, tr.guard, tr.reset, levels(tr.guard)) for tr in view.transitions
            ),
            urgent=view.urgent,
        )

    def expressions(self) -> Iterator[ir.Expr]:
        """Every expression the generated code evaluates."""
        for mode in self.modes:
            yield from mode.flow.values()
            yield from mode.signals.values()
            yield from (expr for _, expr in mode.invariants)
            for tr in mode.transitions:
                yield tr.guard
                yield from tr.reset.values()

    def _library_functions(self) -> dict[str, Function]:
        """The library functions the model calls; each must have a compiled form."""
        used: set[str] = set()
        for expr in self.expressions():
            used.update(
                n.func for n in ir.walk(expr) if isinstance(n, ir.Call) and n.func not in BUILTINS
            )
        functions = {}
        for name in sorted(used):
            function = self.system.functions[name]
            if getattr(function.fn, COMPILED_FORM, None) is None:
                raise no_compiled_form(self.system.name, name)
            functions[name] = function
        return functions

    def parameter_vector(self, model: Automaton | System) -> list[float]:
        """The slot values of ``model`` (this model, possibly with other parameter values):
        its parameters, then the nominal values of its held inputs."""
        automata = (
            (model,) if isinstance(model, Automaton) else tuple(c.automaton for c in model.components)
        )  # as_system(model)'s components, without building the system
        values = list(self.values)
        for (i, name), k in self.slots.items():
            values[k] = float(automata[i].parameters[name])
        if self.held:
            ranges = model.input_ranges()
            values += [float(ranges[name].nominal) for name in self.held]
        return values


def _rename(node: ir.Expr, names: Mapping[str, str], held: Mapping[str, str]) -> ir.Expr:
    """Every parameter and held input renamed to its slot (recursion is safe: depth is
    capped on parsing)."""
    if isinstance(node, ir.Var):
        if node.kind == ir.PARAM:
            return replace(node, name=names[node.name])
        if node.kind == ir.INPUT and node.name in held:
            return replace(node, name=held[node.name], kind=ir.PARAM)
        return node
    if isinstance(node, ir.Call):
        return replace(node, args=tuple(_rename(a, names, held) for a in node.args))
    if isinstance(node, ir.Unary | ir.Not):
        return replace(node, operand=_rename(node.operand, names, held))
    if isinstance(node, ir.Bin):
        return replace(node, left=_rename(node.left, names, held), right=_rename(node.right, names, held))
    if isinstance(node, ir.Cmp):
        return replace(node, operands=tuple(_rename(a, names, held) for a in node.operands))
    if isinstance(node, ir.BoolOp):
        return replace(node, values=tuple(_rename(a, names, held) for a in node.values))
    return node


def _renamed_system(
    system: System, slots: Mapping[tuple[int, str], int], held: Mapping[str, str]
) -> System:
    parts = []
    for i, c in enumerate(system.components):
        a = c.automaton
        names = {name: slot_name(slots[(i, name)]) for name in a.parameters}

        def ren(node: ir.Expr, names: Mapping[str, str] = names) -> ir.Expr:
            return _rename(node, names, held)

        locations = {
            name: _renamed_location(loc, ren) for name, loc in a.locations.items()
        }
        edges = tuple(
            replace(
                e,
                guard=ren(e.guard),
                reset=MappingProxyType({k: ren(v) for k, v in e.reset.items()}),
            )
            for e in a.edges
        )
        renamed = replace(
            a,
            parameters=MappingProxyType({names[n]: v for n, v in a.parameters.items()}),
            signals=MappingProxyType({k: ren(v) for k, v in a.signals.items()}),
            locations=MappingProxyType(locations),
            edges=edges,
        )
        parts.append(Component(c.name, renamed, c.position))
    return replace(system, components=tuple(parts))


def _renamed_location(loc: Location, ren: Callable[[ir.Expr], ir.Expr]) -> Location:
    return replace(
        loc,
        flow=MappingProxyType({k: ren(v) for k, v in loc.flow.items()}),
        signals=MappingProxyType({k: ren(v) for k, v in loc.signals.items()}),
        invariant=ren(loc.invariant),
    )


def structure_key(model: System) -> tuple[tuple[Any, ...], tuple[Any, ...]]:
    """``(key, objects)``: what identifies a model's structure, parameter and initial values aside.

    ``with_parameters`` and ``with_initial`` keep the locations, edges and
    signals objects, so the models of a sweep share one entry. The key holds
    their ids; a cache keyed by it holds the objects, so no other object can take an id.

    Examples
    --------
    >>> import hybrid
    >>> from hybrid.compose import as_system
    >>> ball = as_system(hybrid.load("specs/bouncing_ball.yaml"))
    >>> structure_key(ball)[0] == structure_key(ball.with_parameters({"g": 1.6}))[0]
    True
    """
    objects = tuple(
        (c.automaton.locations, c.automaton.edges, c.automaton.signals) for c in model.components
    )
    names = tuple((c.name, c.automaton.name) for c in model.components)
    single = model.single
    # the modes generated are those reachable from the initial one: another start is
    # another structure (with_initial keeps the locations objects)
    key = (model.name, single, names, model.initial_mode,
           tuple(id(o) for trio in objects for o in trio))  # fmt: skip
    return key, objects
