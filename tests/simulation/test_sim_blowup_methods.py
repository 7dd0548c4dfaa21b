"""A finite-time blow-up ends cleanly with every method, near the closed-form instant.

x' = x y, y' = x y from (1, 2): x - y stays -1, so x' = x (x + 1) and
x(t) = 1 / (2 e^(-t) - 1), which blows up at t = ln 2. RK45 and Radau give up
("step size less than spacing"); scipy's LSODA instead loops on ever smaller
steps without advancing, which the engine detects and ends (see
hybrid/simulation/events.py, STALL_CALLS).
"""

from __future__ import annotations

import math

import pytest

import hybrid

BLOWUP = """
automaton: blowup
state: {x: {initial: 1}, y: {initial: 2}}
locations: {L: {flow: {x: x*y, y: x*y}}}
"""


@pytest.mark.parametrize("method", ["RK45", "Radau", "LSODA", "BDF"])
def test_blowup_ends_as_solver_failure_near_ln2(method: str) -> None:
    run = hybrid.simulate(hybrid.load_text(BLOWUP), t_end=3.0, method=method, handle_sigint=False)
    term = run.termination
    assert term.cause in ("solver_failure", "nonfinite")
    assert term.t == pytest.approx(math.log(2.0), abs=1e-3)
    assert "blow up" in term.message
    # what was computed is kept and follows the closed form before the blow-up
    early = run.t < 0.6
    exact = 1.0 / (2.0 * (1.0 / math.e) ** run.t[early] - 1.0)
    assert run["x"][early] == pytest.approx(exact, rel=1e-4)
