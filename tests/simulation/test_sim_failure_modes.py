"""A failure in a function reused across modes is described with the mode where it happened.

The compiled model compiles a guard, an invariant, a reset or a flow once and
reuses it in every mode where its expressions and the definitions it reads
are the same (a product meets the same ones in many modes). The message of a
failure must still name the mode where it happened, not the mode the function
was first compiled for.

The plant below runs x' = -1 from x = 1; the controller, which reads nothing of
it, switches from ``idle`` to ``busy`` at t = 0.5 (its signal ``k`` is the
plant's input, so the two are one product). Every failure happens after
t = 0.5, in ``plant.run|ctrl.busy``, in a function first compiled for
``plant.run|ctrl.idle``.
"""

from __future__ import annotations

import numpy as np
import pytest
from support import Simulate

import hybrid
from hybrid.simulation.compiled import CompiledModel

PLANT = """
automaton: plant
inputs: [k]
state: {x: {initial: 1.0}, y: {initial: 0.0}}
locations:
  run: {flow: {x: -1, y: FLOW}}
  stop: {flow: {x: 0, y: 0}}
edges:
  - {name: halt, from: run, to: stop, guard: 'GUARD', reset: RESET}
"""
CONTROLLER = """
automaton: ctrl
signals: {k: 5}
locations: {idle: {}, busy: {}}
edges:
  - {name: start, from: idle, to: busy, guard: t >= 0.5}
"""
FIRST, SECOND = ("run", "idle"), ("run", "busy")


def system(flow: str = "0", guard: str = "x < -k", reset: str = "{}") -> hybrid.System:
    text = PLANT.replace("FLOW", flow).replace("GUARD", guard).replace("RESET", reset)
    return hybrid.compose(hybrid.load_text(text), hybrid.load_text(CONTROLLER))


def run_of(model: hybrid.System) -> hybrid.Run:
    return hybrid.simulate(model, t_end=3.0, handle_sigint=False)


def test_a_guard_that_fails_in_the_second_mode_is_said_in_it() -> None:
    # log(x) fails once x < 0, that is after t = 1, in plant.run|ctrl.busy
    model = system(guard="log(x) > k")
    compiled = CompiledModel(model)
    first, second = compiled.mode(FIRST), compiled.mode(SECOND)
    assert first.transitions[0].rho is second.transitions[0].rho  # one function, two modes
    end = run_of(model).termination
    assert end.cause == "nonfinite" and end.location == "plant.run|ctrl.busy"
    assert end.t > 1.0
    # before: "the guard of plant.halt failed: ...", no mode at all
    assert end.message.startswith("the guard of plant.halt in plant.run|ctrl.busy failed: log(-")


def test_a_reset_that_fails_in_the_second_mode_is_said_in_it() -> None:
    # halt fires where x = 0.25 (t = 0.75, in plant.run|ctrl.busy); its reset divides by 0
    model = system(guard="x <= 0.25", reset="{x: 1 / (x - x)}")
    end = run_of(model).termination
    assert end.cause == "nonfinite"
    assert end.t == pytest.approx(0.75, abs=1e-9)
    assert end.message.startswith(
        "the reset of plant.halt in plant.run|ctrl.busy failed: 1 / 0: float division by zero"
    )


def test_a_flow_that_fails_in_the_second_mode_is_said_in_it() -> None:
    # y' = sqrt(x) leaves its domain at t = 1; the controller has no state, so the
    # right-hand side of both modes is the same function
    model = system(flow="sqrt(x)")
    compiled = CompiledModel(model)
    assert compiled.mode(FIRST).rhs is compiled.mode(SECOND).rhs
    assert list(compiled.mode(SECOND).rhs(0.0, np.array([4.0, 0.0]))) == [-1.0, 2.0]
    end = run_of(model).termination
    assert end.cause == "nonfinite" and end.location == "plant.run|ctrl.busy"
    assert end.message.startswith("the flow of plant.run|ctrl.busy failed: sqrt(-")


def test_an_automaton_alone_is_said_as_before(simulate: Simulate) -> None:
    # one component: its modes are its locations, named by the guard's edge already
    text = PLANT.replace("FLOW", "0").replace("GUARD", "log(x) > k").replace("RESET", "{}")
    model = hybrid.load_text(text)
    run = simulate(model, t_end=3.0, inputs={"k": lambda t: 5.0}, handle_sigint=False)
    assert run.termination.message.startswith("the guard of halt failed: log(-")
