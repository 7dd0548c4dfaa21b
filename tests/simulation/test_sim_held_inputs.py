"""Inputs held piecewise constant (reach's witnesses, the falsifier), and runs with other inputs.

A model is compiled once per thread and run again with other inputs put in its
slots (``reuse.compiled_model``): each run reads its own inputs, and a run
that starts while another still steps the model gets a compiled model of its own.
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

import hybrid
from hybrid.compose import as_system
from hybrid.errors import UsageError
from hybrid.simulation.inputs import PiecewiseConstant
from hybrid.simulation.reuse import compiled_model

HELD = PiecewiseConstant(np.array([0.0, 1.0, 3.0]), np.array([1.0, -2.0, 0.5]))

DRIVEN = """\
automaton: driven
inputs: [u]
state: {x: {initial: 0.0}}
locations: {a: {flow: {x: u}}}
"""


@pytest.mark.parametrize(
    ("t", "value"),
    [
        (-5.0, 1.0),  # before the first start: the first value
        (0.0, 1.0),
        (0.999, 1.0),
        (1.0, -2.0),  # a start belongs to the piece it starts
        (2.5, -2.0),
        (3.0, 0.5),
        (1e300, 0.5),
        (math.inf, 0.5),
        (-math.inf, 1.0),
    ],
)
def test_a_held_input_has_the_value_of_the_piece_it_is_in(t: float, value: float) -> None:
    for time in (t, np.float64(t)):
        got = HELD(time)
        assert got == value and type(got) is float


def test_a_held_input_pickles_and_keeps_its_pieces() -> None:
    again = pickle.loads(pickle.dumps(HELD))
    assert [again(t) for t in (0.5, 2.0, 9.0)] == [1.0, -2.0, 0.5]
    assert np.array_equal(again.starts, HELD.starts) and np.array_equal(again.values, HELD.values)


@pytest.mark.parametrize("t_end", [0.5, 2.0, 4.0])
def test_a_flow_driven_by_a_held_input_integrates_it_piece_by_piece(t_end: float) -> None:
    # x' = u: x(t) is the integral of u, 1 on [0, 1), -2 on [1, 3), 0.5 after; the solver
    # meets each switch inside a step (a wrong piece would be off by at least 0.5)
    exact = min(t_end, 1.0) - 2.0 * min(max(t_end - 1.0, 0.0), 2.0) + 0.5 * max(t_end - 3.0, 0.0)
    run = hybrid.simulate(
        hybrid.load_text(DRIVEN), t_end, inputs={"u": HELD}, rtol=1e-10, atol=1e-12,
        handle_sigint=False,
    )  # fmt: skip
    assert run.termination.cause == "t_end"
    assert run.states[-1, 0] == pytest.approx(exact, abs=1e-6)


def _integral(steps: PiecewiseConstant, t: float) -> float:
    """The integral of a held input over [0, t] (it starts at 0), by hand."""
    ends = [*steps.starts[1:].tolist(), math.inf]
    return sum(
        v * max(0.0, min(t, end) - start)
        for start, end, v in zip(steps.starts.tolist(), ends, steps.values.tolist(), strict=True)
    )


def test_runs_with_other_inputs_share_the_compiled_model_and_read_their_own() -> None:
    model = hybrid.load_text(DRIVEN)
    other = PiecewiseConstant(np.array([0.0, 2.0]), np.array([-3.0, 4.0]))
    system = as_system(model)
    assert compiled_model(system, {"u": HELD}) is compiled_model(system, {"u": other})
    for inputs in (HELD, other, HELD):
        run = hybrid.simulate(model, 4.0, inputs={"u": inputs}, rtol=1e-10, atol=1e-12,
                              handle_sigint=False)  # fmt: skip
        assert run.states[-1, 0] == pytest.approx(_integral(inputs, 4.0), abs=1e-6)


def test_a_run_started_inside_another_gets_its_own_compiled_model() -> None:
    """An input that simulates its own model: the inner run must not change the outer's input."""
    model = hybrid.load_text(DRIVEN)
    inner: list[float] = []

    def one(t: float) -> float:
        if not inner:
            run = hybrid.simulate(model, 1.0, inputs={"u": lambda t: 5.0}, handle_sigint=False)
            inner.append(float(run.states[-1, 0]))
        return 1.0

    outer = hybrid.simulate(model, 2.0, inputs={"u": one}, rtol=1e-10, atol=1e-12,
                            handle_sigint=False)  # fmt: skip
    assert inner == [pytest.approx(5.0)]
    assert outer.states[-1, 0] == pytest.approx(2.0, abs=1e-9)  # u = 1 throughout


def test_a_refused_input_leaves_the_compiled_model_as_it_was() -> None:
    model = hybrid.load_text(DRIVEN)
    first = hybrid.simulate(model, 4.0, inputs={"u": HELD}, handle_sigint=False)
    with pytest.raises(UsageError, match="'v' is not a declared input"):
        hybrid.simulate(model, 4.0, inputs={"u": HELD, "v": HELD}, handle_sigint=False)
    again = hybrid.simulate(model, 4.0, inputs={"u": HELD}, handle_sigint=False)
    assert np.array_equal(first.t, again.t) and np.array_equal(first.states, again.states)


def test_independent_components_run_again_read_their_new_inputs() -> None:
    """A system simulated apart (no shared label or signal): its groups are compiled once too."""
    from hybrid.compose import compose
    from hybrid.simulation.apart import group_system

    def component(name: str, u: str, x: str) -> hybrid.Automaton:  # with a free input
        text = (f"automaton: {name}\ninputs: {{{u}: {{range: [-5, 5]}}}}\n"
                f"state: {{{x}: {{initial: 0.0}}}}\nlocations: {{a: {{flow: {{{x}: {u}}}}}}}\n")  # fmt: skip
        model = hybrid.load_text(text)
        assert isinstance(model, hybrid.Automaton)
        return model

    system = compose(component("driven", "u", "x"), component("other", "w", "y"))
    assert group_system(system, (0,)) is group_system(system, (0,))
    steps = PiecewiseConstant(np.array([0.0, 1.5]), np.array([2.0, -1.0]))
    for u, w in ((HELD, steps), (steps, HELD)):
        run = hybrid.simulate(system, 4.0, inputs={"u": u, "w": w}, rtol=1e-10, atol=1e-12,
                              handle_sigint=False)  # fmt: skip
        assert run.states[-1].tolist() == pytest.approx(
            [_integral(u, 4.0), _integral(w, 4.0)], abs=1e-6
        )
