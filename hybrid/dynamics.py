"""Compiled dynamics of each mode: the functions the simulator calls.

For a mode (one location per component) this compiles, once and lazily:
the right-hand side ``rhs(t, x) -> list`` (signals computed in dependency
order, then the derivative of every state variable), the output function
giving every signal column, and per transition and invariant a ``rho``
function (``<= 0`` iff it holds), a boolean ``holds`` function and a reset.

Evaluation errors (a math domain error, an overflow, a division by zero) never
raise: the compiled function records them and returns NaN. The right-hand side
records into :attr:`Dynamics.flow_failure`, everything else into
:attr:`Dynamics.failure`, because the solver also tries the right-hand side at
trial points it then rejects: a failure there is only fatal if the solver gives
up. :meth:`Dynamics.describe_failure` names the call that failed and its
arguments, for the message a user reads.

Examples
--------
>>> import hybrid
>>> ball = hybrid.load("specs/bouncing_ball.yaml")
>>> dyn = Dynamics(ball)
>>> mode = dyn.mode(dyn.initial_key)
>>> import numpy as np
>>> [float(v) for v in mode.rhs(0.0, np.array([10.0, 0.0]))]
[0.0, -9.81]
>>> bool(mode.transitions[0].rho(0.0, np.array([0.0, -1.0])) <= 0)
True
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, replace
from typing import Any

from hybrid.compose import System, as_system
from hybrid.errors import SimulationError
from hybrid.expr import ir
from hybrid.expr.codegen import CodeContext, EvalFailure, compile_function, signal_order
from hybrid.expr.functions import Function
from hybrid.expr.rho import guard_to_rho
from hybrid.model import Automaton
from hybrid.modes import Mode, ModeView, TransitionView, initial_mode, mode_of

__all__ = ["CompiledCondition", "CompiledMode", "CompiledTransition", "Dynamics"]

Fn = Callable[[float, Any], Any]


@dataclass
class CompiledCondition:
    """A guard or invariant: ``rho(t, x) <= 0`` iff ``holds(t, x)`` (off the boundary)."""

    name: str
    rho: Fn
    holds: Fn


@dataclass
class CompiledTransition(CompiledCondition):
    view: TransitionView
    reset: Fn


@dataclass
class CompiledMode:
    key: Mode
    name: str
    rhs: Fn
    outputs: Fn
    invariants: list[CompiledCondition]
    transitions: list[CompiledTransition]


class LatestFailure(EvalFailure):
    """An :class:`EvalFailure` that keeps the latest failure, not the first.

    The solver retries the right-hand side at points ever closer to where the
    solution leaves the domain; the last try is the most telling.
    """

    def record(self, error: BaseException, t: float, where: str) -> None:
        self.error, self.t, self.where = error, t, where


class Dynamics:
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
            raise SimulationError(
                f"input '{missing[0]}' needs a value: pass inputs={{'{missing[0]}': f}} "
                "with f a function of t"
            )
        unknown = [n for n in self.inputs if n not in external]
        if unknown:
            raise SimulationError(
                f"'{unknown[0]}' is not a declared input of {self.system.name} "
                f"(inputs: {', '.join(external) or 'none'})"
            )
        self.state_names = self.system.state_names
        self.functions: dict[str, Function] = {}
        for c in self.system.components:
            self.functions.update(c.automaton.functions)
        self.columns = self._signal_columns()
        self.initial_key = initial_mode(self.system)
        self._modes: dict[Mode, CompiledMode] = {}
        self._sources: dict[str, tuple[str, list[ir.Expr], CodeContext]] = {}

    def _external_inputs(self) -> list[str]:
        if not self.system.single:
            return []
        return list(self.system.components[0].automaton.inputs)

    def _signal_columns(self) -> list[str]:
        columns: list[str] = []
        for c in self.system.components:
            a = c.automaton
            for name in a.signal_names:
                if name in a.vectors:
                    size = self.functions[a.vectors[name].func].outputs
                    columns.extend(f"{name}[{k}]" for k in range(size))
                else:
                    columns.append(name)
        return columns

    def mode(self, key: Mode) -> CompiledMode:
        """The compiled mode ``key`` (compiled on first use, then cached)."""
        compiled = self._modes.get(key)
        if compiled is None:
            compiled = self._compile(mode_of(self.system, key))
            self._modes[key] = compiled
        return compiled

    def _context(self, view: ModeView) -> CodeContext:
        return CodeContext(
            states=self.state_names,
            signals=view.signals,
            vectors=view.vectors,
            inputs=self.inputs,
            functions=self.functions,
            failure=self.failure,
        )

    def _compile(self, view: ModeView) -> CompiledMode:
        ctx = self._context(view)
        tag = _identifier(view.name)
        flows = [view.flow.get(s, ir.Num(0.0)) for s in self.state_names]
        flow_ctx = replace(ctx, failure=self.flow_failure)
        rhs = compile_function(f"rhs_{tag}", flows, flow_ctx, shape="list")
        self._sources[f"rhs_{tag}"] = (f"the flow of {view.name}", flows, ctx)
        outputs_ir: list[ir.Expr] = []
        for c in self.system.components:
            for name in c.automaton.signal_names:
                if name in view.vectors:
                    size = self.functions[view.vectors[name].func].outputs
                    outputs_ir.extend(ir.Index(name, k) for k in range(size))
                else:
                    outputs_ir.append(ir.Var(name, ir.SIGNAL))
        outputs = compile_function(f"out_{tag}", outputs_ir, ctx, shape="tuple")
        self._sources[f"out_{tag}"] = (f"the signals of {view.name}", outputs_ir, ctx)
        for i, (name, expr) in enumerate(view.invariants):
            for prefix in ("inv", "invb"):
                self._sources[f"{prefix}_{tag}_{i}"] = (f"the invariant of {name}", [expr], ctx)
        invariants = [
            CompiledCondition(
                name,
                compile_function(f"inv_{tag}_{i}", [guard_to_rho(expr)], ctx, shape="scalar"),
                compile_function(f"invb_{tag}_{i}", [expr], ctx, shape="scalar"),
            )
            for i, (name, expr) in enumerate(view.invariants)
        ]
        transitions = []
        for i, tr in enumerate(view.transitions):
            reset_of = [tr.reset.get(s) for s in self.state_names]
            for prefix in ("g", "gb"):
                self._sources[f"{prefix}_{tag}_{i}"] = (f"the guard of {tr.name}", [tr.guard], ctx)
            self._sources[f"r_{tag}_{i}"] = (
                f"the reset of {tr.name}",
                [e for e in reset_of if e is not None],
                ctx,
            )
            transitions.append(
                CompiledTransition(
                    name=tr.name,
                    rho=compile_function(
                        f"g_{tag}_{i}", [guard_to_rho(tr.guard)], ctx, shape="scalar"
                    ),
                    holds=compile_function(f"gb_{tag}_{i}", [tr.guard], ctx, shape="scalar"),
                    view=tr,
                    reset=compile_function(f"r_{tag}_{i}", [], ctx, reset_of=reset_of),
                )
            )
        return CompiledMode(view.key, view.name, rhs, outputs, invariants, transitions)

    def describe_failure(self, failure: EvalFailure) -> str:
        """``<what> failed: <call(args)>: <error>`` for a recorded failure, for a user message.

        ``what`` is "the flow of A", "the guard of e", ...; the call is the
        innermost sub-expression that fails at the point of the failure, with
        its argument values (found by re-evaluating, so only on this rare path).
        """
        what, exprs, ctx = self._sources.get(failure.where, (failure.where, [], None))
        error = failure.error
        culprit = None
        if ctx is not None and error is not None:
            point = _failure_point(error, self.state_names)
            if point is not None:
                culprit = _culprit(exprs, ctx, *point)
        detail = f"{culprit}: {error}" if culprit else f"{error}"
        return f"{what} failed: {detail}"


def _failure_point(error: BaseException, states: Sequence[str]) -> tuple[float, list[float]] | None:
    """``(t, x)`` at which a compiled function failed, read from its frame."""
    tb = error.__traceback__
    while tb is not None:
        local = tb.tb_frame.f_locals
        if tb.tb_frame.f_code.co_filename.startswith("<hybrid:") and "t" in local:
            try:
                if all(f"x_{s}" in local for s in states):
                    return float(local["t"]), [float(local[f"x_{s}"]) for s in states]
                return float(local["t"]), [float(v) for v in local["x"]]
            except (KeyError, TypeError, ValueError):
                return None
        tb = tb.tb_next
    return None


def _post_order(node: ir.Expr) -> list[ir.Expr]:
    """Every node, children before parents."""
    out: list[ir.Expr] = []
    stack: list[tuple[ir.Expr, bool]] = [(node, False)]
    while stack:
        current, expanded = stack.pop()
        if expanded:
            out.append(current)
            continue
        stack.append((current, True))
        stack.extend((c, False) for c in reversed(ir.children(current)))
    return out


def _culprit(exprs: list[ir.Expr], ctx: CodeContext, t: float, x: list[float]) -> str | None:
    """The innermost call or operation of ``exprs`` that fails at ``(t, x)``, shown with values."""
    point = _Point(float(v) for v in x)
    probe = replace(ctx, failure=EvalFailure())
    used: set[str] = set()
    for e in exprs:
        used |= {n for n in ir.names_in(e) if n in ctx.signals or n in ctx.vectors}
    order = signal_order(used, ctx.signals, ctx.vectors)
    roots = [ctx.signals.get(s) or ctx.vectors[s] for s in order] + list(exprs)

    def value(node: ir.Expr) -> Any:
        probe.failure.clear()
        result = compile_function("probe", [node], probe, shape="scalar")(t, point)
        return None if probe.failure.error is not None else result

    for root in roots:
        for node in _post_order(root):
            if not isinstance(node, ir.Call | ir.Bin):
                continue
            if value(node) is not None:
                continue
            args = node.args if isinstance(node, ir.Call) else (node.left, node.right)
            shown = [_show(value(a)) for a in args]
            if isinstance(node, ir.Call):
                return f"{node.func}({', '.join(shown)})"
            return f"{shown[0]} {node.op} {shown[1]}"
    return None


class _Point(list[float]):
    """A state as plain floats that compiled functions can read like an array.

    Plain floats keep Python's arithmetic, which raises on a division by zero or
    an overflow where numpy scalars would only warn, so the probe finds the culprit.
    """

    def tolist(self) -> list[float]:
        return list(self)


def _show(value: Any) -> str:
    if isinstance(value, float | int):
        return f"{float(value):.6g}"
    return "?"


def _identifier(name: str) -> str:
    return "".join(ch if ch.isalnum() else "_" for ch in name)
