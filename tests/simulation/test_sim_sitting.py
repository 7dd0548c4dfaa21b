"""A guard that sits on its boundary is decided as on it, not by the sign of a rounding error.

A reset computes ``x := x + 0.2`` from ``x = 0.1``, or ``x := x - 0.4`` from
``x = 0.7``: 0.3 in exact arithmetic, ``0.30000000000000004`` and
``0.29999999999999993`` in floating point. In the next location ``x`` does not
move, so every guard on ``x`` against 0.3 *sits* on its boundary (rho within the
band, slope 0), and docs/semantics.md says how it is decided: each comparison
within the band as on its boundary, so ``<=``, ``>=`` and ``==`` hold and
``<``, ``>`` and ``!=`` do not, whichever side rounding put ``x`` on. Before
this rule the boolean form decided at the rounded value, so the two spellings
of one model ran differently, and the two backends did on a generated model
whose event times differ by an ulp (the differential property, model 963).
Invariants sit the same way.
"""

from __future__ import annotations

import pytest
from support import Simulate

import hybrid

MODEL = """
automaton: sitting
state: {x: {initial: START}, c: {initial: 0.0}}
locations:
  set: {flow: {x: 0, c: 1}}
  hold: {flow: {x: 0, c: 1}, invariant: 'INVARIANT'}
  done: {flow: {x: 0, c: 1}}
edges:
  - {name: arrive, from: set, to: hold, guard: c >= 1, reset: {x: RESET}}
  - {name: fire, from: hold, to: done, guard: 'GUARD'}
  - {name: wait, from: hold, to: done, guard: c >= 2}
"""
ROUNDINGS = {  # the same exact 0.3, rounded above and below
    "above": ("0.1", "x + 0.2"),
    "below": ("0.7", "x - 0.4"),
}
ON_BOUNDARY = {"x <= 0.3": True, "x >= 0.3": True, "x == 0.3": True,
               "x < 0.3": False, "x > 0.3": False, "x != 0.3": False,
               "0.3 >= x and c >= 0": True, "not (x > 0.3)": True, "0.2 < x < 0.3": False}  # fmt: skip


def model(rounding: str, guard: str = "false", invariant: str = "true") -> hybrid.Automaton:
    start, reset = ROUNDINGS[rounding]
    text = MODEL.replace("START", start).replace("RESET", reset)
    loaded = hybrid.load_text(text.replace("GUARD", guard).replace("INVARIANT", invariant))
    assert isinstance(loaded, hybrid.Automaton)
    return loaded


def test_the_two_roundings_are_on_either_side() -> None:
    assert 0.1 + 0.2 > 0.3 > 0.7 - 0.4  # what the test relies on


@pytest.mark.parametrize("rounding", ROUNDINGS)
@pytest.mark.parametrize("guard", ON_BOUNDARY)
def test_a_sitting_guard_is_decided_on_its_boundary(
    simulate: Simulate, rounding: str, guard: str
) -> None:
    run = simulate(model(rounding, guard), t_end=3.0)
    after_arrival = [(j.edge, j.t) for j in run.jumps[1:]]
    if ON_BOUNDARY[guard]:
        assert after_arrival == [("fire", pytest.approx(1.0, abs=1e-12))]
    else:
        assert after_arrival == [("wait", pytest.approx(2.0, abs=1e-12))]


@pytest.mark.parametrize("rounding", ROUNDINGS)
@pytest.mark.parametrize("invariant", ["x <= 0.3", "x >= 0.3", "x == 0.3"])
def test_a_sitting_invariant_holds_where_it_is_not_strict(
    simulate: Simulate, rounding: str, invariant: str
) -> None:
    run = simulate(model(rounding, invariant=invariant), t_end=3.0)
    assert [j.edge for j in run.jumps] == ["arrive", "wait"]
    assert run.jumps[-1].t == pytest.approx(2.0, abs=1e-12)
    assert run.termination.cause == "t_end"


@pytest.mark.parametrize("invariant", ["x < 0.3", "x > 0.3", "x != 0.3"])
def test_a_sitting_strict_invariant_ends_the_stay_the_same_either_way(
    simulate: Simulate, invariant: str
) -> None:
    runs = [simulate(model(r, invariant=invariant), t_end=3.0) for r in ROUNDINGS]
    for run in runs:
        assert [j.edge for j in run.jumps] == ["arrive"]
        assert run.t[-1] == pytest.approx(1.0, abs=1e-12)
    assert runs[0].termination.cause == runs[1].termination.cause
