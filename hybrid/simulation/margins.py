"""The requirements of a model and their margins, compiled per mode.

A requirement's **margin** is the negative of its condition's rho
(:func:`hybrid.expr.rho.guard_to_rho`): ``margin(t, x) >= 0`` where the condition
holds, and its value is the usual robustness of signal temporal logic for an
atomic predicate (``x >= 15`` has margin ``x - 15``; ``and`` is the smaller of two
margins, ``or`` the larger, ``not`` the negation). It is compiled, like a guard,
once per mode in which the requirement is in scope (its ``in:`` location), with
the signal definitions in force there and the owning component's parameters
bound. Evaluation errors are recorded in :attr:`MarginTable.failure`, never in
the compiled model's own records: a requirement never changes the run.

Examples
--------
>>> import hybrid, numpy as np
>>> from hybrid.simulation.compiled import CompiledModel
>>> heater = hybrid.load_text('''
... automaton: heater
... state: {x: {initial: 20.0}}
... locations: {cooling: {flow: {x: -0.1*x}}}
... requirements: [{name: warm, always: "x >= 15"}]
... ''')
>>> compiled = CompiledModel(heater)
>>> table = MarginTable(compiled, watched_requirements(compiled.system))
>>> [(k, float(fn(0.0, np.array([20.0])))) for k, fn in table.of(compiled.mode(compiled.initial_key))]
[(0, 5.0)]
"""

from __future__ import annotations

import threading
import weakref
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from hybrid.compose import System
from hybrid.expr import ir
from hybrid.expr.codegen import CodeContext, EvalFailure, compile_function
from hybrid.expr.rho import guard_to_rho
from hybrid.model import Requirement
from hybrid.modes import Binder, Mode, mode_of
from hybrid.simulation.compiled import CompiledMode, CompiledModel, Source

__all__ = ["MarginTable", "Watched", "margin_table", "owners", "watched_requirements"]

Fn = Callable[[float, Any], Any]


@dataclass(frozen=True)
class Watched:
    """A requirement as the monitor of a system sees it.

    ``name`` is what results are reported under: the plain name in an automaton
    and for a system file's own requirements, ``comp.name`` for a component's
    requirement inside a system. ``component`` is the component whose
    parameters the condition reads (None for a system file's requirement);
    ``location`` is the ``in:`` location as ``(component index, location)``.
    """

    name: str
    requirement: Requirement
    component: int | None
    location: tuple[int, str] | None


def watched_requirements(system: System) -> list[Watched]:
    """Every requirement of ``system``: each component's (in order), then the system file's."""
    found: list[Watched] = []
    for i, c in enumerate(system.components):
        for r in c.automaton.requirements:
            where = (i, r.location) if r.location is not None else None
            found.append(Watched(system.qualified(i, r.name), r, i, where))
    names = [c.name for c in system.components]
    for r in system.requirements:
        where = None
        if r.location is not None:
            comp, _, loc = r.location.partition(".")
            where = (names.index(comp), loc)
        found.append(Watched(r.name, r, None, where))
    return found


def owners(system: System, watched: Watched) -> set[int]:
    """The components a requirement depends on: its own, or those owning what it reads."""
    if watched.component is not None:
        return {watched.component}
    read = ir.names_in(watched.requirement.predicate)
    found = {
        i
        for i, c in enumerate(system.components)
        if read & {*c.automaton.state_names, *c.automaton.signal_names}
    }
    if watched.location is not None:
        found.add(watched.location[0])
    return found


class MarginTable:
    """The margin function of each requirement in scope, per mode (compiled on first use)."""

    def __init__(self, compiled: CompiledModel, watched: Sequence[Watched]) -> None:
        self.compiled = compiled
        self.watched = list(watched)
        self.failure = EvalFailure()
        self._binder = Binder(compiled.system)
        self._modes: dict[Mode, list[tuple[int, Fn]]] = {}
        self._functions: dict[tuple[int, tuple[tuple[str, int], ...]], Fn] = {}

    def of(self, mode: CompiledMode) -> list[tuple[int, Fn]]:
        """``(requirement index, margin)`` of every requirement in scope in ``mode``."""
        found = self._modes.get(mode.key)
        if found is None:
            found = self._compile(mode)
            self._modes[mode.key] = found
        return found

    def _compile(self, mode: CompiledMode) -> list[tuple[int, Fn]]:
        system = self.compiled.system
        view = None
        found: list[tuple[int, Fn]] = []
        for k, w in enumerate(self.watched):
            if w.location is not None and mode.key[w.location[0]] != w.location[1]:
                continue
            if view is None:
                view = mode_of(system, mode.key, binder=self._binder)
            predicate = w.requirement.predicate
            if w.component is not None:
                predicate = self._binder(w.component, predicate)
            margin = ir.Unary("-", guard_to_rho(predicate))
            reads = _signals_read(margin, view.signals)
            key = (k, tuple((s, id(view.signals[s])) for s in reads))
            fn = self._functions.get(key)
            if fn is None:
                ctx = CodeContext(
                    states=self.compiled.state_names,
                    signals=view.signals,
                    inputs=self.compiled.inputs,
                    functions=system.functions,
                    failure=self.failure,
                )
                name = f"margin_{k}_{len(self._functions)}"
                fn = compile_function(name, [margin], ctx, shape="scalar")
                what = f"the condition of requirement '{w.name}'"
                self.compiled.sources[name] = Source(what, (margin,), ctx)
                self._functions[key] = fn
            found.append((k, fn))
        return found


def _signals_read(expr: ir.Expr, signals: Any) -> list[str]:
    """The signals ``expr`` reads, directly or through other signals, sorted."""
    seen: set[str] = set()
    todo = list(ir.names_in(expr))
    while todo:
        name = todo.pop()
        if name in seen or name not in signals:
            continue
        seen.add(name)
        todo.extend(ir.names_in(signals[name]))
    return sorted(seen)


_LOCK = threading.Lock()
_TABLES: weakref.WeakKeyDictionary[CompiledModel, MarginTable | None] = weakref.WeakKeyDictionary()


def margin_table(compiled: CompiledModel) -> MarginTable | None:
    """The margins of ``compiled``'s requirements (None without any), kept as long as it lives.

    The simulator reuses a compiled model across runs of the same model in a
    thread; its requirements' margins are compiled once with it.
    """
    with _LOCK:
        if compiled in _TABLES:
            return _TABLES[compiled]
        watched = watched_requirements(compiled.system)
        table = MarginTable(compiled, watched) if watched else None
        _TABLES[compiled] = table
        return table
