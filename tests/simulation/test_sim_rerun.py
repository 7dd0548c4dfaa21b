"""A model simulated again after a run that ended on an evaluation failure runs in full."""

from __future__ import annotations

import math

import pytest
from support import Simulate

import hybrid

SPEC = """
automaton: draining
state: {x: {initial: 1.0}}
signals: {s: sqrt(x)}
locations: {A: {flow: {x: -1}}}
"""


def test_a_second_run_does_not_inherit_the_first_runs_failure(simulate: Simulate) -> None:
    model = hybrid.load_text(SPEC)
    first = simulate(model, t_end=10.0, handle_sigint=False)
    second = simulate(model, t_end=10.0, handle_sigint=False)
    # x = 1 - t: the signal sqrt(x) fails at the first stored point past t = 1
    for run in (first, second):
        assert run.termination.cause == "nonfinite"
        assert run.termination.t > 1.0
        assert "sqrt(" in run.termination.message
    assert len(second) == len(first) > 1
    assert second.termination.t == pytest.approx(first.termination.t, abs=0.0)
    tight = simulate(model, t_end=10.0, rtol=1e-10, atol=1e-12, handle_sigint=False)
    assert tight.termination.cause == "nonfinite" and len(tight) > 1
    assert math.isclose(tight["x"][-1], 1.0 - tight.t[-1], abs_tol=1e-9)
