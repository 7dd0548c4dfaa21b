"""The compiled model: per mode, the Python functions the simulator calls.

For a mode (one location per component) this compiles, once and lazily: the
right-hand side ``rhs(t, x) -> list`` (signals in dependency order, then every
derivative), the output function giving every signal column, and per
transition and invariant a ``rho`` (``<= 0`` iff it holds), a boolean ``holds``
and a reset. If the flow reads signals that call library functions, the
solver steps a second form of it, ``flow``, which keeps them for the invariants,
guards and outputs evaluated at the same point (the end of each step;
:class:`~hybrid.expr.codegen.Stash`).
A guard with equality atoms (docs/semantics.md, "Equality guards") also gets
the difference ``a - b`` of each atom (``levels``) and, compiled on first use,
its *oriented* rho (the atoms read one-sided) and its *snapped* forms (the
atoms replaced by constants).

A product meets the same expressions in many modes: each function is compiled
once, keyed by its expressions and the definitions of the signals and inputs it
reads (a system of many components: :mod:`~hybrid.simulation.parts`). What a
function computes is kept per mode (:meth:`CompiledModel.source`), so a
failure is described with the mode where it happened.

Evaluation errors (a math domain error, an overflow, a division by zero) never
raise: the function records them and returns NaN; the right-hand side into
:attr:`CompiledModel.flow_failure` (the solver tries it at trial points it may
reject: only fatal if the solver gives up), the rest into
:attr:`CompiledModel.failure`; :func:`~hybrid.simulation.failures.describe_failure`
words them.

Examples
--------
>>> import hybrid
>>> ball = hybrid.load("specs/bouncing_ball.yaml")
>>> from hybrid.compose import as_system
>>> compiled = CompiledModel(as_system(ball))
>>> mode = compiled.mode(compiled.initial_key)
>>> import numpy as np
>>> [float(v) for v in mode.rhs(0.0, np.array([10.0, 0.0]))]
[0.0, -9.81]
>>> bool(mode.transitions[0].rho(0.0, np.array([0.0, -1.0])) <= 0)
True
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import replace
from typing import Any

from hybrid.allocation import gc_paused
from hybrid.compose import System
from hybrid.errors import UsageError
from hybrid.expr import ir
from hybrid.expr.codegen import (
    CodeContext,
    EvalFailure,
    Stash,
    compile_function,
    reads_items,
    reads_library,
)
from hybrid.expr.dependencies import signals_read
from hybrid.expr.rho import guard_to_rho, level_key, levels
from hybrid.modes import Binder, Mode, ModeView, TransitionView, mode_of
from hybrid.simulation.forms import (
    CompiledCondition,
    CompiledMode,
    CompiledTransition,
    Fn,
    Sitting,
    Source,
    sitting_form,
)
from hybrid.simulation.parts import Parts, signal_outputs, uses_parts

__all__ = [
    "CompiledCondition",
    "CompiledMode",
    "CompiledModel",
    "CompiledTransition",
    "LatestFailure",
    "Source",
]

class LatestFailure(EvalFailure):
    """An :class:`EvalFailure` that keeps the latest failure, not the first.

    The solver retries the right-hand side at points ever closer to where the
    solution leaves the domain; the last try is the most telling.
    """

    def record(self, error: BaseException, t: float, where: str) -> None:
        self.error, self.t, self.where = error, t, where


class CompiledModel:
    """Lazily compiled modes of a model, with external inputs bound.

    ``inputs`` maps an automaton's declared input names to callables of ``t``
    (:meth:`bind_inputs` puts others in their place for the next run).
    ``failure`` records evaluation errors of conditions, signals and resets;
    ``flow_failure`` those of the right-hand side (see the module docstring).
    """

    def __init__(
        self,
        model: System,
        inputs: Mapping[str, Callable[[float], float]] | None = None,
    ) -> None:
        self.system = model
        self.failure = EvalFailure()
        self.flow_failure: EvalFailure = LatestFailure()
        self.terms_failure = EvalFailure()
        """Where a mode's ``terms`` record failures (read and cleared by the watch)."""
        self.running = False
        """A run is stepping it (``reuse.running``): it is not given other inputs then."""
        self.inputs: dict[str, list[Callable[[float], float]]] = {}
        """Each input's slot: item 0 is the callable the compiled functions read
        (:class:`~hybrid.expr.codegen.CodeContext`); :meth:`bind_inputs` fills them."""
        self.bind_inputs(inputs)
        self.state_names = self.system.state_names
        self.columns = self.system.signal_columns
        self.initial_key = self.system.initial_mode
        # what each function computes: by the name it records failures under, and per mode
        self.sources: dict[str, Source] = {}
        self._mode_sources: dict[tuple[Mode, str], Source] = {}
        self._modes: dict[Mode, CompiledMode] = {}
        # a guard, invariant or reset met in many modes is bound and compiled once
        self._binder = Binder(self.system)
        self._functions: dict[tuple[object, ...], tuple[tuple[object, str], Fn]] = {}
        self._rhos: dict[int, tuple[ir.Expr, ir.Expr]] = {}
        self._reads: dict[int, tuple[ir.Expr, frozenset[str]]] = {}
        self._zero = ir.Num(0.0)  # the flow of a state variable a location leaves alone
        self.stash_slot: list[Any] = [None]
        """Where the stepped flow keeps its signals (read by :mod:`~hybrid.simulation.recorder`)."""
        self._stashes: dict[int, Stash] = {}
        self.parts = Parts(self, self._binder) if uses_parts(self.system) else None

    def _external_inputs(self) -> list[str]:
        return list(self.system.free_inputs)

    def bind_inputs(self, inputs: Mapping[str, Callable[[float], float]] | None) -> None:
        """Put ``inputs`` in the slots the compiled functions read: the next run reads them.

        Every declared input needs one; a :class:`UsageError` (the slots unchanged)
        if one is missing or a name is not a declared input.
        """
        given = {name: _numeric(fn, name) for name, fn in (inputs or {}).items()}
        external = self._external_inputs()
        missing = [n for n in external if n not in given]
        if missing:
            raise UsageError(
                f"input '{missing[0]}' needs a value: pass inputs={{'{missing[0]}': f}} "
                "with f a function of t",
                at=self.system.input_position(missing[0]),
            )
        unknown = [n for n in given if n not in external]
        if unknown:
            raise UsageError(
                f"'{unknown[0]}' is not a declared input of {self.system.name} "
                f"(inputs: {', '.join(external) or 'none'})"
            )
        for name, fn in given.items():
            self.inputs.setdefault(name, [fn])[0] = fn

    def mode(self, key: Mode) -> CompiledMode:
        """The compiled mode ``key`` (compiled on first use, then cached).

        Compiling allocates many small objects and keeps most of them (as loading a
        model does): the cyclic collector is paused meanwhile
        (:func:`~hybrid.allocation.gc_paused`), so that its passes, full ones among
        them, do not walk the process's objects again and again while the run
        compiles the modes it meets.
        """
        compiled = self._modes.get(key)
        if compiled is None:
            with gc_paused():
                if self.parts is not None:
                    compiled = self.parts.mode(key)
                else:
                    compiled = self._compile(mode_of(self.system, key, binder=self._binder))
            self._modes[key] = compiled
        return compiled

    def target(self, mode: CompiledMode, tr: CompiledTransition) -> CompiledMode:
        """The compiled mode ``tr`` leads to from ``mode`` (compiled as :meth:`mode` does)."""
        if tr.move is None:
            return self.mode(tr.view.target)
        i, location = tr.move
        key = (*mode.key[:i], location, *mode.key[i + 1 :])
        found = self._modes.get(key)
        if found is None and self.parts is not None:  # built from ``mode``'s parts
            with gc_paused():
                found = self._modes[key] = self.parts.mode(key, mode, i)
        return found if found is not None else self.mode(key)

    def _rho(self, cond: ir.Expr) -> ir.Expr:
        """``guard_to_rho(cond)``, the same object each time ``cond`` is met again."""
        found = self._rhos.get(id(cond))
        if found is None or found[0] is not cond:
            found = (cond, guard_to_rho(cond))
            self._rhos[id(cond)] = found
        return found[1]

    def source(self, where: str, mode: Mode | None = None) -> Source | None:
        """What the function that recorded a failure as ``where`` computes, in ``mode``.

        A function reused across modes records failures under the name it was first
        compiled with; ``mode`` (where the failure happened) picks that mode's words.
        """
        if self.parts is not None and (found := self.parts.source(where, mode)) is not None:
            return found
        found = self._mode_sources.get((mode, where)) if mode is not None else None
        return found if found is not None else self.sources.get(where)

    def _function(
        self,
        name: str,
        role: str,
        what: str,
        exprs: list[ir.Expr],
        ctx: CodeContext,
        mode: Mode,
        **kwargs: Any,
    ) -> Fn:
        """``exprs`` compiled as ``name`` (or reused); ``role`` and the expressions key the reuse."""
        signals = self._signals_read(exprs, ctx.signals)
        key = (
            role,
            kwargs.get("shape"),
            ctx.failure is self.flow_failure,
            tuple(id(e) for e in exprs),
            tuple((s, id(ctx.signals[s])) for s in signals),
        )
        found = self._functions.get(key)
        source = Source(what, tuple(exprs), ctx)
        if found is None:
            self.sources[name] = source
            keep = (exprs, [ctx.signals[s] for s in signals])  # the ids in the key stay valid
            found = ((keep, name), compile_function(name, exprs, ctx, **kwargs))
            self._functions[key] = found
        self._mode_sources[(mode, found[0][1])] = source
        return found[1]

    def _widen(
        self, name: str, what: str, ctx: CodeContext, mode: Mode
    ) -> Callable[[ir.Expr], Sitting]:
        """Compiles a condition decided within a band (its sitting form) when first needed."""
        count = [0]

        def widen(expr: ir.Expr) -> Sitting:
            count[0] += 1
            full = f"{name}_{count[0]}"
            source = Source(what, (expr,), ctx)
            self.sources[full] = source
            self._mode_sources[(mode, full)] = source
            return sitting_form(full, expr, ctx)

        return widen

    def _reset(
        self, name: str, tr: TransitionView, ctx: CodeContext, what: str, mode: Mode
    ) -> Fn:
        """The reset of ``tr``, compiled when it first fires (most transitions never do)."""
        exprs = list(tr.reset.values())
        signals = self._signals_read(exprs, ctx.signals)
        key = (
            "reset",
            tr.name,
            tuple((k, id(v)) for k, v in tr.reset.items()),
            tuple((s, id(ctx.signals[s])) for s in signals),
        )
        found = self._functions.get(key)
        if found is None:
            compiled: list[Fn] = []

            def reset(t: float, x: Any) -> Any:
                if not compiled:
                    reset_of = [tr.reset.get(s) for s in self.state_names]
                    compiled.append(compile_function(name, exprs, ctx, reset_of=reset_of))
                return compiled[0](t, x)

            self.sources[name] = Source(what, tuple(exprs), ctx)
            found = (((exprs, [ctx.signals[s] for s in signals]), name), reset)
            self._functions[key] = found
        self._mode_sources[(mode, found[0][1])] = Source(what, tuple(exprs), ctx)
        return found[1]

    def _signals_read(self, exprs: list[ir.Expr], signals: Mapping[str, ir.Expr]) -> list[str]:
        """The signals ``exprs`` read, directly or through other signals, sorted."""
        return signals_read(exprs, signals, self._reads_of)

    def _reads_of(self, expr: ir.Expr) -> frozenset[str]:
        found = self._reads.get(id(expr))
        if found is None or found[0] is not expr:
            # an input of a component reads the signal another component defines
            found = (expr, frozenset(ir.names_in(expr, ir.SIGNAL) | ir.names_in(expr, ir.INPUT)))
            self._reads[id(expr)] = found
        return found[1]

    def _compile(self, view: ModeView) -> CompiledMode:
        ctx = CodeContext(
            states=self.state_names,
            signals=view.signals,
            inputs=self.inputs,
            functions=self.system.functions,
            failure=self.failure,
        )
        tag = _identifier(view.name)
        key = view.key
        # in a system, what a guard, invariant or reset computes is said with its mode
        within = "" if self.system.single else f" in {view.name}"
        flows = [view.flow.get(s, self._zero) for s in self.state_names]
        rhs = self._function(
            f"rhs_{tag}",
            "flow",
            f"the flow of {view.name}",
            flows,
            replace(ctx, failure=self.flow_failure),
            key,
            shape="list",
        )
        flow: Fn | None = None
        share: Stash | None = None
        if reads_library(flows, ctx):
            stash = Stash(self.stash_slot)
            flow = self._function(
                f"flow_{tag}",
                "stepped flow",
                f"the flow of {view.name}",
                flows,
                replace(ctx, failure=self.flow_failure),
                key,
                shape="list",
                stash=stash,
                steady=frozenset(
                    s
                    for s, e in zip(self.state_names, flows, strict=True)
                    if isinstance(e, ir.Num) and e.value == 0.0
                ),
            )
            share = self._stashes.setdefault(id(flow), stash)
        outputs_ir = signal_outputs(self.system)
        outputs = self._function(
            f"out_{tag}",
            "signals",
            f"the signals of {view.name}",
            outputs_ir,
            ctx,
            key,
            shape="tuple",
            share=share,
        )
        invariants = []
        for i, (name, expr) in enumerate(view.invariants):
            what = f"the invariant of {name}{within}"
            role = f"invariant {name}"
            invariants.append(
                CompiledCondition(
                    name,
                    self._function(
                        f"inv_{tag}_{i}",
                        role,
                        what,
                        [self._rho(expr)],
                        ctx,
                        key,
                        shape="scalar",
                        share=share,
                    ),
                    self._function(
                        f"invb_{tag}_{i}", role, what, [expr], ctx, key, shape="scalar"
                    ),
                    widen=self._widen(f"invw_{tag}_{i}", what, ctx, key),
                    expr=expr,
                )
            )
        transitions = []
        for i, tr in enumerate(view.transitions):
            what = f"the guard of {tr.name}{within}"
            role = f"guard {tr.name}"
            differences = levels(tr.guard)
            owners = [i for i, _ in tr.edges]

            def variant(
                suffix: str, expr: ir.Expr, kind: str, i: int = i, what: str = what, role: str = role
            ) -> Fn:
                prefix = "g" if kind == "rho" else "gb"
                return self._function(
                    f"{prefix}_{tag}_{i}_{suffix}", role, what, [expr], ctx, key, shape="scalar"
                )

            transitions.append(
                CompiledTransition(
                    name=tr.name,
                    rho=self._function(
                        f"g_{tag}_{i}",
                        role,
                        what,
                        [self._rho(tr.guard)],
                        ctx,
                        key,
                        shape="scalar",
                        share=share,
                    ),
                    holds=self._function(
                        f"gb_{tag}_{i}", role, what, [tr.guard], ctx, key, shape="scalar"
                    ),
                    view=tr,
                    reset=self._reset(
                        f"r_{tag}_{i}", tr, ctx, f"the reset of {tr.name}{within}", key
                    ),
                    levels=tuple(
                        self._function(
                            f"lvl_{tag}_{i}_{k}", role, what, [d], ctx, key, shape="scalar"
                        )
                        for k, d in enumerate(differences)
                    ),
                    level_keys=tuple(level_key(d, owners) for d in differences),
                    variant=variant if differences else None,
                    widen=self._widen(f"gw_{tag}_{i}", what, ctx, key),
                    expr=tr.guard,
                )
            )
        terms = None
        rhos = [self._rho(tr.guard) for tr in view.transitions]
        rhos += [self._rho(expr) for _, expr in view.invariants]
        if len(rhos) >= 2 and not any(reads_items([e], ctx) for e in rhos):
            # the watch's terms in one call; only where each term's own function reads
            # floats too (a function of few state items reads numpy scalars: same values,
            # but numpy's arithmetic does not raise where a float's does)
            terms = self._function(
                f"terms_{tag}",
                "watch terms",
                f"the guards and invariants of {view.name}",
                rhos,
                replace(ctx, failure=self.terms_failure),
                key,
                shape="tuple",
                share=share,
            )
        return CompiledMode(
            view.key,
            view.name,
            rhs,
            outputs,
            invariants,
            transitions,
            view.urgent,
            flow,
            terms,
            self.terms_failure if terms is not None else None,
        )


def _identifier(name: str) -> str:
    return "".join(ch if ch.isalnum() else "_" for ch in name)


def _numeric(fn: Callable[[float], float], name: str = "") -> Callable[[float], float]:
    """``fn`` if it gives floats (an expression or a time series of the command line, inputs
    held piecewise constant by reach), else
    ``fn`` with each value made a float: text, None, a complex number or an array of several
    values is then an evaluation error where the input is read (the run ends ``nonfinite``,
    naming the expression and the value), not an error inside numpy or the solver; so is
    a NaN or an infinity, which a guard or an invariant would read as false without a word."""
    from hybrid.simulation.inputs import ExpressionInput, PiecewiseConstant, TimeSeries

    if isinstance(fn, ExpressionInput | TimeSeries | PiecewiseConstant):
        return fn

    def number(t: float) -> float:
        value = fn(t)
        if isinstance(value, str | bytes):
            raise TypeError(f"an input gave {value!r}, not a number")
        result = float(value)
        if not math.isfinite(result):
            raise ValueError(f"input '{name}' gave {result} at t={t:.9g}, not a finite number")
        return result

    return number
