"""Every check against one table of small automata, networkx style.

Each case is a YAML spec with the findings it must produce and those it must
not, as ``(rule, where)`` pairs. Every check runs on every case: it must
produce the expected findings of its rule, none of the forbidden ones, and no
finding of another rule. Every rule appears on both sides of the table.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import pytest

import hybrid
from hybrid.analysis import analyse, check
from hybrid.analysis.checks import (
    CHECKS,
    blocked_starts,
    dead_edges,
    incomplete_analysis,
    nondeterminism,
    property_violations,
    run_checks,
    sink_locations,
    unreachable_locations,
    unused_declarations,
    zero_time_cycles,
)
from hybrid.analysis.findings import RULES

RULE_OF = {
    unreachable_locations: ("unreachable-location",),
    blocked_starts: ("blocked-start",),
    sink_locations: ("sink-location",),
    dead_edges: ("dead-edge",),
    nondeterminism: ("nondeterminism",),
    zero_time_cycles: ("zero-time-cycle",),
    unused_declarations: ("unused-declaration",),
    # disproved (a proof) is an error; not proved, with a candidate path, a warning; a
    # violation a run shows (property-violated) comes from reach only
    property_violations: ("property-disproved", "property-unproved"),
    incomplete_analysis: ("analysis-incomplete",),
}


@dataclass
class Case:
    name: str
    spec: str
    must: set[tuple[str, str]] = field(default_factory=set)
    must_not: set[tuple[str, str]] = field(default_factory=set)


BLOCKED_STARTS = [
    Case(
        "start_outside_invariant",
        """
automaton: tank
state: {x: {initial: 7}}
locations: {fill: {flow: {x: -1}, invariant: x <= 5}}
""",
        must={("blocked-start", "fill")},
    ),
    Case(
        "start_set_outside_invariant",
        """
automaton: tank
state: {x: {initial: [6, 8], nominal: 7.5}}
locations: {fill: {flow: {x: -x}, invariant: x <= 5 and x >= -9}}
""",
        must={("blocked-start", "fill")},
    ),
    Case(
        "start_set_partly_inside",
        """
automaton: tank
state: {x: {initial: [4, 8], nominal: 4.5}}
locations: {fill: {flow: {x: -1}, invariant: x <= 5}}
""",
        must_not={("blocked-start", "fill")},
    ),
    Case(
        "start_outside_left_at_once",
        """
automaton: tank
state: {x: {initial: 7}}
locations: {fill: {flow: {x: 1}, invariant: x <= 5}, drain: {flow: {x: -1}}}
edges: [{name: spill, from: fill, to: drain, guard: x >= 5}]
""",
        must_not={("blocked-start", "fill")},
    ),
    Case(
        "start_within_the_band",
        """
automaton: tank
state: {x: {initial: 5.000000000001}}
locations: {fill: {flow: {x: -1}, invariant: x <= 5}}
""",
        must_not={("blocked-start", "fill")},
    ),
]
"""Starts the simulator blocks at t = 0, and starts it does not (a run of each point of
the initial set checks every ``blocked-start`` below)."""

CASES = [
    *BLOCKED_STARTS,
    Case(
        "clean_thermostat",
        """
automaton: clean
parameters: {lo: 18, hi: 22}
state: {T: {initial: 20, bounds: [0, 40]}}
labels: [switch]
locations:
  off: {flow: {T: -0.1*(T - 10)}, invariant: T >= lo}
  on: {flow: {T: 0.1*(30 - T)}, invariant: T <= hi}
edges:
  - {name: turn_on, from: off, to: on, guard: T <= lo, label: switch}
  - {name: turn_off, from: on, to: off, guard: T >= hi}
properties: {reachable: [off, on], deadlock_free: true, deterministic: true}
""",
        must_not={
            ("unreachable-location", "on"),
            ("sink-location", "off"),
            ("sink-location", "on"),
            ("blocked-start", "off"),
            ("dead-edge", "turn_on"),
            ("zero-time-cycle", "turn_on"),
            ("unused-declaration", "lo"),
            ("unused-declaration", "switch"),
            ("property-violated", "deadlock_free"),
            ("property-violated", "deterministic"),
            ("property-disproved", "reachable: on"),
            ("property-unproved", "deadlock_free"),
            ("property-unproved", "deterministic"),
            ("nondeterminism", "turn_off"),
            ("analysis-incomplete", "clean"),
        },
    ),
    Case(
        "island",
        """
automaton: island
locations: {home: {}, island: {}}
""",
        must={("unreachable-location", "island")},
        must_not={("unreachable-location", "home"), ("sink-location", "home")},
    ),
    Case(
        "dead_guard_prunes",
        """
automaton: gate
state: {x: {initial: 0, bounds: [0, 1]}}
locations: {a: {flow: {x: 1}}, b: {}}
edges:
  - {name: never, from: a, to: b, guard: x > 2}
""",
        must={("dead-edge", "never"), ("unreachable-location", "b")},
        must_not={("sink-location", "a")},
    ),
    Case(
        "strict_boundary_is_dead",
        """
automaton: edge_of_bounds
state: {x: {initial: 0, bounds: [0, 5]}}
locations: {a: {flow: {x: 1}}, b: {}}
edges:
  - {name: below_zero, from: a, to: b, guard: x < 0}
  - {name: at_five, from: a, to: b, guard: x >= 5}
""",
        must={("dead-edge", "below_zero")},
        must_not={("dead-edge", "at_five"), ("unreachable-location", "b")},
    ),
    Case(
        "sink",
        """
automaton: trap
state: {x: {initial: 0, bounds: [0, 10]}}
locations:
  filling: {flow: {x: 1}, invariant: x <= 1}
  forever: {flow: {x: 1}}
  draining: {flow: {x: -1}, invariant: x <= 1}
edges:
  - {name: spill, from: filling, to: draining, guard: x >= 5}
  - {name: rest, from: filling, to: forever, guard: x >= 5}
""",
        must={
            ("sink-location", "filling"),
            ("dead-edge", "spill"),
            ("unreachable-location", "draining"),
        },
        must_not={("sink-location", "forever"), ("sink-location", "draining")},
    ),
    Case(
        "nondeterministic",
        """
automaton: fork
state: {x: {initial: 0, bounds: [0, 10]}}
locations: {a: {flow: {x: 1}, invariant: x <= 3}, b: {}, c: {}, d: {}}
edges:
  - {name: first, from: a, to: b, guard: x >= 1}
  - {name: second, from: a, to: c, guard: x >= 2}
  - {name: ranked, from: a, to: d, guard: x >= 2, priority: 1}
  - {name: low, from: b, to: c, guard: x <= 1}
  - {name: high, from: b, to: d, guard: x > 1}
""",
        must={("nondeterminism", "second")},
        must_not={("nondeterminism", "ranked"), ("nondeterminism", "high")},
    ),
    Case(
        "linear_overlap_decided_exactly",
        """
automaton: planes
state: {x: {bounds: [0, 10]}, y: {bounds: [0, 10]}}
locations: {a: {}, b: {}, c: {}}
edges:
  - {name: p, from: a, to: b, guard: x - y >= 1}
  - {name: q, from: a, to: c, guard: y - x >= 1}
  - {name: r, from: b, to: c, guard: x + y >= 12}
  - {name: s, from: b, to: a, guard: x - y >= 5}
""",
        # box contraction alone leaves x in [3, 10], y in [4, 10] for p and q together;
        # only the linear program sees that x - y >= 1 and y - x >= 1 exclude each other
        must={("nondeterminism", "s")},
        must_not={("nondeterminism", "q"), ("dead-edge", "q")},
    ),
    Case(
        "zero_time",
        """
automaton: ping
state: {x: {initial: 0, bounds: [0, 10]}}
locations: {a: {flow: {x: 1}}, b: {flow: {x: 1}}, c: {flow: {x: 1}}}
edges:
  - {name: go, from: a, to: b}
  - {name: back, from: b, to: a, guard: x >= 0}
  - {name: tick, from: c, to: c, guard: x >= 1, reset: {x: 0}}
  - {name: leave, from: a, to: c, guard: x >= 5, priority: 1}
""",
        must={("zero-time-cycle", "go")},
        must_not={("zero-time-cycle", "tick")},
    ),
    Case(
        "bouncing_not_zeno_cycle",
        """
automaton: ball
parameters: {g: 9.81, e: 0.8}
state: {h: {initial: 10, bounds: [0, .inf]}, v: {bounds: [-20, 20]}}
labels: [bounce]
locations: {falling: {flow: {h: v, v: -g}, invariant: h >= 0}}
edges:
  - {name: bounce, from: falling, to: falling, label: bounce, guard: h <= 0 and v < 0,
     reset: {h: 0, v: -e*v}}
properties: {reachable: [falling], deadlock_free: true, deterministic: true}
""",
        must_not={
            ("zero-time-cycle", "bounce"),
            ("property-violated", "deadlock_free"),
            ("property-unproved", "deadlock_free"),
            ("sink-location", "falling"),
        },
    ),
    Case(
        "unused",
        """
automaton: leftovers
parameters: {k: 1.0, used: 2.0}
state: {x: {}}
inputs: [u, w]
labels: [ping, pong]
locations: {a: {flow: {x: used * w}}}
edges:
  - {from: a, to: a, label: pong, guard: x >= 1, reset: {x: 0}}
""",
        must={
            ("unused-declaration", "k"),
            ("unused-declaration", "u"),
            ("unused-declaration", "ping"),
        },
        must_not={
            ("unused-declaration", "used"),
            ("unused-declaration", "w"),
            ("unused-declaration", "pong"),
        },
    ),
    Case(
        "properties_violated",
        """
automaton: promises
state: {x: {initial: 0, bounds: [0, 10]}, y: {initial: 0, bounds: [-1, 1]}}
locations:
  start: {flow: {x: 1}, invariant: x <= 2}
  mid: {flow: {x: 1}, invariant: x <= 4}
  goal: {}
  never: {}
  end: {}
edges:
  - {name: step, from: start, to: mid, guard: x >= 2 and y > 0}
  - {name: stepb, from: start, to: mid, guard: x >= 2 and y < 0.5}
  - {name: arrive, from: mid, to: goal, guard: x >= 4}
  - {name: unreal, from: goal, to: never, guard: x > 20}
  - {name: finish, from: goal, to: end}
properties:
  reachable: [never, goal]
  unreachable: [goal]
  deadlock_free: true
  deterministic: true
""",
        must={
            ("property-disproved", "reachable: never"),
            ("property-unproved", "unreachable: goal"),
            ("property-unproved", "deterministic"),
            ("nondeterminism", "stepb"),
            ("dead-edge", "unreal"),
        },
        must_not={
            ("property-disproved", "reachable: goal"),
            ("property-violated", "deadlock_free"),
            ("property-violated", "unreachable: goal"),
            ("property-violated", "deterministic"),
            ("property-unproved", "deadlock_free"),
            ("unreachable-location", "never"),
        },
    ),
    Case(
        "deadlock_partial_cover",
        """
automaton: gap
state: {x: {initial: 0, bounds: [0, 10]}, y: {initial: 0, bounds: [-1, 1]}}
locations:
  run: {flow: {x: 1}, invariant: x <= 2}
  done: {}
edges:
  - {name: exit_up, from: run, to: done, guard: x >= 2 and y > 0}
properties: {deadlock_free: true}
""",
        must={("property-unproved", "deadlock_free")},
        must_not={("sink-location", "run"), ("dead-edge", "exit_up")},
    ),
    Case(
        "system_synchronised",
        None,  # built from SYSTEM_PARTS below
        must={
            ("unreachable-location", "heater.broken"),
            ("dead-edge", "heater.fail"),
            ("property-unproved", "unreachable: heater.warm"),
        },
        must_not={
            ("unreachable-location", "heater.warm"),
            ("dead-edge", "heater.heat"),
            ("dead-edge", "ctrl.start"),
        },
    ),
]

HEATER = """
automaton: heater
state: {T: {initial: 20, bounds: [0, 40]}}
labels: [start, stop, fail]
locations: {cold: {flow: {T: -1}}, warm: {flow: {T: 1}}, broken: {}}
edges:
  - {name: heat, from: cold, to: warm, label: start}
  - {name: cool, from: warm, to: cold, label: stop}
  - {name: fail, from: warm, to: broken, label: fail}
"""
CTRL = """
automaton: ctrl
state: {c: {initial: 0, bounds: [0, 10]}}
labels: [start, stop, fail]
locations: {idle: {flow: {c: 1}, invariant: c <= 5}, busy: {flow: {c: 1}, invariant: c <= 5}}
edges:
  - {name: start, from: idle, to: busy, label: start, guard: c >= 5, reset: {c: 0}}
  - {name: stop, from: busy, to: idle, label: stop, guard: c >= 5, reset: {c: 0}}
  - {name: fail, from: idle, to: idle, label: fail, guard: c >= 5, reset: {c: 0}}
"""
SYSTEM = """
system: plant
components:
  - {spec: heater.yaml}
  - {spec: ctrl.yaml}
properties: {unreachable: [heater.warm], deadlock_free: true}
"""


def _load(case: Case, tmp_path_factory: pytest.TempPathFactory) -> hybrid.Automaton | hybrid.System:
    if case.spec is not None:
        return hybrid.load_text(case.spec, file=f"{case.name}.yaml")
    folder = tmp_path_factory.mktemp(case.name)
    (folder / "heater.yaml").write_text(HEATER)
    (folder / "ctrl.yaml").write_text(CTRL)
    (folder / "plant.yaml").write_text(SYSTEM)
    return hybrid.load(folder / "plant.yaml")


@pytest.fixture(scope="module")
def analyses(tmp_path_factory: pytest.TempPathFactory) -> dict[str, object]:
    return {case.name: analyse(_load(case, tmp_path_factory)) for case in CASES}


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.name)
@pytest.mark.parametrize("check_fn", CHECKS, ids=lambda f: f.__name__)
def test_check_against_table(check_fn, case, analyses):
    rules = RULE_OF[check_fn]
    findings = check_fn(analyses[case.name])
    got = {(f.rule, f.where) for f in findings}
    assert {r for r, _ in got} <= set(rules), f"{check_fn.__name__} produced another rule: {got}"
    expected = {m for m in case.must if m[0] in rules}
    assert expected <= got, f"missing {expected - got}; got {got}"
    forbidden = {m for m in case.must_not if m[0] in rules}
    assert not (forbidden & got), f"unexpected {forbidden & got}"
    for f in findings:
        assert f.line >= 1 and f.column >= 1 and f.file
        assert f.severity == RULES[f.rule].severity


def test_every_rule_is_covered_both_ways():
    rules = {r for group in RULE_OF.values() for r in group} - {"analysis-incomplete"}
    assert rules <= {r for c in CASES for r, _ in c.must}
    assert rules | {"analysis-incomplete"} <= {r for c in CASES for r, _ in c.must_not}


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.name)
def test_check_runs_every_check(case, analyses, tmp_path_factory):
    analysis = analyses[case.name]
    assert sorted(run_checks(analysis), key=lambda f: f.sort_key()) == run_checks(analysis)
    report = check(analysis.model)
    assert list(report.findings) == run_checks(analysis)
    assert report.ok == (not any(f.severity == "error" for f in report.findings))


def test_clean_case_has_no_findings(analyses):
    assert run_checks(analyses["clean_thermostat"]) == []


def test_witness_of_unreachable_property_is_a_path(analyses):
    (finding,) = [
        f
        for f in property_violations(analyses["properties_violated"])
        if f.where == "unreachable: goal"
    ]
    assert [m for _, m in finding.witness] == ["start", "mid", "goal"]
    assert finding.witness[0][0] is None
    assert finding.witness[1][0] in ("step", "stepb") and finding.witness[2][0] == "arrive"
    assert "start -[" in finding.message and "]-> goal" in finding.message


def test_deadlock_witness_points_at_the_uncovered_location(analyses):
    (finding,) = property_violations(analyses["deadlock_partial_cover"])
    assert "'run'" in finding.message
    assert finding.witness == ((None, "run"),)


def test_exploration_limit_gives_a_note_and_no_reachability_claims(tmp_path_factory):
    case = next(c for c in CASES if c.name == "system_synchronised")
    analysis = analyse(_load(case, tmp_path_factory), max_states=1)
    findings = run_checks(analysis)
    rules = {f.rule for f in findings}
    assert "analysis-incomplete" in rules
    assert "unreachable-location" not in rules
    note = next(f for f in findings if f.rule == "analysis-incomplete")
    assert note.severity == "note"


@pytest.mark.parametrize("case", BLOCKED_STARTS, ids=lambda c: c.name)
def test_a_blocked_start_is_a_run_blocked_at_its_start(case, analyses, tmp_path_factory):
    """Each initial point of a ``blocked-start`` case (the set's ends and its nominal value)
    ends ``blocked`` at t = 0 in the simulator; a start reported as not blocked is run too."""
    model = _load(case, tmp_path_factory)
    reported = bool(blocked_starts(analyses[case.name]))
    state = model.states[0]
    ends = (state.initial, state.initial) if state.initial_range is None else (
        state.initial_range.lo, state.initial_range.hi)  # fmt: skip
    for x in sorted({*ends, state.initial}):
        run = hybrid.simulate(model, t_end=1.0, initial={state.name: x}, handle_sigint=False)
        at_start = run.termination.cause == "blocked" and run.termination.t == 0.0
        if reported:
            assert at_start, (case.name, x, run.termination)
        elif case.name == "start_outside_left_at_once":
            assert run.jumps and run.jumps[0].t == 0.0  # left at once, not blocked
