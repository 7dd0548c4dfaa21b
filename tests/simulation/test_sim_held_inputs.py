"""Inputs held piecewise constant (the inputs of reach's witnesses and of the falsifier)."""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

import hybrid
from hybrid.simulation.inputs import PiecewiseConstant

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
