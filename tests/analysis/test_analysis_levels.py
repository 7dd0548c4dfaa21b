"""`check` reasons about equality guards and boundaries as the simulator does (issues 10, 11).

The half-plane circle (x' = y, y' = -x from (1, 0), so x = cos t, y = -sin t;
``p`` keeps ``x >= 0``, ``n`` keeps ``x <= 0``, both edges guarded by ``x ==
0``) switches every pi forever. ``check`` used to call it deadlocked: it let
``down`` fire anywhere on the level (any y) and counted an equality guard as
possibly idle anywhere on entry, so ``n`` might be entered at x = 0 moving out
of it. Now a level is reached, while flowing, from the side the invariant
keeps (``down`` fires with y <= 0), and on entry an equality guard that holds
is enabled unless the flow leaves the level. Each "never" stays a proof: a
model where the simulator does end blocked is still reported.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import pytest
from support import REPO, main_in_process

import hybrid
from hybrid.analysis import check
from hybrid.analysis.static import AutomatonFacts

sys.path.insert(0, str(Path(__file__).parent))
from test_analysis_zero_time import navigation

CIRCLE = """
automaton: circle
state: {x: {initial: 1.0}, y: {initial: 0.0}}
locations:
  p: {flow: {x: y, y: -x}, invariant: 'PINV'}
  n: {flow: {x: y, y: -x}, invariant: 'NINV'}
edges:
  - {name: down, from: p, to: n, guard: 'GUARD'}
  - {name: up, from: n, to: p, guard: 'GUARD'}
properties: {deadlock_free: true, reachable: [p, n]}
"""
SPELLINGS = ["x == 0", "x >= 0 and x <= 0", "0 <= x <= 0", "0 >= x and x >= 0", "not (x != 0)"]
TOL = {"rtol": 1e-10, "atol": 1e-12, "handle_sigint": False}


def circle(guard: str = "x == 0", p: str = "x >= 0", n: str = "x <= 0") -> hybrid.Automaton:
    text = CIRCLE.replace("GUARD", guard).replace("PINV", p).replace("NINV", n)
    model = hybrid.load_text(text)
    assert isinstance(model, hybrid.Automaton)
    return model


@pytest.mark.parametrize("guard", SPELLINGS)
def test_the_circle_is_proved_deadlock_free_and_runs_for_ever(guard: str) -> None:
    model = circle(guard)
    report = check(model)
    assert report.ok, report  # before: property-violated: deadlock_free (an error)
    assert not report.by_rule("property-violated") and not report.by_rule("property-unproved")
    run = hybrid.simulate(model, t_end=10.0, **TOL)
    assert run.termination.cause == "t_end"
    assert [j.t for j in run.jumps] == pytest.approx([math.pi / 2 + k * math.pi for k in range(3)])


def test_a_level_is_reached_from_the_side_the_invariant_keeps() -> None:
    facts = AutomatonFacts(circle())
    down, up = facts.edges
    # down: in p (x >= 0) the level x = 0 is reached with x' = y <= 0; up: in n with y >= 0
    assert down.fires is not None and up.fires is not None
    assert down.fires["x"].lo == down.fires["x"].hi == 0.0 and down.fires["y"].hi == 0.0
    assert up.fires["x"].lo == up.fires["x"].hi == 0.0 and up.fires["y"].lo == 0.0
    # so n is entered with y <= 0 (the simulator enters it at (0, -1)), p with y >= 0
    entry_n = facts.entries["n"]
    assert entry_n is not None and entry_n["y"].hi == 0.0


def test_a_circle_that_does_end_blocked_is_still_reported() -> None:
    # n keeps x >= 0: entered at (0, -1), x' = -1 leaves it at once and `up` (x == 0) is
    # not enabled there (the flow leaves the level): the run ends blocked at t = pi/2
    model = circle(n="x >= 0")
    run = hybrid.simulate(model, t_end=10.0, **TOL)
    assert run.termination.cause == "blocked"
    assert run.termination.t == pytest.approx(math.pi / 2, abs=1e-9)
    report = check(model)
    # not proved, with a candidate path (the run above shows it: check does not simulate)
    (violation,) = report.by_rule("property-unproved")
    assert "deadlock_free" in violation.message and "'n'" in violation.message


def test_an_entry_on_the_boundary_that_the_flow_enters_fires_at_once() -> None:
    # start in n (y <= 0) at (1, 0) with y' = x = 1: n is left at once, and `up`
    # (y >= 0, its boundary entered) fires at t = 0; check proves no deadlock
    text = """
automaton: entered
state: {x: {initial: 1.0}, y: {initial: 0.0}}
locations:
  p: {flow: {x: -y, y: x}, invariant: y >= 0}
  n: {flow: {x: -y, y: x}, invariant: y <= 0}
initial: {location: n}
edges:
  - {name: down, from: p, to: n, guard: y <= 0}
  - {name: up, from: n, to: p, guard: y >= 0}
properties: {deadlock_free: true}
"""
    model = hybrid.load_text(text)
    assert check(model).ok
    run = hybrid.simulate(model, t_end=7.0, **TOL)
    assert run.termination.cause == "t_end"
    assert [j.edge for j in run.jumps] == ["up", "down", "up"]
    assert [j.t for j in run.jumps] == pytest.approx([0.0, math.pi, 2 * math.pi], abs=1e-9)


def _imported_circle(tmp_path: Path, name: str, initial: str) -> Path:
    source = REPO / "tests/data/spaceex/circle" / name
    assert main_in_process("import", "spaceex", source, "--out", tmp_path) == 0
    spec = tmp_path / "circle.yaml"
    text = spec.read_text()
    # SpaceEx starts in every location the initial set meets; the reader takes one today
    assert 'initial: {location: [p, "n"]}' in text
    text = text.replace('initial: {location: [p, "n"]}', f"initial: {{location: {initial}}}")
    spec.write_text(text + "properties: {deadlock_free: true}\n")
    return spec


@pytest.mark.parametrize("name", ["circle.xml", "circle_flattened.xml"])
@pytest.mark.parametrize("initial", ["p", "n"])
def test_the_spacex_circle_has_no_error_and_one_right_warning(
    tmp_path: Path, name: str, initial: str
) -> None:
    spec = _imported_circle(tmp_path, name, initial)
    model = hybrid.load(spec)
    report = check(model)
    assert report.ok, report
    assert [(f.rule, f.severity) for f in report.findings] == [("zero-time-cycle", "warning")]
    # the simulator agrees: from (1, 0) the circle switches every pi
    run = hybrid.simulate(model, t_end=7.0, **TOL)
    assert run.termination.cause == "t_end"
    # and the warning is right: at the origin (rest) both guards hold and stay so
    at_rest = hybrid.simulate(
        model, t_end=1.0, initial={"x": 0.0, "y": 0.0}, max_jumps_per_instant=20, **TOL
    )
    assert at_rest.termination.cause == "zeno" and at_rest.termination.t == 0.0


@pytest.mark.parametrize("equality", [True, False])
def test_the_navigation_grid_has_no_error_and_its_warnings_are_right(equality: bool) -> None:
    model = hybrid.load_text(navigation(equality=equality))
    report = check(model)
    assert report.ok, report
    assert {f.rule for f in report.findings} == {"zero-time-cycle", "nondeterminism"}
    # nondeterminism: at a corner of a cell two boundary guards hold at once
    corner = hybrid.simulate(model, t_end=1.0, initial={"x": 1.0, "y": 1.0}, max_jumps=1, **TOL)
    assert corner.jumps[0].enabled == ("c00_c10", "c00_c01")
    assert corner.jumps[0].chosen_by == "file order"
    # zero-time cycle: at rest on a boundary (vx = 0) the guards on both sides hold
    at_rest = hybrid.simulate(model, t_end=1.0, initial={"x": 1.0}, max_jumps_per_instant=20, **TOL)
    assert at_rest.termination.cause == "zeno" and at_rest.termination.t == 0.0
    assert {j.edge for j in at_rest.jumps} == {"c00_c10", "c10_c00"}


def test_an_exit_where_the_guard_is_being_left_is_a_deadlock() -> None:
    # x = t, y = 1 - t: at t = 1 the flow leaves x <= 1 while `go` (y >= 0 and x >= 1)
    # sits on the boundary of y >= 0 moving out of it: the slope test does not fire it
    # and the run ends blocked. check used to prove deadlock freedom (y >= 0 holds there)
    text = """
automaton: leaving
state: {x: {initial: 0}, y: {initial: 1, bounds: [0, .inf]}}
locations:
  a: {flow: {x: 1, y: -1}, invariant: x <= 1}
  b: {}
edges:
  - {name: go, from: a, to: b, guard: y >= 0 and x >= 1}
properties: {deadlock_free: true}
"""
    model = hybrid.load_text(text)
    run = hybrid.simulate(model, t_end=2.0, **TOL)
    assert run.termination.cause == "blocked"
    assert run.termination.t == pytest.approx(1.0, abs=1e-12)
    (violation,) = check(model).by_rule("property-unproved")
    assert "deadlock_free" in violation.message and "'a'" in violation.message


SNAP = """
automaton: snap
state: {x: {initial: 0}, y: {initial: 0}}
locations:
  l1: {flow: {x: 1, y: 1}}
  l2: {flow: {x: 1, y: 0}, invariant: x >= 1}
  l3: {flow: {x: 0, y: 0}}
edges:
  - {from: l1, to: l2, guard: y >= 1}
  - {from: l2, to: l3, guard: x == 1}
properties: {forbidden: [{location: l3}]}
"""


def test_a_level_reached_when_the_last_stay_stopped_is_snapped_on_entry() -> None:
    """At t = 1 the stay in l1 stops with x = 1 and y = 1: l1 -> l2 is taken, and at the
    same instant x == 1 is a level that stay reached and no jump used, so l2 -> l3 fires
    although x' = 1 leaves it. check called l3 unreachable, the edge dead and the
    forbidden entry proved, 'for every run'."""
    model = hybrid.load_text(SNAP)
    run = hybrid.simulate(model, 3.0, handle_sigint=False)
    assert [j.target for j in run.jumps] == ["l2", "l3"]
    assert run.jumps[1].t == pytest.approx(1.0)
    report = hybrid.check(model, reach_t_end=3.0)
    rules = {f.rule for f in report.findings}
    assert not rules & {"dead-edge", "unreachable-location"}
    assert "property-violated" in rules  # reach refutes it with a simulated run
