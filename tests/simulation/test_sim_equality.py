"""Equality guards fire where the level is reached, and ``check`` reasons the same way.

The half-plane circle of the SpaceEx examples: ``x' = y, y' = -x`` from
``(1, 0)``, so ``x = cos t``; location ``p`` keeps ``x >= 0``, ``n`` keeps
``x <= 0``, and each hands over to the other when ``x == 0``: at
``t = pi/2 + k pi``. Every spelling of the equality gives the same run.
"""

from __future__ import annotations

import math

import pytest
from support import Simulate

import hybrid
from hybrid.analysis import check

CIRCLE = """
automaton: circle
state: {x: {initial: 1.0}, y: {initial: 0.0}}
locations:
  p: {flow: {x: y, y: -x}, invariant: x >= 0}
  n: {flow: {x: y, y: -x}, invariant: x <= 0}
edges:
  - {name: down, from: p, to: n, guard: 'GUARD'}
  - {name: up, from: n, to: p, guard: 'GUARD'}
"""
SPELLINGS = ["x == 0", "x >= 0 and x <= 0", "0 <= x <= 0", "0 >= x and x >= 0", "not (x != 0)"]
TOL = {"rtol": 1e-10, "atol": 1e-12}


def circle(guard: str) -> hybrid.Automaton:
    model = hybrid.load_text(CIRCLE.replace("GUARD", guard))
    assert isinstance(model, hybrid.Automaton)
    return model


@pytest.mark.parametrize("guard", SPELLINGS)
def test_the_circle_switches_every_pi(simulate: Simulate, guard: str) -> None:
    run = simulate(circle(guard), t_end=20.0, **TOL)
    assert run.termination.cause == "t_end", run.termination.message
    expected = [math.pi / 2 + k * math.pi for k in range(6)]  # 6 levels before t = 20
    assert [j.edge for j in run.jumps] == ["down", "up"] * 3
    for jump, t in zip(run.jumps, expected, strict=True):
        assert jump.t == pytest.approx(t, abs=1e-7)
        assert abs(jump.before["x"]) < 1e-9
    # between the jumps the state follows the circle
    assert max(abs(run["x"] - [math.cos(t) for t in run.t])) < 1e-7


def test_with_default_tolerances_the_solution_limits_the_accuracy(simulate: Simulate) -> None:
    # the event is located on the computed solution; at rtol 1e-6 that solution is
    # about 1e-7 off cos t, so the jump times are too
    run = simulate(circle("x == 0"), t_end=5.0)
    assert [j.edge for j in run.jumps] == ["down", "up"]
    assert run.jumps[0].t == pytest.approx(math.pi / 2, abs=1e-6)
    assert run.jumps[1].t == pytest.approx(3 * math.pi / 2, abs=1e-6)


@pytest.mark.parametrize("guard", SPELLINGS)
def test_check_agrees_both_edges_can_fire_and_every_exit_is_covered(guard: str) -> None:
    report = check(circle(guard))
    rules = {f.rule for f in report.findings}
    assert "dead-edge" not in rules and "sink-location" not in rules
    assert "property-violated" not in rules and "property-unproved" not in rules
    assert report.ok


def test_check_and_simulate_agree_on_deadlock_freedom(simulate: Simulate) -> None:
    text = (
        CIRCLE.replace("GUARD", "x == 0") + "properties: {deadlock_free: true, reachable: [p, n]}\n"
    )
    model = hybrid.load_text(text)
    assert check(model).ok
    assert simulate(model, t_end=10.0, **TOL).termination.cause == "t_end"


def test_a_level_reached_while_the_rest_of_the_guard_is_false_does_not_fire() -> None:
    # x = cos t crosses 0 at pi/2 (y = -1 there) and 3 pi/2 (y = +1); the guard
    # x == 0 and y > 0 holds only at the second. In between, the one-sided form of
    # the level is true after pi/2 while y > 0 becomes true at pi: no jump there.
    text = """
automaton: gated
state: {x: {initial: 1.0}, y: {initial: 0.0}}
locations:
  A: {flow: {x: y, y: -x}}
  B: {flow: {x: 0, y: 0}}
edges:
  - {name: gate, from: A, to: B, guard: x == 0 and y > 0}
"""
    run = hybrid.simulate(hybrid.load_text(text), t_end=10.0, **TOL)
    (jump,) = run.jumps
    assert jump.t == pytest.approx(3 * math.pi / 2, abs=1e-7)
    assert jump.before["y"] == pytest.approx(1.0, abs=1e-7)


def test_a_level_in_a_disjunction_fires_at_its_crossing() -> None:
    text = """
automaton: either
state: {x: {initial: 1.0}}
locations:
  A: {flow: {x: -1}}
  B: {flow: {x: 0}}
edges:
  - {name: e, from: A, to: B, guard: x == 0.25 or t >= 5}
"""
    (jump,) = hybrid.simulate(hybrid.load_text(text), t_end=10.0, **TOL).jumps
    assert jump.t == pytest.approx(0.75, abs=1e-12)


def test_starting_on_the_level_and_leaving_it_is_not_reaching_it() -> None:
    # reset onto x == 0 with x' = 1: the guard of `back` does not fire at the jump;
    # x = t - 1 never returns to 0, so there is no second jump
    text = """
automaton: leave
state: {x: {initial: 0.0}}
locations:
  A: {flow: {x: 1}}
  B: {flow: {x: 1}}
  C: {flow: {x: 0}}
edges:
  - {name: go, from: A, to: B, guard: x >= 1, reset: {x: 0}}
  - {name: back, from: B, to: C, guard: x == 0}
"""
    run = hybrid.simulate(hybrid.load_text(text), t_end=3.0, **TOL)
    assert [j.edge for j in run.jumps] == ["go"]


def test_sitting_on_the_level_holds_at_once() -> None:
    text = """
automaton: sit
state: {x: {initial: 0.0}}
locations:
  A: {flow: {x: 0}}
  B: {flow: {x: 0}}
edges:
  - {name: e, from: A, to: B, guard: x == 0}
"""
    (jump,) = hybrid.simulate(hybrid.load_text(text), t_end=1.0).jumps
    assert jump.t == 0.0


def test_check_and_simulate_agree_on_the_zero_time_cycle_at_the_origin(simulate: Simulate) -> None:
    # check warns that down and up can fire again and again without time passing: at
    # the origin the state sits on the level x == 0 (the flow is zero there), both
    # guards hold at entry, and the simulator indeed jumps back and forth at t = 0
    model = circle("x == 0")
    cycles = [f for f in check(model).findings if f.rule == "zero-time-cycle"]
    assert len(cycles) == 1 and "down" in cycles[0].message and "up" in cycles[0].message
    run = simulate(model, t_end=1.0, initial={"x": 0.0, "y": 0.0})
    assert run.termination.cause == "zeno" and run.termination.t == 0.0
    assert "jumps at the same instant" in run.termination.message
    # from (1, 0) the state only passes the level, so no jump follows another at once
    run = simulate(model, t_end=10.0, **TOL)
    assert len({j.t for j in run.jumps}) == len(run.jumps)
