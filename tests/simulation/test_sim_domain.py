"""A flow outside its domain ends the run as ``nonfinite`` at once, with every method.

Before, a stay that started where the flow cannot be evaluated (``sqrt(x)`` at
``x = -1``) made RK45 search for an initial step size for minutes, and made
Radau and BDF raise scipy's ``ValueError('array must not contain infs or
NaNs')`` out of ``simulate``. The flow is now evaluated at the start of every
stay. How quickly the run ends is measured by what it costs, not by a clock:
the flow reads an input that counts its own evaluations.
"""

from __future__ import annotations

import pytest
from support import Simulate

import hybrid
from hybrid.simulation import METHODS

START = """
automaton: outside
inputs: [u]
state: {x: {initial: -1.0}, y: {initial: 0.0}}
locations:
  A: {flow: {x: 1 + u, y: FLOW}}
"""

# x' = -1 from x = 1 while y' = sqrt(x): x < 0 after t = 1, where sqrt is undefined
LATER = """
automaton: domain
state: {x: {initial: 1.0}, y: {initial: 0.0}}
locations:
  A: {flow: {x: -1, y: sqrt(x)}}
"""

# a jump resets x into the region where the flow of the target fails
AFTER_JUMP = """
automaton: jumped
state: {x: {initial: 1.0}}
locations:
  A: {flow: {x: -1}}
  B: {flow: {x: log(x)}}
edges:
  - {name: e, from: A, to: B, guard: x <= 0.5, reset: {x: -2}}
"""


class Counter:
    """An input ``u(t) = 0`` that counts how often the flow was evaluated."""

    def __init__(self) -> None:
        self.calls = 0

    def __call__(self, t: float) -> float:
        self.calls += 1
        return 0.0


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize(
    ("flow", "culprit"), [("sqrt(x)", "sqrt(-1)"), ("log(x)", "log(-1)"), ("1 / (x + 1)", "")]
)
def test_out_of_domain_at_the_start_ends_nonfinite_at_once(
    simulate: Simulate,
    method: str, flow: str, culprit: str
) -> None:
    text = START.replace("FLOW", flow)
    counter = Counter()
    run = simulate(hybrid.load_text(text), t_end=10.0, method=method, inputs={"u": counter})
    term = run.termination
    assert term.cause == "nonfinite", term.message
    assert term.t == 0.0 and len(run) == 1
    assert "the flow of A failed" in term.message and "(at t=0)" in term.message
    assert culprit in term.message
    # one call is simulate's look at the input before the run (a number at t_start?)
    assert counter.calls <= 3, "the run ended at the first evaluation of the flow"


@pytest.mark.parametrize("method", METHODS)
def test_leaving_the_domain_during_a_stay_ends_nonfinite(simulate: Simulate, method: str) -> None:
    run = simulate(hybrid.load_text(LATER), t_end=2.0, method=method)
    term = run.termination
    assert term.cause == "nonfinite", term.message
    assert abs(term.t - 1.0) < 5e-3  # the last accepted step before the domain ends
    assert "the flow of A failed: sqrt(-" in term.message
    # what was computed is kept: y = (2/3) (1 - (1 - t)^(3/2)) up to there
    exact = [2 / 3 * (1 - (1 - min(t, 1.0)) ** 1.5) for t in run.t]
    assert max(abs(a - b) for a, b in zip(run["y"], exact, strict=True)) < 1e-3


@pytest.mark.parametrize("method", METHODS)
def test_a_reset_into_the_domain_error_ends_at_the_jump(simulate: Simulate, method: str) -> None:
    run = simulate(hybrid.load_text(AFTER_JUMP), t_end=2.0, method=method)
    term = run.termination
    assert term.cause == "nonfinite" and term.j == 1
    assert term.t == pytest.approx(0.5, abs=1e-9)
    assert "the flow of B failed: log(-2)" in term.message


def test_a_non_finite_derivative_without_an_error_is_named(simulate: Simulate) -> None:
    # a product that overflows: nothing raises, the derivative is not finite (an input
    # that returns inf is refused where it is read, naming the input: test_sim_api)
    text = START.replace("FLOW", "1e308 * (10 - x)")
    run = simulate(hybrid.load_text(text), t_end=1.0, inputs={"u": lambda t: 0.0})
    term = run.termination
    assert term.cause == "nonfinite" and term.t == 0.0
    assert "the flow of A gives y' = inf" in term.message
