"""Runs that cannot go on: a solution that blows up, a flow outside its domain.

Each ends with a cause and a message a user can act on, never a traceback, and
keeps what was computed up to there.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from support import Simulate, assert_no_traceback, read_csv, read_json, run_cli

import hybrid

# x' = x^2 from x = 1: x(t) = 1 / (1 - t), which blows up at t = 1.
BLOWUP = """
automaton: blowup
state: {x: {initial: 1.0}}
locations:
  A: {flow: {x: x**2}}
"""

# x' = -1 from 1 while y' = sqrt(x): x < 0 after t = 1, where sqrt is undefined.
DOMAIN = """
automaton: domain
state: {x: {initial: 1.0}, y: {initial: 0.0}}
locations:
  A: {flow: {x: -1, y: sqrt(x)}}
"""


@pytest.mark.parametrize("tolerances", [{}, {"rtol": 1e-10, "atol": 1e-12}])
def test_blowup_ends_near_the_singularity(simulate: Simulate, tolerances: dict[str, float]) -> None:
    run = simulate(hybrid.load_text(BLOWUP), t_end=2.0, **tolerances)
    term = run.termination
    assert term.cause in ("nonfinite", "solver_failure")
    assert abs(term.t - 1.0) < 1e-3, term.t
    assert "blow up" in term.message
    # what was computed is kept, and it is the closed form where x is moderate
    assert run.t[-1] == pytest.approx(term.t)
    moderate = run["x"] < 1e3
    np.testing.assert_allclose(run["x"][moderate], 1 / (1 - run.t[moderate]), rtol=1e-3)


def test_blowup_from_the_cli(tmp_path: Path) -> None:
    spec = tmp_path / "blowup.yaml"
    spec.write_text(BLOWUP)
    out, events = tmp_path / "blowup.csv", tmp_path / "blowup.json"
    result = run_cli("simulate", spec, "--t-end", "2", "--out", out, "--events", events)
    assert result.returncode == 1
    assert_no_traceback(result.stderr)
    cause = read_json(events)["termination"]["cause"]
    assert cause in ("nonfinite", "solver_failure")
    assert f": {cause}: solver stopped" in result.stderr
    _, rows = read_csv(out)
    assert float(rows[0]["t"]) == 0.0
    assert abs(float(rows[-1]["t"]) - 1.0) < 1e-3


def test_math_domain_error_names_the_function_and_time(simulate: Simulate) -> None:
    run = simulate(hybrid.load_text(DOMAIN), t_end=2.0)
    term = run.termination
    assert term.cause == "nonfinite"
    assert abs(term.t - 1.0) < 1e-6, term.t
    assert "the flow of A" in term.message
    assert "sqrt(-" in term.message and "math domain error" in term.message
    assert "t=1" in term.message
    assert run.t[-1] == term.t
    # kept output: y = (2/3) (1 - (1 - t)^(3/2)) up to there
    np.testing.assert_allclose(run["y"], 2 / 3 * (1 - (1 - np.minimum(run.t, 1)) ** 1.5), atol=1e-5)


def test_math_domain_error_from_the_cli(tmp_path: Path) -> None:
    spec = tmp_path / "domain.yaml"
    spec.write_text(DOMAIN)
    out, events = tmp_path / "domain.csv", tmp_path / "domain.json"
    result = run_cli("simulate", spec, "--t-end", "2", "--out", out, "--events", events)
    assert result.returncode == 1
    assert_no_traceback(result.stderr)
    assert ": nonfinite: the flow of A failed: sqrt(" in result.stderr
    term = read_json(events)["termination"]
    assert term["cause"] == "nonfinite" and abs(term["t"] - 1.0) < 1e-6
    _, rows = read_csv(out)
    assert float(rows[-1]["t"]) == term["t"]


def test_rejected_trial_point_outside_the_domain_is_not_a_failure(simulate: Simulate) -> None:
    # x' = -x stays positive, but once x is tiny the solver tries long steps whose
    # trial stages have x < 0, where sqrt fails; it rejects them and goes on.
    # y' = sqrt(x) = e^(-t/2), so y(T) = 2 (1 - e^(-T/2)).
    text = DOMAIN.replace("x: -1, y: sqrt(x)", "x: -x, y: sqrt(x)")
    run = simulate(hybrid.load_text(text), t_end=100.0)
    assert run.termination.cause == "t_end", run.termination.message
    assert run["y"][-1] == pytest.approx(2 * (1 - math.exp(-50)), rel=1e-4)


def test_failures_in_guards_signals_and_resets_are_named() -> None:
    signal = """
automaton: s
state: {x: {initial: 1.0}}
signals: {s: log(x - 2)}
locations: {A: {flow: {x: -1}}}
"""
    reset = """
automaton: r
state: {x: {initial: 1.0}}
locations: {A: {flow: {x: -1}}, B: {flow: {x: 0}}}
edges: [{name: e, from: A, to: B, guard: x <= 0.5, reset: {x: 1/(x - 0.5)}}]
"""
    term = hybrid.simulate(hybrid.load_text(signal), t_end=1.0).termination
    assert (term.cause, term.t) == ("nonfinite", 0.0)
    assert "the signals of A failed: log(-1): math domain error" in term.message
    term = hybrid.simulate(hybrid.load_text(reset), t_end=1.0).termination
    assert term.cause == "nonfinite" and term.t == pytest.approx(0.5)
    assert "the reset of e failed: 1 / 0" in term.message


def test_a_clock_far_from_zero_is_named_as_the_cause(simulate: Simulate) -> None:
    """At t = 1e17 doubles are 2**(56-52) = 16 apart (2**56 < 1e17 < 2**57): no step below
    10 spacings is possible, so a flow with time constant 10 cannot be stepped at all."""
    decay = hybrid.load_text(
        "automaton: decay\nstate: {x: {initial: 20.0}}\nlocations:\n  A: {flow: {x: -x / 10}}\n"
    )
    run = simulate(decay, t_start=1e17, t_end=1e17 + 1e4)
    term = run.termination
    assert (term.cause, term.t) == ("solver_failure", 1e17)
    assert "16 apart" in term.message and "shorter than 160" in term.message
    assert "t_start" in term.message and "blow up" not in term.message
    assert run.t.tolist() == [1e17] and run["x"].tolist() == [20.0]
