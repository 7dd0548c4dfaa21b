"""What the compiled backend compiles: a model's structure, with parameters left as slots.

The counterpart of :class:`hybrid.simulation.compiled.CompiledModel` and of
:func:`hybrid.modes.mode_of`, except that parameters are *not* inlined: each
parameter of each component becomes a slot of the parameter vector ``p``
(``Var("#p3")`` in the IR, printed ``p[3]``), so the generated source depends
on the model's structure only, and a sweep over parameters or initial values
compiles once.

Modes: every location of a plain automaton (so ``initial_location`` is a
run-time choice too); for a system, the modes reachable from its initial mode
through the transition graph (guards ignored), at most :data:`MAX_MODES`.

Guards are prepared for the announced equality rule: a conjunction of
``a >= b`` and ``a <= b`` (in any spelling, chains included) is the equality
``a == b`` (same truth, same rho), and each equality not under a ``not`` is a
*level* of its guard: the difference ``a - b`` (whose sign change means the
level is reached) and the guard with that equality taken as true.

Examples
--------
>>> import hybrid
>>> model = NativeModel(hybrid.load("specs/bouncing_ball.yaml"))
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

from hybrid.compose import Component, System, as_system
from hybrid.errors import UsageError
from hybrid.expr import ir
from hybrid.expr.functions import BUILTINS, Function
from hybrid.expr.printer import expression_text
from hybrid.model import Automaton, Location
from hybrid.modes import Mode, TransitionView, transitions_of

__all__ = [
    "COMPILED_FORM",
    "MAX_MODES",
    "Level",
    "NativeMode",
    "NativeModel",
    "NativeTransition",
    "levels_of",
    "merge_equalities",
    "slot_name",
]

MAX_MODES = 4096
"""Modes of a system the compiled backend generates code for; more is refused."""

COMPILED_FORM = "hybrid_compiled"
"""The attribute of a library function that holds its numba-compilable implementation."""


def slot_name(k: int) -> str:
    """The IR name of parameter slot ``k`` (``#`` cannot start a user's name)."""
    return f"#p{k}"


@dataclass(frozen=True)
class Level:
    """An equality ``a == b`` in a guard: ``difference = a - b`` and the guard with it true."""

    difference: ir.Expr
    relaxed: ir.Expr


@dataclass(frozen=True)
class NativeTransition:
    """An outgoing transition: the reference view (names, target) and its prepared guard."""

    view: TransitionView
    guard: ir.Expr
    reset: Mapping[str, ir.Expr]
    levels: tuple[Level, ...]


@dataclass(frozen=True)
class NativeMode:
    """What is in force in one mode, parameters as slots."""

    key: Mode
    name: str
    flow: Mapping[str, ir.Expr]
    signals: Mapping[str, ir.Expr]
    invariants: tuple[tuple[str, ir.Expr], ...]
    transitions: tuple[NativeTransition, ...]


class NativeModel:
    """The modes of ``model`` with parameter slots, and the slots' current values."""

    def __init__(self, model: Automaton | System) -> None:
        self.system = as_system(model)
        if self.system.single and self.system.components[0].automaton.inputs:
            name = self.system.components[0].automaton.inputs[0]
            raise UsageError(
                f"input '{name}' of {self.system.name} needs a value, and the compiled backend "
                "cannot take inputs given as Python functions: use backend='scipy' with "
                f"inputs={{'{name}': f}}, or compose the automaton with one that defines '{name}'"
            )
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
        self.values = tuple(values)
        self.renamed = _renamed_system(self.system, slots)
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
                        raise UsageError(
                            f"the compiled backend generates code for at most {MAX_MODES} modes; "
                            f"{system.name} has more (use backend='scipy')"
                        )
                    seen.add(tr.target)
                    keys.append(tr.target)
        return keys

    def _mode(self, key: Mode) -> NativeMode:
        """:func:`hybrid.modes.mode_of` without binding parameters."""
        system = self.renamed
        flow: dict[str, ir.Expr] = {}
        signals: dict[str, ir.Expr] = {}
        invariants: list[tuple[str, ir.Expr]] = []
        for i, (c, loc_name) in enumerate(zip(system.components, key, strict=True)):
            a = c.automaton
            loc = a.locations[loc_name]
            for name in a.signal_names:
                signals[name] = loc.signals.get(name, a.signals[name])
            flow.update(loc.flow)
            if not (isinstance(loc.invariant, ir.BoolConst) and loc.invariant.value):
                invariants.append((system.qualified(i, loc_name), loc.invariant))
        transitions = []
        for view in transitions_of(system, key, bind=False):
            guard = merge_equalities(view.guard)
            transitions.append(NativeTransition(view, guard, view.reset, levels_of(guard)))
        return NativeMode(
            key=key,
            name=system.mode_name(key),
            flow=MappingProxyType(flow),
            signals=MappingProxyType(signals),
            invariants=tuple(invariants),
            transitions=tuple(transitions),
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
                raise UsageError(
                    f"the compiled backend cannot run {self.system.name}: library function "
                    f"'{name}' has no compiled form (its library registers none; see "
                    "docs/backends.md), so use backend='scipy'"
                )
            functions[name] = function
        return functions

    def parameter_vector(self, model: Automaton | System) -> list[float]:
        """The slot values of ``model`` (this model, possibly with other parameter values)."""
        system = as_system(model)
        values = list(self.values)
        for (i, name), k in self.slots.items():
            values[k] = float(system.components[i].automaton.parameters[name])
        return values


def _rename(node: ir.Expr, names: Mapping[str, str]) -> ir.Expr:
    """Every parameter renamed to its slot (recursion is safe: depth is capped on parsing)."""
    if isinstance(node, ir.Var):
        return replace(node, name=names[node.name]) if node.kind == ir.PARAM else node
    if isinstance(node, ir.Call):
        return replace(node, args=tuple(_rename(a, names) for a in node.args))
    if isinstance(node, ir.Unary | ir.Not):
        return replace(node, operand=_rename(node.operand, names))
    if isinstance(node, ir.Bin):
        return replace(node, left=_rename(node.left, names), right=_rename(node.right, names))
    if isinstance(node, ir.Cmp):
        return replace(node, operands=tuple(_rename(a, names) for a in node.operands))
    if isinstance(node, ir.BoolOp):
        return replace(node, values=tuple(_rename(a, names) for a in node.values))
    return node


def _renamed_system(system: System, slots: Mapping[tuple[int, str], int]) -> System:
    parts = []
    for i, c in enumerate(system.components):
        a = c.automaton
        names = {name: slot_name(slots[(i, name)]) for name in a.parameters}

        def ren(node: ir.Expr, names: Mapping[str, str] = names) -> ir.Expr:
            return _rename(node, names)

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


def _conjuncts(node: ir.Expr) -> list[ir.Expr]:
    """The conjuncts of ``node``, chains split into single comparisons."""
    if isinstance(node, ir.BoolOp) and node.op == "and":
        return [c for v in node.values for c in _conjuncts(v)]
    if isinstance(node, ir.Cmp) and len(node.ops) > 1:
        return [
            ir.Cmp((op,), (node.operands[i], node.operands[i + 1]), node.col)
            for i, op in enumerate(node.ops)
        ]
    return [node]


def _as_le(node: ir.Expr) -> tuple[str, str, ir.Expr, ir.Expr] | None:
    """``(text of u, text of v, u, v)`` if ``node`` is ``u <= v`` (or ``v >= u``)."""
    if not (isinstance(node, ir.Cmp) and len(node.ops) == 1 and node.ops[0] in ("<=", ">=")):
        return None
    a, b = node.operands
    u, v = (a, b) if node.ops[0] == "<=" else (b, a)
    return expression_text(u), expression_text(v), u, v


def merge_equalities(node: ir.Expr) -> ir.Expr:
    """``a >= b and a <= b`` (any spelling) as ``a == b``; the rest unchanged."""
    if isinstance(node, ir.Not):
        return replace(node, operand=merge_equalities(node.operand))
    if isinstance(node, ir.BoolOp) and node.op == "or":
        return replace(node, values=tuple(merge_equalities(v) for v in node.values))
    parts = _conjuncts(node)
    if len(parts) < 2:
        return node
    parts = [merge_equalities(p) if isinstance(p, ir.BoolOp | ir.Not) else p for p in parts]
    used: set[int] = set()
    merged: list[ir.Expr] = []
    les = [_as_le(p) for p in parts]
    for i, le in enumerate(les):
        if i in used:
            continue
        partner = None
        if le is not None:
            for k in range(i + 1, len(les)):
                other = les[k]
                if k not in used and other is not None and (other[0], other[1]) == (le[1], le[0]):
                    partner = k
                    break
        if partner is None or le is None:
            merged.append(parts[i])
            continue
        used.update((i, partner))
        merged.append(ir.Cmp(("==",), (le[2], le[3]), parts[i].col))
    if len(merged) == len(parts):
        return node
    return merged[0] if len(merged) == 1 else ir.BoolOp("and", tuple(merged), node.col)


def _replace_node(node: ir.Expr, target: ir.Expr, by: ir.Expr) -> ir.Expr:
    if node == target:
        return by
    if isinstance(node, ir.Not):
        return replace(node, operand=_replace_node(node.operand, target, by))
    if isinstance(node, ir.BoolOp):
        return replace(node, values=tuple(_replace_node(v, target, by) for v in node.values))
    return node


def levels_of(guard: ir.Expr) -> tuple[Level, ...]:
    """The equality levels of a (merged) guard: those not under a ``not``."""
    found: list[ir.Expr] = []

    def visit(node: ir.Expr) -> None:
        if isinstance(node, ir.BoolOp):
            for v in node.values:
                visit(v)
        elif (
            isinstance(node, ir.Cmp)
            and node.ops == ("==",)
            and node not in found
        ):
            found.append(node)

    visit(guard)
    levels = []
    for atom in found:
        assert isinstance(atom, ir.Cmp)
        a, b = atom.operands
        relaxed = _replace_node(guard, atom, ir.BoolConst(True, atom.col))
        levels.append(Level(ir.Bin("-", a, b, atom.col), relaxed))
    return tuple(levels)
