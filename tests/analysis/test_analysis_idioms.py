"""The field's standard idioms give no error-level finding (issue 11)."""

from __future__ import annotations

import hybrid
from hybrid.analysis import check

CLOCK = """
automaton: clock
parameters: {T: 100}
state: {clk: {initial: 0, bounds: [0, 100]}}
locations: {running: {flow: {clk: 1}, invariant: clk <= T}}
"""
THERMOSTAT = """
automaton: heater
state: {x: {initial: 20, bounds: [0, 40]}}
locations:
  off: {flow: {x: -0.1*(x - 10)}, invariant: x >= 18}
  on: {flow: {x: 0.1*(30 - x)}, invariant: x <= 22}
edges:
  - {name: heat, from: off, to: on, guard: x <= 18}
  - {name: rest, from: on, to: off, guard: x >= 22}
"""
BROKEN = """
automaton: broken
state: {x: {initial: 0, bounds: [0, 10]}}
locations: {a: {flow: {x: 1}, invariant: x <= 5}, b: {}}
edges:
  - {name: late, from: a, to: b, guard: x >= 7}
"""


def test_a_global_clock_is_a_note_not_an_error():
    system = hybrid.compose(hybrid.load_text(CLOCK), hybrid.load_text(THERMOSTAT))
    report = check(system)
    assert report.ok
    (note,) = report.findings
    assert (note.rule, note.severity, note.where) == ("sink-location", "note", "clock.running")
    assert "no edge out" in note.message
    assert not report.failed(strict=True)  # notes never fail a run


def test_a_location_whose_edges_can_never_fire_is_still_an_error():
    report = check(hybrid.load_text(BROKEN))
    sink = report.by_rule("sink-location")
    assert [(f.where, f.severity) for f in sink] == [("a", "error")]
    assert not report.ok
