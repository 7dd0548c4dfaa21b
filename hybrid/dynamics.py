"""Compiled dynamics of each mode: the functions the simulator calls.

For a mode (one location per component) this compiles, once and lazily:
the right-hand side ``rhs(t, x) -> list`` (signals computed in dependency
order, then the derivative of every state variable), the output function
giving every signal column, and per transition and invariant a ``rho``
function (``<= 0`` iff it holds), a boolean ``holds`` function and a reset.

Examples
--------
>>> import hybrid
>>> ball = hybrid.load("specs/bouncing_ball.yaml")
>>> dyn = Dynamics(ball)
>>> mode = dyn.mode(dyn.initial_key)
>>> mode.rhs(0.0, [10.0, 0.0])
[0.0, -9.81]
>>> mode.transitions[0].rho(0.0, [0.0, -1.0]) <= 0
True
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from hybrid.compose import Mode, ModeView, System, TransitionView, as_system, initial_mode, mode_of
from hybrid.errors import SimulationError
from hybrid.expr import ir
from hybrid.expr.codegen import CodeContext, EvalFailure, compile_function
from hybrid.expr.functions import Function
from hybrid.expr.rho import guard_to_rho
from hybrid.model import Automaton

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


class Dynamics:
    """Lazily compiled modes of a model, with external inputs bound.

    ``inputs`` maps an automaton's declared input names to callables of ``t``.
    """

    def __init__(
        self,
        model: Automaton | System,
        inputs: Mapping[str, Callable[[float], float]] | None = None,
    ) -> None:
        self.system = as_system(model)
        self.failure = EvalFailure()
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

    def mode_name(self, key: Mode) -> str:
        from hybrid.compose import mode_name

        return mode_name(self.system, key)

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
        rhs = compile_function(f"rhs_{tag}", flows, ctx, shape="list")
        outputs_ir: list[ir.Expr] = []
        for c in self.system.components:
            for name in c.automaton.signal_names:
                if name in view.vectors:
                    size = self.functions[view.vectors[name].func].outputs
                    outputs_ir.extend(ir.Index(name, k) for k in range(size))
                else:
                    outputs_ir.append(ir.Var(name, ir.SIGNAL))
        outputs = compile_function(f"out_{tag}", outputs_ir, ctx, shape="tuple")
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


def _identifier(name: str) -> str:
    return "".join(ch if ch.isalnum() else "_" for ch in name)
