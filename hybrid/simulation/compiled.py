"""The compiled model: per mode, the Python functions the simulator calls.

For a mode (one location per component) this compiles, once and lazily:
the right-hand side ``rhs(t, x) -> list`` (signals computed in dependency
order, then the derivative of every state variable), the output function
giving every signal column, and per transition and invariant a ``rho``
function (``<= 0`` iff it holds), a boolean ``holds`` function and a reset.
A guard with equality atoms (docs/semantics.md, "Equality guards") also gets
the difference ``a - b`` of each atom (``levels``) and, compiled on first use,
its *oriented* rho (the atoms read one-sided) and its *snapped* forms (the
atoms replaced by constants).

A product of many components meets the same expressions in many modes: each
function is compiled once, keyed by its expressions and by the definitions of
the signals and inputs it reads, and reused in every mode where those are the
same. What a function computes is kept per mode (:meth:`CompiledModel.source`),
so a failure is described with the mode where it happened.

Evaluation errors (a math domain error, an overflow, a division by zero) never
raise: the compiled function records them and returns NaN. The right-hand side
records into :attr:`CompiledModel.flow_failure`, everything else into
:attr:`CompiledModel.failure`, because the solver also tries the right-hand
side at trial points it then rejects: a failure there is only fatal if the
solver gives up. :func:`hybrid.simulation.failures.describe_failure` turns a
recorded failure into the message a user reads.

Examples
--------
>>> import hybrid
>>> ball = hybrid.load("specs/bouncing_ball.yaml")
>>> compiled = CompiledModel(ball)
>>> mode = compiled.mode(compiled.initial_key)
>>> import numpy as np
>>> [float(v) for v in mode.rhs(0.0, np.array([10.0, 0.0]))]
[0.0, -9.81]
>>> bool(mode.transitions[0].rho(0.0, np.array([0.0, -1.0])) <= 0)
True
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, replace
from typing import Any

from hybrid.compose import System, as_system
from hybrid.errors import UsageError
from hybrid.expr import ir
from hybrid.expr.codegen import CodeContext, EvalFailure, compile_function
from hybrid.expr.rho import guard_to_rho, level_key, levels, oriented_rho, snapped
from hybrid.model import Automaton
from hybrid.modes import Binder, Mode, ModeView, TransitionView, mode_of

__all__ = [
    "CompiledCondition",
    "CompiledMode",
    "CompiledModel",
    "CompiledTransition",
    "LatestFailure",
    "Source",
]

Fn = Callable[[float, Any], Any]


@dataclass
class CompiledCondition:
    """A guard or invariant: ``rho(t, x) <= 0`` iff ``holds(t, x)`` (off the boundary)."""

    name: str
    rho: Fn
    holds: Fn


@dataclass
class CompiledTransition(CompiledCondition):
    """A transition; a guard with equality atoms has ``levels`` and compiles variants on demand."""

    view: TransitionView
    reset: Fn
    levels: tuple[Fn, ...] = ()
    level_keys: tuple[str, ...] = ()
    """Each level's :func:`~hybrid.expr.rho.level_key`: one level read by several guards."""
    variant: Callable[[str, ir.Expr, str], Fn] | None = None
    _oriented: dict[tuple[int, ...], Fn] = field(default_factory=dict)
    _snapped: dict[tuple[bool, ...], tuple[Fn, Fn]] = field(default_factory=dict)

    def oriented(self, signs: tuple[int, ...]) -> Fn:
        """Rho with level atom ``i`` read as ``signs[i] * (a - b) <= 0`` (``a == b`` for a 0).

        The plain rho for a guard without levels.
        """
        if not self.levels:
            return self.rho
        fn = self._oriented.get(signs)
        if fn is None:
            assert self.variant is not None
            tag = "".join("p" if s > 0 else "n" if s < 0 else "z" for s in signs)
            fn = self.variant(tag, oriented_rho(self.view.guard, signs), "rho")
            self._oriented[signs] = fn
        return fn

    def snapped(self, at_level: tuple[bool, ...]) -> tuple[Fn, Fn]:
        """``(rho, holds)`` of the guard with level atom ``i`` replaced by ``at_level[i]``."""
        if not self.levels:
            return self.rho, self.holds
        pair = self._snapped.get(at_level)
        if pair is None:
            assert self.variant is not None
            tag = "".join("y" if a else "n" for a in at_level)
            guard = snapped(self.view.guard, at_level)
            pair = (
                self.variant(tag, guard_to_rho(guard), "rho"),
                self.variant(tag, guard, "holds"),
            )
            self._snapped[at_level] = pair
        return pair


@dataclass
class CompiledMode:
    key: Mode
    name: str
    rhs: Fn
    outputs: Fn
    invariants: list[CompiledCondition]
    transitions: list[CompiledTransition]
    urgent: tuple[str, ...] = ()
    """Urgent locations of the mode: no time may pass while in one."""


@dataclass(frozen=True)
class Source:
    """What a generated function computes, for messages: its role and its expressions."""

    what: str
    exprs: tuple[ir.Expr, ...]
    context: CodeContext


class LatestFailure(EvalFailure):
    """An :class:`EvalFailure` that keeps the latest failure, not the first.

    The solver retries the right-hand side at points ever closer to where the
    solution leaves the domain; the last try is the most telling.
    """

    def record(self, error: BaseException, t: float, where: str) -> None:
        self.error, self.t, self.where = error, t, where


class CompiledModel:
    """Lazily compiled modes of a model, with external inputs bound.

    ``inputs`` maps an automaton's declared input names to callables of ``t``.
    ``failure`` records evaluation errors of conditions, signals and resets;
    ``flow_failure`` those of the right-hand side (see the module docstring).
    """

    def __init__(
        self,
        model: Automaton | System,
        inputs: Mapping[str, Callable[[float], float]] | None = None,
    ) -> None:
        self.system = as_system(model)
        self.failure = EvalFailure()
        self.flow_failure: EvalFailure = LatestFailure()
        self.inputs = dict(inputs or {})
        external = self._external_inputs()
        missing = [n for n in external if n not in self.inputs]
        if missing:
            raise UsageError(
                f"input '{missing[0]}' needs a value: pass inputs={{'{missing[0]}': f}} "
                "with f a function of t",
                at=self.system.input_position(missing[0]),
            )
        unknown = [n for n in self.inputs if n not in external]
        if unknown:
            raise UsageError(
                f"'{unknown[0]}' is not a declared input of {self.system.name} "
                f"(inputs: {', '.join(external) or 'none'})"
            )
        self.state_names = self.system.state_names
        self.columns = self.system.signal_columns
        self.initial_key = self.system.initial_mode
        # what each compiled function computes: by the name it records failures under
        # (that of the mode it was first compiled for), and per mode it is used in
        self.sources: dict[str, Source] = {}
        self._mode_sources: dict[tuple[Mode, str], Source] = {}
        self._modes: dict[Mode, CompiledMode] = {}
        # a product of many components meets the same guard, invariant and reset in many
        # modes: bind and compile each once (keyed by the expressions and the definitions
        # of the signals they read), not once per mode
        self._binder = Binder(self.system)
        # key -> ((what keeps the key's ids valid, the name it was compiled as), function)
        self._functions: dict[tuple[object, ...], tuple[tuple[object, str], Fn]] = {}
        self._rhos: dict[int, tuple[ir.Expr, ir.Expr]] = {}
        self._reads: dict[int, tuple[ir.Expr, frozenset[str]]] = {}
        self._zero = ir.Num(0.0)  # the flow of a state variable a location leaves alone

    def _external_inputs(self) -> list[str]:
        return list(self.system.free_inputs)

    def mode(self, key: Mode) -> CompiledMode:
        """The compiled mode ``key`` (compiled on first use, then cached)."""
        compiled = self._modes.get(key)
        if compiled is None:
            compiled = self._compile(mode_of(self.system, key, binder=self._binder))
            self._modes[key] = compiled
        return compiled

    def _rho(self, cond: ir.Expr) -> ir.Expr:
        """``guard_to_rho(cond)``, the same object each time ``cond`` is met again."""
        found = self._rhos.get(id(cond))
        if found is None or found[0] is not cond:
            found = (cond, guard_to_rho(cond))
            self._rhos[id(cond)] = found
        return found[1]

    def source(self, where: str, mode: Mode | None = None) -> Source | None:
        """What the function that recorded a failure as ``where`` computes, in ``mode``.

        A function reused across modes records failures under the name it was
        first compiled with; ``mode`` (the mode where the failure happened) picks
        the description of that mode.
        """
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
        seen: set[str] = set()
        todo = [n for e in exprs for n in self._reads_of(e)]
        while todo:
            name = todo.pop()
            if name in seen or name not in signals:
                continue
            seen.add(name)
            todo.extend(self._reads_of(signals[name]))
        return sorted(seen)

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
        outputs_ir: list[ir.Expr] = []
        for c in self.system.components:
            sizes = c.automaton.vector_sizes
            for name in c.automaton.signal_names:
                if name in sizes:
                    outputs_ir.extend(ir.Index(name, k) for k in range(sizes[name]))
                else:
                    outputs_ir.append(ir.Var(name, ir.SIGNAL))
        outputs = self._function(
            f"out_{tag}", "signals", f"the signals of {view.name}", outputs_ir, ctx, key, shape="tuple"
        )
        invariants = []
        for i, (name, expr) in enumerate(view.invariants):
            what = f"the invariant of {name}{within}"
            role = f"invariant {name}"
            invariants.append(
                CompiledCondition(
                    name,
                    self._function(
                        f"inv_{tag}_{i}", role, what, [self._rho(expr)], ctx, key, shape="scalar"
                    ),
                    self._function(
                        f"invb_{tag}_{i}", role, what, [expr], ctx, key, shape="scalar"
                    ),
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
                        f"g_{tag}_{i}", role, what, [self._rho(tr.guard)], ctx, key, shape="scalar"
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
                )
            )
        return CompiledMode(view.key, view.name, rhs, outputs, invariants, transitions, view.urgent)


def _identifier(name: str) -> str:
    return "".join(ch if ch.isalnum() else "_" for ch in name)
