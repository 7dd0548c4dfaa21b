"""Event semantics on small automata whose answers are known in closed form.

Re-arming (a guard on its boundary moving away does not fire), firing at once
when a reset lands inside a guard, priority then file order with the choice
logged, and ``blocked`` when an invariant is left with no edge enabled.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from support import Simulate, assert_no_traceback, main_in_process, read_csv, read_json, run_cli

import hybrid
from hybrid.export import write_events

TOL = {"rtol": 1e-10, "atol": 1e-12}

# After `go` at t = 1 the state is x = 0, exactly on the boundary of `back`
# (x <= 0), with x' = 2 - t = 1 > 0: moving away. `back` must not fire then,
# only once x has been strictly positive and returns to 0:
# x(t) = 2 (t - 1) - (t^2 - 1) / 2 = 0 again at t = 3.
BOUNDARY = """
automaton: boundary
state: {x: {initial: 0.0}}
locations:
  A: {flow: {x: 1}}
  B: {flow: {x: 2 - t}}
  C: {flow: {x: 0}}
edges:
  - {name: go, from: A, to: B, guard: x >= 1, reset: {x: 0}}
  - {name: back, from: B, to: C, guard: x <= 0}
"""

# `go` at t = 1 resets x to -1, inside the guard of `at_once` (x <= 0): it fires
# at the same instant, one step further in j.
INSIDE = """
automaton: inside
state: {x: {initial: 0.0}}
locations:
  A: {flow: {x: 1}}
  B: {flow: {x: 1}}
  C: {flow: {x: 0}}
edges:
  - {name: go, from: A, to: B, guard: x >= 1, reset: {x: -1}}
  - {name: at_once, from: B, to: C, guard: x <= 0, reset: {x: 7}}
"""


def test_reset_on_a_boundary_moving_away_does_not_fire(simulate: Simulate) -> None:
    run = simulate(hybrid.load_text(BOUNDARY), t_end=5.0, **TOL)
    assert [jump.edge for jump in run.jumps] == ["go", "back"]
    go, back = run.jumps
    assert go.t == pytest.approx(1.0, abs=1e-12)
    assert back.t == pytest.approx(3.0, abs=1e-9)  # re-armed once x > 0, fires at x = 0 again
    assert back.j == 1 and run.termination.cause == "t_end"
    in_b = run.location == "B"
    t_b = run.t[in_b]
    np.testing.assert_allclose(run["x"][in_b], 2 * (t_b - 1) - (t_b**2 - 1) / 2, atol=1e-9)


def test_reset_on_a_boundary_sitting_still_fires(simulate: Simulate) -> None:
    # x' = 0 on the boundary x <= 0: the guard holds and stays so, it fires at once
    text = BOUNDARY.replace("B: {flow: {x: 2 - t}}", "B: {flow: {x: 0}}")
    run = simulate(hybrid.load_text(text), t_end=2.0, **TOL)
    assert [jump.edge for jump in run.jumps] == ["go", "back"]
    assert run.jumps[0].t == run.jumps[1].t


def test_reset_inside_a_guard_fires_at_once(simulate: Simulate, tmp_path: Path) -> None:
    run = simulate(hybrid.load_text(INSIDE), t_end=3.0, **TOL)
    assert [jump.edge for jump in run.jumps] == ["go", "at_once"]
    go, at_once = run.jumps
    assert go.t == at_once.t == pytest.approx(1.0, abs=1e-12)
    assert (go.j, at_once.j) == (0, 1)
    assert at_once.before == {"x": -1.0} and at_once.after == {"x": 7.0}
    rows = np.flatnonzero(run.t == go.t)
    assert list(run.j[rows]) == [0, 1, 2]
    assert list(run.location[rows]) == ["A", "B", "C"]
    assert list(run["x"][rows]) == [go.before["x"], -1.0, 7.0]
    events = tmp_path / "events.json"
    write_events(run, events)
    jumps = read_json(events)["jumps"]
    assert [(e["edge"], e["t"], e["j"]) for e in jumps] == [
        ("go", go.t, 0),
        ("at_once", go.t, 1),
    ]


PRIORITY = """
automaton: choice
state: {x: {initial: 0.0}}
locations:
  A: {flow: {x: 1}}
  B: {flow: {x: 0}}
  C: {flow: {x: 0}}
  D: {flow: {x: 0}}
edges:
  - {name: first, from: A, to: B, guard: x >= 1, priority: P_FIRST}
  - {name: second, from: A, to: C, guard: x >= 1, priority: P_SECOND}
  - {name: never, from: A, to: D, guard: x >= 2, priority: 9}
"""


@pytest.mark.parametrize(
    ("p_first", "p_second", "winner", "chosen_by"),
    [
        (0, 5, "second", "priority"),
        (5, 0, "first", "priority"),
        (0, 0, "first", "file order"),
        (3, 3, "first", "file order"),
    ],
)
def test_simultaneous_edges_priority_then_file_order(
    tmp_path: Path, p_first: int, p_second: int, winner: str, chosen_by: str
) -> None:
    spec = tmp_path / "choice.yaml"
    spec.write_text(PRIORITY.replace("P_FIRST", str(p_first)).replace("P_SECOND", str(p_second)))
    events = tmp_path / "events.json"
    code = main_in_process(
        "simulate", spec, "--t-end", "3", "--rtol", "1e-10", "--atol", "1e-12", "--events", events
    )
    assert code == 0
    doc = read_json(events)
    assert doc["termination"]["cause"] == "t_end"
    (jump,) = doc["jumps"]
    assert jump["edge"] == winner
    assert jump["enabled"] == ["first", "second"]
    assert jump["chosen_by"] == chosen_by
    assert jump["t"] == pytest.approx(1.0, abs=1e-12)
    assert jump["target"] == {"first": "B", "second": "C"}[winner]


def test_single_enabled_edge_is_logged_as_only(simulate: Simulate) -> None:
    run = simulate(hybrid.load_text(BOUNDARY), t_end=2.0, **TOL)
    assert run.jumps[0].enabled == ("go",) and run.jumps[0].chosen_by == "only"


# x' = -x from 1 must keep x >= 0.25; the only edge needs x <= -1. The invariant
# is left at t = ln 4 with nothing enabled: blocked there.
BLOCKED = """
automaton: stuck
state: {x: {initial: 1.0}}
signals: {twice: 2*x}
locations:
  A: {flow: {x: -x}, invariant: x >= 0.25}
  B: {flow: {x: 0}}
edges:
  - {name: late, from: A, to: B, guard: x <= -1}
"""


def test_blocked_at_the_closed_form_instant_api(simulate: Simulate) -> None:
    run = simulate(hybrid.load_text(BLOCKED), t_end=5.0, **TOL)
    term = run.termination
    assert term.cause == "blocked"
    assert term.t == pytest.approx(math.log(4), abs=1e-9)
    assert run.t[-1] == term.t and run["x"][-1] == pytest.approx(0.25, abs=1e-9)
    assert "invariant" in term.message and not run.jumps


def test_blocked_from_the_cli_writes_complete_output(tmp_path: Path) -> None:
    spec = tmp_path / "stuck.yaml"
    spec.write_text(BLOCKED)
    out, events = tmp_path / "traj.csv", tmp_path / "events.json"
    result = run_cli(
        "simulate", spec, "--t-end", "5", "--rtol", "1e-10", "--atol", "1e-12",
        "--out", out, "--events", events,
    )  # fmt: skip
    assert result.returncode == 1
    assert_no_traceback(result.stderr)
    assert "blocked" in result.stderr
    header, rows = read_csv(out)
    assert header == ["t", "j", "location", "x", "twice"]
    t = np.array([float(r["t"]) for r in rows])
    x = np.array([float(r["x"]) for r in rows])
    assert t[0] == 0.0 and np.all(np.diff(t) > 0)
    assert abs(t[-1] - math.log(4)) < 1e-9, f"last row t = {t[-1]!r}"
    np.testing.assert_allclose(x, np.exp(-t), rtol=1e-8)
    assert {r["location"] for r in rows} == {"A"} and {r["j"] for r in rows} == {"0"}
    doc = read_json(events)
    assert doc["termination"]["cause"] == "blocked"
    assert doc["termination"]["t"] == float(rows[-1]["t"])
    assert doc["jumps"] == []


def test_blocked_at_start_when_the_initial_state_violates_the_invariant(simulate: Simulate) -> None:
    run = simulate(hybrid.load_text(BLOCKED), t_end=5.0, initial={"x": 0.1}, **TOL)
    assert run.termination.cause == "blocked" and run.termination.t == 0.0
    assert len(run) == 1


# A sawtooth bounded by a clock, as the field's models bound their horizon (HyST's
# toy_unsafe: `tglobal <= tmax`): x rises at 1 from 5 to 9 (t = 4), falls at 2 to 3
# (t = 7), rises to 9 (t = 13), falls to 3 (t = 16) and rises again; c = t reaches
# the invariant's bound 20 exactly at t = 20, where no edge is enabled.
HORIZON = """
automaton: sawtooth
state: {x: {initial: 5.0}, c: {initial: 0.0}}
locations:
  up: {flow: {x: 1, c: 1}, invariant: x <= 10 and c <= 20}
  down: {flow: {x: -2, c: 1}, invariant: x >= 2 and c <= 20}
edges:
  - {from: up, to: down, guard: x >= 9}
  - {from: down, to: up, guard: x <= 3}
"""


def test_an_invariant_bound_reached_at_t_end_ends_the_run_at_t_end(simulate: Simulate) -> None:
    """At t_end nothing is left to flow: a boundary reached there is not left within the
    run, so it ends as ``t_end`` (exit 0), as with ``t_end`` a hair earlier; with time
    left after it, the same boundary blocks."""
    model = hybrid.load_text(HORIZON)
    for t_end in (20.0, 19.999):
        run = simulate(model, t_end=t_end, **TOL)
        assert (run.termination.cause, run.termination.t) == ("t_end", t_end)
        np.testing.assert_allclose(run.jump_times, [4.0, 7.0, 13.0, 16.0], atol=1e-9)
        assert run["c"][-1] == pytest.approx(t_end, abs=1e-9)
    run = simulate(model, t_end=20.5, **TOL)
    assert run.termination.cause == "blocked"
    assert run.termination.t == pytest.approx(20.0, abs=1e-9)


def test_a_jump_exactly_at_t_end_gives_its_two_rows_and_ends_there() -> None:
    text = """
automaton: timed
state: {x: {initial: 0.0}}
locations:
  A: {flow: {x: 1}}
  B: {flow: {x: 2}}
edges:
  - {name: go, from: A, to: B, guard: t >= 1}
"""
    for dt in (None, 0.25):
        run = hybrid.simulate(hybrid.load_text(text), t_end=1.0, dt=dt)
        assert run.termination.cause == "t_end" and run.termination.j == 1
        (jump,) = run.jumps
        assert jump.t == 1.0
        assert list(run.t[-2:]) == [1.0, 1.0] and list(run.j[-2:]) == [0, 1]
        assert np.count_nonzero(run.t == 1.0) == 2
    # with time left after it, a time-triggered jump is at its exact instant
    run = hybrid.simulate(hybrid.load_text(text), t_end=3.0, **TOL)
    assert run.jumps[0].t == pytest.approx(1.0, abs=1e-12)
    assert run["x"][-1] == pytest.approx(1.0 + 2 * 2.0, abs=1e-9)
