"""Reach against the simulator's semantics where they are easy to get wrong.

- A run may start (or enter a location) outside its invariant: the simulator
  stores that point and ends ``blocked`` there (docs/semantics.md, "Invariants
  and blocked"). The entry box is a set of its own, so the point is covered and a
  forbidden set there is refuted by that run.
- A location may define a signal its own way: a forbidden condition reading it is
  decided with each location's definition, not the initial one's.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from pathlib import Path

import pytest

import hybrid

OUTSIDE = """
automaton: outside
state: {x: {initial: [0, 2]}}
locations: {l: {flow: {x: 1}, invariant: x <= 1}}
properties: {forbidden: [{when: x > 1.5}]}
"""


def test_an_entry_outside_the_invariant_is_covered_and_refutes() -> None:
    model = hybrid.load_text(OUTSIDE)
    run = hybrid.simulate(model, 2.0, initial={"x": 1.8}, handle_sigint=False)
    assert run.termination.cause == "blocked" and run.t[-1] == 0.0
    result = hybrid.reach(model, 2.0, step=0.01)
    first = [s for s in result.sets if s.t[0] <= 0.0 <= s.t[1]]
    assert any(s.lo[0] <= 1.8 <= s.hi[0] for s in first)
    (entry,) = result.properties
    assert entry.verdict == "refuted" and entry.witness_time == 0.0
    # while flowing, x stays within the invariant: no set after t = 0 goes above 1 (+ slack)
    assert max(s.hi[0] for s in result.sets if s.t[0] > 0.0) <= 1.0 + 1e-6


SIGNAL = """
automaton: relabel
state: {x: {initial: 0}}
signals: {s: x}
locations:
  a: {flow: {x: 1}}
  b: {flow: {x: 0}, signals: {s: x + 10}}
edges: [{from: a, to: b, guard: x >= 1}]
properties: {forbidden: [{location: b, when: s > 5}, {location: a, when: s > 5}]}
"""


def test_a_signal_is_read_as_each_location_defines_it() -> None:
    # in b, s = x + 10 = 11 > 5 (x is 1 on entry); in a, s = x: runs jump at x = 1, but
    # the may-semantics lets a flow on (no invariant), reaching x = 5 at t = 5: within
    # 3 s that is proved, within 6 s unknown (the sets meet it, no run does)
    model = hybrid.load_text(SIGNAL)
    result = hybrid.reach(model, 3.0, max_jumps=1, step=0.01)
    assert [p.verdict for p in result.properties] == ["refuted", "proved"]
    result = hybrid.reach(model, 6.0, max_jumps=1, step=0.01)
    b, a = result.properties
    assert b.verdict == "refuted" and b.witness is not None
    assert b.witness_time == 1.0 or math.isclose(b.witness_time or 0.0, 1.0, rel_tol=1e-6)
    assert a.verdict == "unknown" and a.first_contact is not None and a.first_contact > 4.9


def test_a_signal_that_is_not_affine_is_named_with_its_definitions() -> None:
    model = hybrid.load_text(
        "automaton: a\nstate: {x: {initial: 1}}\nsignals: {s: x * x, r: s}\n"
        "locations: {l: {flow: {x: 2 * r}}}\n",
        file="a.yaml",
    )
    with pytest.raises(hybrid.SpecError) as info:
        hybrid.reach(model, 1.0)
    assert (info.value.file, info.value.line, info.value.column) == ("a.yaml", 4, 31)
    assert "the flow of x in location 'l' is not affine" in str(info.value)
    assert "'r' (signals: r = 's'; s = 'x * x')" in str(info.value)


def test_a_forbidden_set_behind_a_jump_is_refuted_by_a_simulated_run() -> None:
    # x climbs from [0, 0.5] in a, jumps to b at x = 1 (reset x := 2 x), climbs on: in b
    # x = 2 + (t - t_jump) > 2.5 half a second after the jump; runs sampled from the
    # initial set find it (the support candidate covers the initial mode only)
    model = hybrid.load_text(
        """
automaton: two_stage
state: {x: {initial: [0, 0.5]}}
locations: {a: {flow: {x: 1}}, b: {flow: {x: 1}}}
edges: [{from: a, to: b, guard: x >= 1, reset: {x: 2 * x}}]
properties: {forbidden: [{location: b, when: x > 2.5}, {location: b, when: x < 1.9}]}
"""
    )
    result = hybrid.reach(model, 2.0, max_jumps=1, step=0.01)
    reached, below = result.properties
    assert reached.verdict == "refuted" and reached.witness is not None
    assert reached.witness.jumps and reached.witness.jumps[0].target == "b"
    # where the run enters the set: half a second after its jump (x = 2 + (t - t_jump))
    assert reached.witness_time == pytest.approx(reached.witness.jumps[0].t + 0.5, abs=1e-9)
    # in b, x starts at 2 (the guard x >= 1 is met at 1, widened by 1e-7): never below 1.9
    assert below.verdict == "proved"


GRAZE = """
automaton: osc
state: {x: {initial: [0.9, 1.1]}, y: {initial: 0}}
locations: {a: {flow: {x: y, y: -x}}}
properties: {forbidden: [{when: x >= 1.1000001}]}
"""


def test_the_first_contact_is_never_before_the_start() -> None:
    """x = x0 cos t never exceeds 1.1, but the initial box widened by rounding meets the
    entry at once: 'meets it from t = -5e-12' was reported, before any run begins."""
    (entry,) = hybrid.reach(hybrid.load_text(GRAZE), 6.0, step=0.05).properties
    assert entry.verdict == "unknown"
    assert entry.first_contact == 0.0 and "meets it from t = 0," in entry.message


# One variable near 1e9 makes the simulator's boundary band 0.1 (1e-10 (1 + max |x_i|)):
# it takes y >= 0 at y = -0.05 (moving into it), and keeps y <= 0 until y = 0.1.
BIG_GUARD = """
automaton: band
state: {big: {initial: 1.0e9}, y: {initial: -0.05}}
locations: {a: {flow: {y: 1}}, b: {flow: {y: 1}}}
edges: [{from: a, to: b, guard: y >= 0}]
properties: {forbidden: [{location: b, when: y <= -0.01}]}
"""
BIG_INVARIANT = """
automaton: band_inv
state: {pos: {initial: 10000.0}, y: {initial: -1.0e-6}}
locations: {a: {flow: {pos: 0, y: 5.0e-7}, invariant: y <= 0}}
properties: {forbidden: [{location: a, when: y >= 5.0e-7}]}
"""


@pytest.mark.parametrize(
    ("text", "location", "forbidden"),
    [(BIG_GUARD, "b", lambda y: y <= -0.01), (BIG_INVARIANT, "a", lambda y: y >= 5e-7)],
    ids=["guard", "invariant"],
)
def test_the_simulator_s_band_over_the_whole_state_is_covered(
    text: str, location: str, forbidden: Callable[[float], bool]
) -> None:
    """Both were 'proved' while the simulator's own run enters the forbidden set: reach
    widened a condition only by the size of the variables it reads."""
    model = hybrid.load_text(text)
    run = hybrid.simulate(model, 10.0, handle_sigint=False)
    places = run.location.tolist()
    assert any(p == location and forbidden(y) for p, y in zip(places, run["y"].tolist(), strict=True))
    result = hybrid.reach(model, 10.0, step=0.01)
    assert result.properties[0].verdict != "proved"
    # every stored point of the run lies in a set of its location, at its time
    for k, place in enumerate(places):
        t, x = float(run.t[k]), run.states[k]
        assert any(
            s.location == place and s.t[0] <= t <= s.t[1] and all(s.lo <= x) and all(x <= s.hi)
            for s in result.sets
        ), (t, x)


def test_a_witness_holds_the_condition_as_written() -> None:
    """x stays exactly 1: 'x > 1' and 'x >= 1 + 5e-10' were refuted by points within 1e-9."""
    level = hybrid.load_text(
        "automaton: level\nstate: {x: {initial: 1}}\nlocations: {a: {flow: {x: 0}}}\n"
        "properties: {forbidden: [{when: x > 1}, {when: x >= 1.0000000005}, {when: x >= 1}]}\n"
    )
    strict, above, closed = hybrid.reach(level, 1.0, step=0.01).properties
    assert strict.verdict == above.verdict == "unknown"
    assert closed.verdict == "refuted" and closed.witness_time == 0.0


def test_a_witness_starts_in_the_initial_location_it_was_found_from() -> None:
    """Found from 'b' (x' = 1 from 0.5), the witness was replayed from 'a' (x' = 0) and
    never entered the set; its overrides left the location out."""
    multi = hybrid.load_text(
        "automaton: multi\nstate: {x: {initial: [0, 0.5]}}\n"
        "locations: {a: {flow: {x: 0}}, b: {flow: {x: 1}}}\ninitial: {location: [a, b]}\n"
        "properties: {forbidden: [{location: b, when: x >= 1}]}\n"
    )
    (entry,) = hybrid.reach(multi, 2.0, step=0.01).properties
    assert entry.verdict == "refuted" and entry.witness_location == "b"
    run = entry.witness
    assert run is not None and set(run.location.tolist()) == {"b"}
    assert run["x"][-1] >= 1.0 and entry.witness_time == pytest.approx(0.5, abs=0.02)


@pytest.mark.parametrize("step", [0.1, 0.01])
def test_an_exact_refutation_reports_where_its_run_enters_not_its_step(step: float) -> None:
    """x' = 1 from 0.5 in b meets x >= 1 at t = 0.5; the exact walk meets it at a step point
    past that (0.6 at step 0.1, 0.5005 by default) and reported that step's time."""
    multi = hybrid.load_text(
        "automaton: multi\nstate: {x: {initial: [0, 0.5]}}\n"
        "locations: {a: {flow: {x: 0}}, b: {flow: {x: 1}}}\ninitial: {location: [a, b]}\n"
        "properties: {forbidden: [{location: b, when: x >= 1}]}\n"
    )
    (entry,) = hybrid.reach(multi, 2.0, step=step).properties
    assert entry.verdict == "refuted" and "propagated exactly" in entry.message
    assert entry.witness_time == pytest.approx(0.5, abs=1e-9)


def test_a_visit_between_stored_points_is_the_witness_time() -> None:
    """x' = 1 from 0 passes 0.5 <= x <= 0.6 at t in [0.5, 0.6] between two stored points of
    its run (0.111 and 1, the steps growing), and is put back to 0.5 by the jump at t = 1:
    the first stored point in the set is at t = 1, which was reported."""
    model = hybrid.load_text(
        "automaton: reent\nstate: {x: {initial: 0}}\n"
        "locations: {l1: {flow: {x: 1}}, l2: {flow: {x: 0}}}\n"
        "edges: [{from: l1, to: l2, guard: x >= 1, reset: {x: 0.5}}]\n"
        "properties: {forbidden: [{when: x >= 0.5 and x <= 0.6}]}\n"
    )
    (entry,) = hybrid.reach(model, 2.0).properties
    assert entry.verdict == "refuted" and "simulated run" in entry.message
    assert entry.witness_time == pytest.approx(0.5, abs=1e-9)
    run = entry.simulated
    assert run is not None and not any(0.5 <= x <= 0.6 for x in run["x"][run.j == 0])


SYNCED = {
    "C.yaml": """
automaton: C
state: {x: {initial: 0}}
locations:
  c1: {flow: {x: 1}}
  c2: {flow: {x: 1}, invariant: x >= 1}
  c3: {flow: {x: 0}}
  c4: {flow: {x: 0}}
labels: [go, stop]
initial: {location: [c1, c4]}
edges:
  - {from: c1, to: c2, label: go}
  - {from: c2, to: c3, guard: x == 1}
  - {from: c4, to: c3, label: stop}
""",
    "D.yaml": """
automaton: D
state: {k: {initial: 0}}
locations: {d1: {flow: {k: 1}}, d2: {flow: {k: 1}}, d3: {flow: {k: 0}}}
labels: [go, stop]
initial: {location: [d2, d1]}
edges:
  - {from: d1, to: d3, label: go, guard: k >= 1}
  - {from: d2, to: d3, label: stop, guard: k >= 2}
""",
    "CD.yaml": """
system: CD
components: [{spec: C.yaml}, {spec: D.yaml}]
properties:
  forbidden:
    - {locations: {C: c3, D: d3}, when: "x <= 1.5"}
    - {locations: {C: c3, D: d3}, when: "k >= 1.5"}
""",
}


def test_a_witness_is_searched_from_every_initial_mode(tmp_path: Path) -> None:
    """(c3, d3) is reached only from initial modes other than the first, (c1, d2): from
    (c1, d1), go at k = 1 then x == 1 at t = 1 (x = 1); from (c4, d2), stop at k = 2 (x = 0,
    k = 2). Witnesses were tried from the first initial mode only: both entries unknown."""
    for name, text in SYNCED.items():
        (tmp_path / name).write_text(text, encoding="utf-8")
    near, late = hybrid.reach(hybrid.load(tmp_path / "CD.yaml"), 3.0).properties
    assert near.verdict == late.verdict == "refuted"
    assert near.witness_time == pytest.approx(1.0, abs=1e-9)
    assert near.witness_location == {"C": "c1", "D": "d1"}
    assert late.witness_time == pytest.approx(2.0, abs=1e-9)
    assert late.witness_location == {"C": "c4", "D": "d2"}


def test_check_reports_a_run_that_reaches_what_its_analysis_proved() -> None:
    """The analysis decides y >= 0 exactly, so b is entered with y >= 0 and 'b with
    y <= -0.01' was proved, check ok; the simulator's run enters b at y = -0.05."""
    model = hybrid.load_text(BIG_GUARD, file="band.yaml")
    assert hybrid.check(model).ok  # the analysis alone: its proof stands, as docs/check.md says
    (violated,) = [f for f in hybrid.check(model, reach_t_end=1.0).findings]
    assert (violated.rule, violated.line) == ("property-violated", 6)
    assert "reached at t = 0 by a simulated run" in violated.message


def test_an_entry_reads_a_signal_of_any_component_and_is_reached_where_it_enters(
    tmp_path: Path,
) -> None:
    """A system's 'qs >= 4' (qs = 5 q in b, q' = 1) was refused as 'not affine: qs' (qs is
    the second component's), and the witness said 'reached at t = 1', its first stored
    point inside, where the run enters at t = 4/5."""
    (tmp_path / "sig1.yaml").write_text(
        "automaton: sig1\nstate: {p: {initial: 0}}\nsignals: {ps: p}\nlocations: {a: {flow: {p: 1}}}\n"
    )
    (tmp_path / "sig2.yaml").write_text(
        "automaton: sig2\nstate: {q: {initial: 0}}\nsignals: {qs: 3 * q}\n"
        "locations: {b: {flow: {q: 1}, signals: {qs: 5 * q}}}\n"
    )
    (tmp_path / "sys.yaml").write_text(
        "system: sigsys\ncomponents: [{spec: sig1.yaml}, {spec: sig2.yaml}]\n"
        "properties: {forbidden: [{when: qs >= 4}, {locations: {sig1: a}, when: qs >= 4.5}]}\n"
    )
    first, second = hybrid.reach(hybrid.load(tmp_path / "sys.yaml"), 1.0, step=0.01).properties
    assert first.verdict == second.verdict == "refuted"
    assert first.witness_time == pytest.approx(0.8, abs=1e-9)
    assert second.witness_time == pytest.approx(0.9, abs=1e-9)


def test_an_ok_bounded_by_the_horizon_says_so(tmp_path: Path) -> None:
    """x = t reaches 5 at t = 5: within t <= 4 the entry is proved, and check said only 'ok'."""
    from support import run_cli

    spec = tmp_path / "horizon.yaml"
    spec.write_text(
        "automaton: horizon\nstate: {x: {initial: 0}}\nlocations: {a: {flow: {x: 1}}}\n"
        "checks: {reach: {t_end: 4}}\nproperties: {forbidden: [{when: x >= 5}]}\n"
    )
    done = run_cli("check", spec)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == f"{spec}: ok (forbidden states: within t <= 4 and 10 jumps)"
    later = run_cli("check", spec, "--reach-t-end", "6")
    assert later.returncode == 1 and "property-violated" in later.stdout
    assert "reached at t = 5 " in later.stdout
