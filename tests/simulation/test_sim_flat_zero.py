"""A guard whose rho falls to exactly 0 and stays there means what its boolean form says.

A true conjunct (``0 >= 0``) used to add a 0 to the ``max`` of the guard's rho,
``max(h, v, 0)``: the watch fell to 0 and never below it, the crossing was
placed at the sample that first saw 0 (late, with h below the floor), and the
ball gained energy at every bounce. An always-false conjunct (``x < x``) left
rho at about ``4e-17`` falling to 0, and the slope test fired it. The rules now:
a comparison that cannot change has the rho of ``true``/``false`` (-1/+1); a
watch is located at the first instant it is at or below 0; where the slope
test steps to a rho of exactly 0, the boolean form there decides. Both
backends are held to it (the compiled one lacked the last two rules until the
second wave's review).

The truth is the bouncing ball's closed form (``h0 = 10, g = 9.81, e = 0.8``):
``t_k = t1 (1 + 2 e (1 - e^(k-1)) / (1 - e))``, ``t1 = sqrt(2 h0 / g)``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import hybrid

ROOT = Path(__file__).resolve().parents[2]
H0, G, E = 10.0, 9.81, 0.8
T1 = math.sqrt(2 * H0 / G)
TOL = {"rtol": 1e-10, "atol": 1e-12}

SPELLINGS = [
    "h <= 0 and v < 0 and 0 >= 0",  # a constant true conjunct
    "max(h, 0) <= 0 and v < 0",  # rho max(max(h, 0), v): a flat zero the user wrote
    "h <= 0 and v < 0 and h - h >= 0",  # a true conjunct that is not a constant
]


def ball_with(guard: str) -> hybrid.Automaton:
    text = (ROOT / "specs/bouncing_ball.yaml").read_text()
    model = hybrid.load_text(text.replace("guard: h <= 0 and v < 0", f"guard: '{guard}'"))
    assert isinstance(model, hybrid.Automaton)
    return model


def impact_time(k: np.ndarray) -> np.ndarray:
    return T1 * (1 + 2 * E * (1 - E ** (k - 1)) / (1 - E))


@pytest.mark.parametrize("guard", SPELLINGS)
def test_a_true_conjunct_changes_nothing(guard: str, backend: str) -> None:
    plain = hybrid.simulate(ball_with("h <= 0 and v < 0"), t_end=20.0, backend=backend, **TOL)
    run = hybrid.simulate(ball_with(guard), t_end=20.0, backend=backend, **TOL)
    # before: 13 jumps, then blocked at t = 12.22 (h below the floor at each late bounce)
    assert run.termination.cause == plain.termination.cause == "zeno"
    assert len(run.jumps) == len(plain.jumps)
    k = np.arange(1, 31, dtype=float)
    assert np.abs(run.jump_times[:30] - impact_time(k)).max() < 1e-9
    assert np.abs(run.jump_times - plain.jump_times).max() < 1e-9
    assert max(abs(j.before["h"]) for j in run.jumps) < 1e-9


@pytest.mark.parametrize("guard", SPELLINGS)
def test_a_true_conjunct_changes_nothing_with_default_tolerances(guard: str, backend: str) -> None:
    plain = hybrid.simulate(ball_with("h <= 0 and v < 0"), t_end=20.0, backend=backend)
    run = hybrid.simulate(ball_with(guard), t_end=20.0, backend=backend)
    assert run.termination.cause == plain.termination.cause == "zeno"
    assert len(run.jumps) == len(plain.jumps)
    assert np.abs(run.jump_times - plain.jump_times).max() < 1e-9


FALSE_GUARD = """
automaton: never
state: {x: {initial: -1}, y: {initial: 2}}
locations:
  L0: {flow: {x: y, y: x}}
edges:
  - {name: never, from: L0, to: L0, guard: 'GUARD'}
  - {name: other, from: L0, to: L0, guard: 'x < x*y'}
"""


@pytest.mark.parametrize("guard", ["x < x and x < x*y", "x - x > 0 and x < x*y"])
def test_an_always_false_guard_never_fires(guard: str, backend: str) -> None:
    # x = 2 sinh t - cosh t, y = 2 cosh t - sinh t: x (1 - y) turns negative where x
    # does, at t = atanh(1/2). There `other` (x < x*y) starts to hold and, its reset
    # being the identity, fires again and again at that instant (a zero-time cycle);
    # `never` stays false (before: the slope test fired it, its rho ~4e-17 falling to 0)
    model = hybrid.load_text(FALSE_GUARD.replace("GUARD", guard))
    run = hybrid.simulate(model, t_end=3.0, max_jumps_per_instant=15, handle_sigint=False,
                          backend=backend)  # fmt: skip
    assert {j.edge for j in run.jumps} == {"other"}
    assert run.termination.cause == "zeno"
    assert run.termination.t == pytest.approx(math.atanh(0.5), abs=1e-6)


@pytest.mark.parametrize("invariant", ["x >= 0", "x >= 0 and 0 >= 0", "x >= 0 and x <= x"])
def test_an_invariant_with_a_true_conjunct_is_left_where_it_is_left(invariant: str, backend: str) -> None:
    # x = 1 - t leaves x >= 0 at t = 1; a constant conjunct used to make rho max(-x, 0),
    # never strictly inside, so the invariant was never watched (before: t_end, x = -1)
    text = f"""
automaton: leave
state: {{x: {{initial: 1.0}}}}
locations:
  A: {{flow: {{x: -1}}, invariant: '{invariant}'}}
"""
    run = hybrid.simulate(hybrid.load_text(text), t_end=2.0, backend=backend, **TOL)
    assert run.termination.cause == "blocked"
    assert run.termination.t == pytest.approx(1.0, abs=1e-12)
