"""The compiled backend against closed forms and the scipy backend, on small scenarios.

Every scenario is one initial location of tests/data/native_zoo.yaml, so the
whole module compiles one model. Both backends must agree (jump times to
1e-9 absolute, 1e-10 relative, same edges, locations and termination), and
the compiled backend is held to the closed form besides.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support import REPO

import hybrid
from hybrid.simulation.result import Run

pytest.importorskip("numba")

TOL = {"rtol": 1e-10, "atol": 1e-12, "handle_sigint": False}


@pytest.fixture(scope="module")
def zoo() -> hybrid.Automaton:
    model = hybrid.load(REPO / "tests" / "data" / "native_zoo.yaml")
    assert isinstance(model, hybrid.Automaton)
    return model


def both(model: hybrid.Automaton, location: str, t_end: float, **kwargs: object) -> tuple[Run, Run]:
    runs = [
        hybrid.simulate(model, t_end=t_end, initial_location=location, backend=backend, **TOL, **kwargs)  # type: ignore[arg-type]
        for backend in ("compiled", "scipy")
    ]
    return runs[0], runs[1]


def assert_agree(compiled: Run, reference: Run) -> None:
    """Same jumps (edges, locations, hybrid times), times to 1e-9, same termination."""
    assert [(j.edge, j.source, j.target, j.j) for j in compiled.jumps] == [
        (j.edge, j.source, j.target, j.j) for j in reference.jumps
    ]
    np.testing.assert_allclose(compiled.jump_times, reference.jump_times, rtol=1e-10, atol=1e-9)
    assert compiled.termination.cause == reference.termination.cause
    assert compiled.termination.j == reference.termination.j
    assert compiled.termination.location == reference.termination.location
    assert compiled.termination.t == pytest.approx(reference.termination.t, rel=1e-10, abs=1e-9)


def test_heater_with_a_timer_switching_times(zoo: hybrid.Automaton) -> None:
    compiled, reference = both(zoo, "timer_on", 30.0, initial={"x": 1.0})
    assert_agree(compiled, reference)
    # on for ton = 2 s: x -> H + (x - H) e^(-a ton); off until x = low: ln(x / low) / a
    a, big_h, ton, low = 0.5, 10.0, 2.0, 2.0
    t, x, expected = 0.0, 1.0, []
    while t < 30.0:
        t, x = t + ton, big_h + (x - big_h) * math.exp(-a * ton)
        expected.append(t)
        t, x = t + math.log(x / low) / a, low
        expected.append(t)
    expected = [e for e in expected if e <= 30.0]
    np.testing.assert_allclose(compiled.jump_times, expected, rtol=1e-10, atol=1e-9)


def test_equality_guards_switch_where_the_level_is_reached(zoo: hybrid.Automaton) -> None:
    compiled, reference = both(zoo, "right", 10.0, initial={"x": 1.0, "y": 0.0})
    assert_agree(compiled, reference)
    # x = cos t: x == 0 at pi/2 + k pi; `x == 0` and `x >= 0 and x <= 0` alike
    expected = [math.pi / 2 + k * math.pi for k in range(3)]
    np.testing.assert_allclose(compiled.jump_times, expected, rtol=1e-10, atol=1e-9)
    assert [j.edge for j in compiled.jumps] == ["to_left", "to_right", "to_left"]
    assert compiled.termination.cause == "t_end"


def test_first_crossing_inside_a_step(zoo: hybrid.Automaton) -> None:
    compiled, reference = both(zoo, "still", 10.0)
    assert_agree(compiled, reference)
    assert [j.edge for j in compiled.jumps] == ["dip"]
    assert compiled.jumps[0].t == pytest.approx(7 * math.pi / 6, abs=1e-9)


def test_blocked_at_an_invariant_boundary(zoo: hybrid.Automaton) -> None:
    compiled, reference = both(zoo, "tank", 10.0, initial={"x": 2.5})
    assert_agree(compiled, reference)
    term = compiled.termination
    assert (term.cause, term.location) == ("blocked", "tank")
    assert term.t == pytest.approx(2.5, abs=1e-9)
    assert term.message == reference.termination.message


@pytest.mark.parametrize(
    ("lvl", "width", "t_end", "max_step", "expected"),
    [
        (1.0, 1e-4, 2.0, None, None),  # docs/semantics.md: between samples 2 ms apart, no dip
        (1.0, 1e-4, 2.0, 0.0004, 1.0),  # the same with the step capped: found
        (5.0, 1e-3, 10.0, None, 5.0),  # 1 ms window, samples 10 ms apart: the dip shows it
    ],
)
def test_narrow_guard_window(
    zoo: hybrid.Automaton, lvl: float, width: float, t_end: float, max_step: float | None,
    expected: float | None,
) -> None:  # fmt: skip
    model = zoo.with_parameters({"lvl": lvl, "width": width})
    compiled, reference = both(model, "moving", t_end, max_step=max_step)
    assert_agree(compiled, reference)
    if expected is None:
        assert compiled.jumps == []
    else:
        assert compiled.jumps[0].t == pytest.approx(expected, abs=1e-9)


def test_priority_race(zoo: hybrid.Automaton) -> None:
    compiled, reference = both(zoo, "race", 3.0)
    assert_agree(compiled, reference)
    jump = compiled.jumps[0]
    assert (jump.edge, jump.enabled, jump.chosen_by) == ("high", ("low", "high", "tie"), "file order")
    assert (jump.edge, jump.enabled, jump.chosen_by) == (
        reference.jumps[0].edge,
        reference.jumps[0].enabled,
        reference.jumps[0].chosen_by,
    )


def test_zero_time_cycle_ends_as_zeno(zoo: hybrid.Automaton) -> None:
    compiled, reference = both(zoo, "ping", 1.0, max_jumps_per_instant=50)
    assert_agree(compiled, reference)
    assert compiled.termination.cause == "zeno" and compiled.termination.zeno_time == 0.0
    assert compiled.termination.message == reference.termination.message


def test_reset_onto_a_boundary_rearms(zoo: hybrid.Automaton) -> None:
    compiled, reference = both(zoo, "ra", 5.0)
    assert_agree(compiled, reference)
    np.testing.assert_allclose(compiled.jump_times, [1.0, 3.0], atol=1e-9)
    in_b = compiled.location == "rb"
    t_b = compiled.t[in_b]
    np.testing.assert_allclose(compiled["x"][in_b], 2 * (t_b - 1) - (t_b**2 - 1) / 2, atol=1e-9)


def test_max_jumps(zoo: hybrid.Automaton) -> None:
    compiled, reference = both(zoo, "timer_on", 30.0, initial={"x": 1.0}, max_jumps=3)
    assert_agree(compiled, reference)
    assert compiled.termination.message == reference.termination.message == "reached max_jumps=3"


@pytest.mark.parametrize(("location", "initial"), [("dry", {"x": 1.0}), ("divide", {})])
def test_evaluation_failures_end_nonfinite_with_the_same_message(
    zoo: hybrid.Automaton, location: str, initial: dict[str, float]
) -> None:
    compiled, reference = both(zoo, location, 3.0, initial=initial)
    assert compiled.termination.cause == reference.termination.cause == "nonfinite"
    assert compiled.termination.t == pytest.approx(1.0, abs=1e-9)
    # same wording; the failing trial point may differ in the last digits
    strip = [m.split(":")[0] for m in (compiled.termination.message, reference.termination.message)]
    assert strip[0] == strip[1]
    assert "sqrt(" in compiled.termination.message


def test_dt_grid_and_dense_output(zoo: hybrid.Automaton) -> None:
    compiled, reference = both(zoo, "timer_on", 10.0, initial={"x": 1.0}, dt=0.3, dense=True)
    assert_agree(compiled, reference)
    np.testing.assert_allclose(compiled.t, reference.t, atol=1e-9)
    np.testing.assert_allclose(compiled["x"], reference["x"], rtol=1e-8, atol=1e-9)
    assert list(compiled.location) == list(reference.location)
    assert len(compiled.segments) == len(reference.segments)
    for (j1, a1, b1, f1), (j2, a2, b2, f2) in zip(compiled.segments, reference.segments, strict=True):
        assert j1 == j2 and a1 == pytest.approx(a2) and b1 == pytest.approx(b2, abs=1e-9)
        grid = np.linspace(a1, min(b1, b2), 7)
        np.testing.assert_allclose(f1(grid), f2(grid), rtol=1e-8, atol=1e-9)


@pytest.mark.parametrize("dt", [0.1, 0.01, 0.3])
def test_dt_grid_between_events_keeps_the_event_state(dt: float) -> None:
    # a grid point falls inside the step that holds a bounce: recording it must not
    # disturb the event's state; bounce k of a ball dropped from h0 with restitution e
    # is at sqrt(2 h0/g) (1 + 2 e + ... + 2 e^(k-1))
    ball = hybrid.load(REPO / "specs" / "bouncing_ball.yaml")
    p = ball.parameters
    h0 = dict(zip(ball.state_names, ball.initial_vector(), strict=True))["h"]
    first = math.sqrt(2 * h0 / p["g"])
    expected = [first * (1 + 2 * sum(p["e"] ** i for i in range(1, k))) for k in range(1, 5)]
    for backend in ("compiled", "scipy"):
        run = hybrid.simulate(ball, t_end=8.0, dt=dt, backend=backend, rtol=1e-10, atol=1e-12,
                              handle_sigint=False, max_jumps=4)  # fmt: skip
        np.testing.assert_allclose(run.jump_times, expected, rtol=1e-9)
        # every point recorded before the first bounce lies on the free fall
        falling = run.j == 0
        assert np.count_nonzero(falling) >= 3
        np.testing.assert_allclose(run["h"][falling], h0 - p["g"] * run.t[falling] ** 2 / 2, atol=1e-8)
        for jump in run.jumps:
            assert abs(jump.before["h"]) < 1e-9
