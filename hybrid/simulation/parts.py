"""A product's modes assembled from its components' parts, each compiled once.

A run of many components visits many modes, each one location away from the
last. Compiling every mode whole (:meth:`CompiledModel._compile`) costs time
and memory in proportion to the number of components for every mode met, so N
components that switch in turn cost N² before the run has stepped at all.
Here a component in one location, together with the locations of the
components whose signals it reads (directly or through their signals), is a
*part*: its flows, signals, invariant and outgoing edges are compiled once.
A mode is its parts side by side: its right-hand side converts the state to
floats once and calls each part's flow (the same expressions in the same
order as the whole mode's function, so the same numbers); a new mode costs a
look-up per component.

Only for systems of :data:`PARTS_FROM` components or more that share no label
(a synchronised edge belongs to several components at once). A smaller
system's few modes are compiled whole: one function per mode evaluates faster
than a call per component.

Examples
--------
>>> import hybrid, numpy as np
>>> from hybrid.simulation.compiled import CompiledModel
>>> text = "automaton: a{i}\\nstate: {{x{i}: {{initial: 1}}}}\\nlocations: {{l: {{flow: {{x{i}: -x{i}}}}}}}\\n"
>>> system = hybrid.compose(*[hybrid.load_text(text.format(i=i)) for i in range(8)])
>>> compiled = CompiledModel(system)
>>> compiled.parts is not None
True
>>> [float(v) for v in compiled.mode(compiled.initial_key).rhs(0.0, np.arange(8.0))][:3]
[-0.0, -1.0, -2.0]
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from hybrid.compose import System
from hybrid.expr import ir
from hybrid.expr.codegen import EVALUATION_ERRORS, CodeContext, EvalFailure, compile_function
from hybrid.expr.dependencies import signals_read
from hybrid.expr.rho import guard_to_rho, level_key, levels
from hybrid.model import Automaton
from hybrid.modes import Binder, Mode, _single, mode_of
from hybrid.simulation.forms import (
    Assembly,
    CompiledCondition,
    CompiledMode,
    CompiledTransition,
    Fn,
    Part,
    Sitting,
    Source,
    sitting_form,
)

if TYPE_CHECKING:
    from hybrid.simulation.compiled import CompiledModel

__all__ = ["PARTS_FROM", "Part", "Parts", "signal_outputs", "uses_parts"]

PARTS_FROM = 8
"""Systems of this many components or more are compiled part by part."""

_ERRORS = EVALUATION_ERRORS  # an expression's failures, as the generated code catches them

FLOW = "rhs_parts"
"""A mode's right-hand side records its failures as ``rhs_parts_K`` (the K-th mode built)."""
SIGNALS = "out_parts"
"""A mode's signal outputs record their failures as ``out_parts_K``."""


def uses_parts(system: System) -> bool:
    """True if ``system``'s modes are assembled from parts."""
    return len(system.components) >= PARTS_FROM and not system.shared_labels


class Parts:
    """The parts of a compiled model's system and the modes assembled from them."""

    def __init__(self, compiled: CompiledModel, binder: Binder) -> None:
        self.compiled = compiled
        self.system = compiled.system
        self._bind = binder
        comps = self.system.components
        owner = {n: i for i, c in enumerate(comps) for n in c.automaton.signal_names}
        self.readers = [self._providers(i, owner) for i in range(len(comps))]
        self.dependents = [
            tuple(p for p, reads in enumerate(self.readers) if i in reads) for i in range(len(comps))
        ]
        """``dependents[i]``: the components whose part changes when ``i`` moves (``i`` too)."""
        self.state_slices = _slices([len(c.automaton.states) for c in comps])
        """Each component's entries of the state vector (its part's flow, in order)."""
        self.column_slices = _slices([len(_columns_of(c.automaton)) for c in comps])
        """Each component's signal columns (its part's signals, in order)."""
        # each component's locations as a system names them (``comp.loc``)
        self._named = [
            {loc: self.system.qualified(i, loc) for loc in c.automaton.locations}
            for i, c in enumerate(comps)
        ]
        # conditions by their expression and the definitions of the signals they read:
        # a component's guard reads the same in most of its parts
        self._conditions: dict[tuple[object, ...], tuple[ir.Expr, Fn]] = {}
        self._parts: dict[tuple[int, tuple[str, ...]], Part] = {}
        self._count = 0
        self._keys: list[Mode] = []  # the modes built, in order (their failures' names)
        # what a part's function computes: its role (said with the mode it fails in), its
        # expressions and context, and the mode it was first compiled for
        # (one expression as itself, not in a tuple: a large system keeps thousands)
        self._what: dict[str, tuple[str, ir.Expr | tuple[ir.Expr, ...], CodeContext, Mode]] = {}

    # --- which components a part depends on --------------------------------------------

    def _providers(self, i: int, owner: Mapping[str, int]) -> tuple[int, ...]:
        """``i`` and the components whose signals ``i`` reads, directly or through signals."""
        a = self.system.components[i].automaton
        exprs: list[ir.Expr] = [*a.signals.values()]
        for loc in a.locations.values():
            exprs += [*loc.flow.values(), *loc.signals.values(), loc.invariant]
        for edge in a.edges:
            exprs += [edge.guard, *edge.reset.values()]
        found = {i}
        todo = [owner[n] for e in exprs for n in _reads(e) if n in owner]
        while todo:
            p = todo.pop()
            if p in found:
                continue
            found.add(p)
            b = self.system.components[p].automaton
            defs = [*b.signals.values()]
            defs += [d for loc in b.locations.values() for d in loc.signals.values()]
            todo += [owner[n] for e in defs for n in _reads(e) if n in owner]
        return tuple(sorted(found))

    # --- modes --------------------------------------------------------------------------

    def mode(self, key: Mode, near: CompiledMode | None = None, moved: int = -1) -> CompiledMode:
        """Mode ``key``: its components' parts side by side.

        ``near``: a mode that differs from ``key`` only in the location of component
        ``moved``; the parts that do not read it are ``near``'s.
        """
        readers = self.readers
        if near is not None and near.assembly is not None and moved >= 0:
            parts = list(near.assembly.parts)
            for i in self.dependents[moved]:
                parts[i] = self._part(i, key, tuple(key[p] for p in readers[i]))
        else:
            parts = [self._part(i, key, tuple(key[p] for p in reads)) for i, reads in enumerate(readers)]
        flows = [p.flow for p in parts]
        outs = [p.signals for p in parts]
        n, m = len(self.compiled.state_names), len(self.compiled.columns)
        k = len(self._keys)
        self._keys.append(key)
        flow_where, signals_where = f"{FLOW}_{k}", f"{SIGNALS}_{k}"
        return CompiledMode(
            key,
            self._mode_name(key),
            _joined(flows, False, self.compiled.flow_failure, flow_where, n),
            _joined(outs, True, self.compiled.failure, signals_where, m),
            [c for p in parts for c in p.invariants],
            [tr for p in parts for tr in p.transitions],
            tuple(p.urgent for p in parts if p.urgent is not None),
            assembly=Assembly(tuple(parts), flow_where, signals_where),
        )

    def _mode_name(self, key: Mode) -> str:
        """``system.mode_name(key)``, from names made once."""
        return "|".join([named[loc] for named, loc in zip(self._named, key, strict=True)])

    def source(self, where: str, mode: Mode | None) -> Source | None:
        """What the function that recorded a failure as ``where`` computes, in ``mode``.

        Built only when a failure is described: a mode keeps no description.
        Without ``mode``, in the mode the function was first compiled for.
        """

        compiled = self.compiled
        kind, _, number = where.rpartition("_")
        whole = kind in (FLOW, SIGNALS) and number.isdigit() and int(number) < len(self._keys)
        if not whole and where not in self._what:
            return None
        described = self._what.get(where)
        if mode is None and whole:
            mode = self._keys[int(number)]
        elif mode is None:
            assert described is not None
            mode = described[3]
        name = self._mode_name(mode)
        if whole:
            view = mode_of(self.system, mode, binder=self._bind)
            ctx = CodeContext(
                states=compiled.state_names,
                signals=view.signals,
                inputs=compiled.inputs,
                functions=self.system.functions,
                failure=compiled.failure,
            )
            if kind == FLOW:
                flows = tuple(view.flow.get(s, _ZERO) for s in compiled.state_names)
                return Source(f"the flow of {name}", flows, ctx)
            return Source(f"the signals of {name}", tuple(signal_outputs(self.system)), ctx)
        assert described is not None
        what, exprs, ctx, _ = described
        exprs = exprs if isinstance(exprs, tuple) else (exprs,)
        return Source(f"{what} in {name}", exprs, ctx)

    def _part(self, i: int, key: Mode, at: tuple[str, ...]) -> Part:
        found = self._parts.get((i, at))
        if found is None:
            found = self._parts[(i, at)] = self._compile(i, key)
        return found

    def _name(self, prefix: str) -> str:
        self._count += 1
        return f"{prefix}_part{self._count}"

    def _compile(self, i: int, key: Mode) -> Part:

        system, compiled, bind = self.system, self.compiled, self._bind
        c = system.components[i]
        a = c.automaton
        loc_name = key[i]
        loc = a.locations[loc_name]
        signals: dict[str, ir.Expr] = {}
        for p in self.readers[i]:
            b = system.components[p].automaton
            here = b.locations[key[p]]
            for name in b.signal_names:
                signals[name] = bind(p, here.signals.get(name, b.signals[name]))
        ctx = CodeContext(
            states=compiled.state_names,
            signals=signals,
            inputs=compiled.inputs,
            functions=system.functions,
            failure=compiled.failure,
        )
        flows = [bind(i, loc.flow[s.name]) if s.name in loc.flow else _ZERO for s in a.states]
        flow_ctx = replace(ctx, failure=compiled.flow_failure)
        flow = compile_function(self._name("rhs"), flows, flow_ctx, shape="list", part=True)
        out = compile_function(self._name("out"), _columns_of(a), ctx, shape="list", part=True)
        invariants: list[CompiledCondition] = []
        if not (isinstance(loc.invariant, ir.BoolConst) and loc.invariant.value):
            where = system.qualified(i, loc_name)
            expr = bind(i, loc.invariant)
            what = f"the invariant of {where}"
            invariants.append(
                CompiledCondition(
                    where,
                    self._scalar("inv", what, expr, ctx, key),
                    self._scalar("invb", what, expr, ctx, key),
                    widen=self._widen(what, ctx, key),
                    expr=expr,
                )
            )
        transitions: list[CompiledTransition] = []
        for edge in sorted(a.outgoing(loc_name), key=lambda e: e.index):
            # its target depends on the mode: CompiledModel.target, from ``move``
            view = replace(_single(system, key, i, edge, True, bind), target=())
            what = f"the guard of {view.name}"
            differences = levels(view.guard)

            def variant(suffix: str, expr: ir.Expr, kind: str, what: str = what) -> Fn:
                return self._scalar(f"g{kind}", what, expr, ctx, key, as_is=True)

            transitions.append(
                CompiledTransition(
                    name=view.name,
                    rho=self._scalar("g", what, view.guard, ctx, key),
                    holds=self._scalar("gb", what, view.guard, ctx, key),
                    view=view,
                    reset=self._reset(view.name, view.reset, ctx, key),
                    levels=tuple(
                        self._scalar("lvl", what, d, ctx, key, as_is=True) for d in differences
                    ),
                    level_keys=tuple(level_key(d, [i]) for d in differences),
                    variant=variant if differences else None,
                    move=(i, edge.target),
                    widen=self._widen(what, ctx, key),
                    expr=view.guard,
                )
            )
        urgent = system.qualified(i, loc_name) if loc.urgent else None
        return Part(flow, out, invariants, transitions, urgent)

    def _scalar(
        self,
        prefix: str,
        what: str,
        expr: ir.Expr,
        ctx: CodeContext,
        key: Mode,
        as_is: bool = False,
    ) -> Fn:
        """A condition ``expr`` compiled: its rho for the prefixes ``inv`` and ``g``, else
        itself (or with ``as_is``); reused wherever it reads the same signal definitions."""
        reads = signals_read([expr], ctx.signals, _reads)
        cache = (prefix, what, id(expr), tuple((s, id(ctx.signals[s])) for s in reads))
        found = self._conditions.get(cache)
        if found is None or found[0] is not expr:
            name = self._name(prefix)
            value = guard_to_rho(expr) if prefix in ("inv", "g") and not as_is else expr
            self._what[name] = (what, value, ctx, key)
            found = (expr, compile_function(name, [value], ctx, shape="scalar"))
            self._conditions[cache] = found
        return found[1]

    def _widen(self, what: str, ctx: CodeContext, key: Mode) -> Callable[[ir.Expr], Sitting]:
        """Compiles a condition decided within a band (its sitting form) when first needed."""
        return _Widen(self, what, ctx, key)

    def sitting(self, what: str, ctx: CodeContext, key: Mode, expr: ir.Expr) -> Sitting:
        """The sitting form of condition ``expr`` (``what``), compiled now."""
        name = self._name("sit")
        self._what[name] = (what, expr, ctx, key)
        return sitting_form(name, expr, ctx)

    def _reset(self, tr: str, reset: Mapping[str, ir.Expr], ctx: CodeContext, key: Mode) -> Fn:
        """The reset, compiled when it first fires (most transitions never do).

        Only the variables it sets are computed; the others are copied, as the
        whole mode's reset copies them.
        """
        name = self._name("r")
        states = self.compiled.state_names
        self._what[name] = (f"the reset of {tr}", tuple(reset.values()), ctx, key)
        index = {s: k for k, s in enumerate(states)}
        where = tuple(index[s] for s in reset if s in index)
        assigned = tuple(e for s, e in reset.items() if s in index)
        return _Reset(name, where, assigned, ctx, len(states))


_ZERO = ir.Num(0.0)


def signal_outputs(system: System) -> list[ir.Expr]:
    """Every signal column of ``system`` as an expression, in column order."""
    return [column for c in system.components for column in _columns_of(c.automaton)]


def _columns_of(a: Automaton) -> list[ir.Expr]:
    """Automaton ``a``'s signal columns as expressions, in order (a vector signal has one
    per entry)."""
    sizes = a.vector_sizes
    found: list[ir.Expr] = []
    for name in a.signal_names:
        if name in sizes:
            found.extend(ir.Index(name, k) for k in range(sizes[name]))
        else:
            found.append(ir.Var(name, ir.SIGNAL))
    return found


def _slices(sizes: list[int]) -> list[slice]:
    """Consecutive slices of the given sizes, from 0."""
    ends = list(itertools.accumulate(sizes))
    return [slice(end - size, end) for size, end in zip(sizes, ends, strict=True)]


def _reads(expr: ir.Expr) -> set[str]:
    return ir.names_in(expr, ir.SIGNAL) | ir.names_in(expr, ir.INPUT)


# A run of many components meets many modes, each with its functions and the parts'
# callables below, and all of them are kept for the next run: as one object each (or a
# partial and its arguments), not a closure, its tuple and a cell a variable (6 to 13
# objects), they leave the cyclic collector fewer to count and follow.


def _joined(parts: list[Fn], as_tuple: bool, failure: EvalFailure, where: str, n: int) -> Fn:
    """One function of ``(t, x)``: the parts' values in order, the state converted once.

    A list, or a tuple with ``as_tuple``; on the first failure (recorded as
    ``where``) ``n`` NaNs, as the whole mode's function gives.
    """
    return functools.partial(_join, parts, as_tuple, failure, where, n)


def _join(
    parts: list[Fn], as_tuple: bool, failure: EvalFailure, where: str, n: int, t: float, x: Any
) -> Any:
    xs = x.tolist()
    out: list[Any] = []
    try:
        for part in parts:
            out += part(t, xs)
    except _ERRORS as e:  # the first failure ends the whole, as in one function
        failure.record(e, t, where)
        return (math.nan,) * n if as_tuple else [math.nan] * n
    return tuple(out) if as_tuple else out


class _Widen:
    """A condition's sitting form, compiled by its parts when first needed."""

    __slots__ = ("ctx", "key", "parts", "what")

    def __init__(self, parts: Parts, what: str, ctx: CodeContext, key: Mode) -> None:
        self.parts, self.what, self.ctx, self.key = parts, what, ctx, key

    def __call__(self, expr: ir.Expr) -> Sitting:
        return self.parts.sitting(self.what, self.ctx, self.key, expr)


class _Reset:
    """A part's reset: the variables it sets (at ``where``) computed, the others copied;
    compiled when it first fires, as ``name``."""

    __slots__ = ("assigned", "ctx", "function", "n", "name", "where")

    def __init__(
        self,
        name: str,
        where: tuple[int, ...],
        assigned: tuple[ir.Expr, ...],
        ctx: CodeContext,
        n: int,
    ) -> None:
        self.name, self.where, self.assigned, self.ctx, self.n = name, where, assigned, ctx, n
        self.function: Fn | None = None

    def __call__(self, t: float, x: Any) -> Any:
        function = self.function
        if function is None:
            function = self.function = compile_function(
                self.name, list(self.assigned), self.ctx, shape="list", part=True
            )
        xs = x.tolist()
        try:
            values = function(t, xs)
        except _ERRORS as e:
            self.ctx.failure.record(e, t, self.name)
            return [math.nan] * self.n
        for k, v in zip(self.where, values, strict=True):
            xs[k] = v
        return xs
