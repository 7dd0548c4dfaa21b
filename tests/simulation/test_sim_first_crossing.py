"""The first crossing inside a step is never missed: guards in ``t`` and in inputs.

With a trivial flow the solver's steps grow to seconds; a guard that depends on
``t`` or on an input changes inside one step. The search of each step
(docs/semantics.md, "First crossings inside a step") must find the first
instant the guard holds, whatever the method, under default settings. The
truths are closed forms: ``sin(t) = -1/2`` first at ``7 pi / 6``; a relay
driven by ``u = sin(2 t)`` switches up where ``sin(2 t) = 1/2`` and down where
``sin(2 t) = -1/2``, and an independent dense evaluation of ``u`` on a fine
grid finds the same switchings.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support import RELAY, Simulate

import hybrid
from hybrid.simulation import METHODS

TRIGGER = """
automaton: trigger
state: {x: {initial: 0.0}}
locations:
  waiting: {flow: {x: 0}}
  fired: {flow: {x: 0}}
edges:
  - {name: go, from: waiting, to: fired, guard: sin(t) <= -0.5}
"""

T_END = 20.0


def relay_closed_form(t_end: float) -> list[tuple[str, float]]:
    """Up at 2t = pi/6 + 2 pi k, down at 2t = 7 pi/6 + 2 pi k, alternating from low."""
    events = []
    for k in range(20):
        events.append(("up", (math.pi / 6 + 2 * math.pi * k) / 2))
        events.append(("down", (7 * math.pi / 6 + 2 * math.pi * k) / 2))
    return [(name, t) for name, t in events if t <= t_end]


def relay_dense_reference(t_end: float, n: int = 2_000_001) -> list[tuple[str, float]]:
    """The relay run by hand on a fine grid of u (independent of the simulator)."""
    t = np.linspace(0.0, t_end, n)
    u = np.sin(2 * t)
    state, found = "low", []
    for ti, ui in zip(t.tolist(), u.tolist(), strict=True):
        if state == "low" and ui >= 0.5:
            state = "high"
            found.append(("up", ti))
        elif state == "high" and ui <= -0.5:
            state = "low"
            found.append(("down", ti))
    return found


@pytest.mark.parametrize("method", METHODS)
def test_sin_guard_fires_first_at_7pi_over_6_with_every_method(simulate: Simulate, method: str) -> None:
    run = simulate(hybrid.load_text(TRIGGER), t_end=20.0, method=method)
    assert run.termination.cause == "t_end"
    (jump,) = run.jumps
    assert jump.t == pytest.approx(7 * math.pi / 6, abs=1e-7), jump.t


def test_the_dense_reference_agrees_with_the_closed_form() -> None:
    dense, exact = relay_dense_reference(T_END), relay_closed_form(T_END)
    assert [name for name, _ in dense] == [name for name, _ in exact]
    assert max(abs(a - b) for (_, a), (_, b) in zip(dense, exact, strict=True)) < 2e-5


@pytest.mark.parametrize("method", METHODS)
def test_relay_driven_by_an_input_takes_every_jump(simulate: Simulate, method: str) -> None:
    run = simulate(
        hybrid.load_text(RELAY), t_end=T_END, method=method, inputs={"u": lambda t: math.sin(2 * t)}
    )
    reference = relay_dense_reference(T_END)
    assert len(reference) == 13
    assert [j.edge for j in run.jumps] == [name for name, _ in reference]
    exact = relay_closed_form(T_END)
    for jump, (_, t) in zip(run.jumps, exact, strict=True):
        assert jump.t == pytest.approx(t, abs=1e-7)


def test_of_several_zeros_inside_one_step_the_first_is_taken(simulate: Simulate) -> None:
    # x' = 0 and the guard |sin(t)| <= 0.1 holds near every multiple of pi; the first
    # instant is t = pi - asin(0.1) (t = 0 is excluded by starting at t = 0.5)
    text = TRIGGER.replace("sin(t) <= -0.5", "abs(sin(t)) <= 0.1")
    run = simulate(hybrid.load_text(text), t_end=100.0, t_start=0.5)
    (jump,) = run.jumps
    assert jump.t == pytest.approx(math.pi - math.asin(0.1), abs=1e-7)


def test_a_level_touched_without_crossing_fires() -> None:
    # x = 1 - cos(t) >= 0 touches the level x == 0 at t = 2 pi without crossing it. A
    # touch is found when the computed minimum is within the band of the level, so the
    # solution must be that accurate (with default tolerances it passes ~4e-7 above)
    text = """
automaton: touch
state: {x: {initial: 1.0}}
locations:
  A: {flow: {x: sin(t)}}
  B: {flow: {x: 0}}
edges:
  - {name: back, from: A, to: B, guard: x == 0}
"""
    run = hybrid.simulate(
        hybrid.load_text(text),
        t_end=10.0,
        t_start=0.5,
        initial={"x": 1 - math.cos(0.5)},
        rtol=1e-10,
        atol=1e-12,
    )
    (jump,) = run.jumps
    # x ~ (t - 2 pi)^2 / 2 near the touch: a minimum within 1e-10 is within ~1.5e-5 in t
    assert jump.t == pytest.approx(2 * math.pi, abs=2e-5)
    assert abs(jump.before["x"]) <= 1e-10 * (1 + abs(jump.before["x"]))
