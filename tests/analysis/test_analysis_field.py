"""`hybrid check` with the field's constructs, in the sound and the unsound direction.

Each "never" is checked against a run (or the lack of one) worked out by hand:
a forbidden state proved unreachable, and one reported with its witness; an
initial set whose corner reaches a location its nominal point does not; an
input range that makes an edge live or dead; urgent locations (edges fire only
on entry; a sink when none can); several initial locations explored; a
template bound twice.
"""

from __future__ import annotations

from pathlib import Path

import pytest

import hybrid
from hybrid.analysis import check
from hybrid.analysis.context import analyse
from hybrid.analysis.forbidden import flowing_box

TANK = """
automaton: tank
state: {level: {initial: 1, bounds: [0, 10]}}
locations:
  filling: {flow: {level: 1}, invariant: level <= 5}
  draining: {flow: {level: -2}, invariant: level >= 1}
edges:
  - {name: full, from: filling, to: draining, guard: level >= 5}
  - {name: empty, from: draining, to: filling, guard: level <= 1}
properties:
  forbidden:
    - {location: filling, when: "level > 5.5"}
    - {location: draining, when: "level < 0.5"}
    - {location: draining, when: "level >= 4.9"}
"""


def _rules(report: hybrid.Report) -> list[tuple[str, str]]:
    return [(f.rule, f.where) for f in report.findings]


def test_a_forbidden_state_is_proved_unreachable_or_reported_with_a_witness() -> None:
    report = check(hybrid.load_text(TANK, file="tank.yaml"))
    # level <= 5 while filling (its invariant) and on entry (1 at the start, 1 from `empty`);
    # level >= 1 while draining, 5 on entry: the first two are unreachable, the third is
    # reached at t = 4, entering draining at level 5
    # the analysis alone does not simulate: the third is not proved, with a candidate path
    (finding,) = report.findings
    assert (finding.rule, finding.severity) == ("property-unproved", "warning")
    assert finding.where == "forbidden: draining with level >= 4.9"
    assert (finding.file, finding.line) == ("tank.yaml", 14)
    assert finding.witness == ((None, "filling"), ("full", "draining"))
    run = hybrid.simulate(hybrid.load_text(TANK), t_end=4.5)
    assert run.jumps[0].t == pytest.approx(4.0) and run.jumps[0].after["level"] >= 4.9
    # with reach (hybrid.check, a horizon): refuted by that simulated run, an error
    (violated,) = hybrid.check(hybrid.load_text(TANK, file="tank.yaml"), reach_t_end=5.0).findings
    assert (violated.rule, violated.severity) == ("property-violated", "error")
    assert (violated.file, violated.line) == ("tank.yaml", 14)
    assert "reached at t = 4 " in violated.message


def test_flows_narrow_the_states_of_a_location_to_one_side_of_its_entries() -> None:
    # no invariant bounds x below in `up`, but x' = 1 and x enters at 2: x >= 2 there
    m = hybrid.load_text(
        """
automaton: climb
state: {x: {initial: 2}}
locations: {up: {flow: {x: 1}}}
properties: {forbidden: [{location: up, when: x < 1.5}, {location: up, when: x < 2.5}]}
"""
    )
    analysis = analyse(m)
    box = flowing_box(analysis.facts[0], "up")
    assert box is not None and box["x"].lo == 2.0 and box["t"].lo == 0.0
    assert [f.where for f in check(m).findings] == ["forbidden: up with x < 2.5"]


def test_a_forbidden_combination_of_locations_in_a_system(tmp_path: Path) -> None:
    (tmp_path / "plant.yaml").write_text(
        "automaton: plant\nlabels: [go]\nlocations: {idle: {}, overflow: {}}\n"
        "edges: [{from: idle, to: overflow, label: go}]\n"
    )
    (tmp_path / "ctrl.yaml").write_text(
        "automaton: ctrl\nlabels: [go]\nlocations: {idle: {}, busy: {}}\n"
        "edges: [{from: idle, to: busy, label: go}]\n"
    )
    (tmp_path / "sys.yaml").write_text(
        "system: s\ncomponents: [{spec: plant.yaml}, {spec: ctrl.yaml}]\n"
        "properties:\n  forbidden:\n"
        "    - {locations: {plant: overflow, ctrl: idle}}\n"
        "    - {locations: {plant: overflow, ctrl: busy}}\n"
    )
    report = check(hybrid.load(tmp_path / "sys.yaml"))
    # `go` moves both at once: overflow never meets idle; the other is not proved
    (finding,) = report.by_rule("property-unproved")
    assert finding.where == "forbidden: plant.overflow, ctrl.busy"
    assert finding.witness == (
        (None, "plant.idle|ctrl.idle"),
        ("plant.idle->overflow#0+ctrl.idle->busy#0", "plant.overflow|ctrl.busy"),
    )
    # with reach it is refuted by a run: `go` fires at once (its guard is true)
    (violated,) = hybrid.check(hybrid.load(tmp_path / "sys.yaml"), reach_t_end=1.0).findings
    assert (violated.rule, violated.where) == ("property-violated", finding.where)
    assert "reached at t = 0 " in violated.message


CORNER = """
automaton: corner
state: {x: {initial: [0, 2]}}
locations:
  a: {flow: {x: 0}, invariant: x <= 1.2}
  far: {}
edges:
  - {name: leap, from: a, to: far, guard: x >= 1.5}
"""


def test_an_initial_corner_reaches_what_the_nominal_point_does_not() -> None:
    # x never changes in `a`; `leap` needs x >= 1.5, which only the entry can give
    m = hybrid.load_text(CORNER)
    assert not [f for f in check(m).findings if f.rule in ("unreachable-location", "dead-edge")]
    run = hybrid.simulate(m, t_end=5.0)  # from the midpoint x = 1, x stays 1
    assert run.jumps == [] and set(run.location) == {"a"}
    corner = hybrid.simulate(m, t_end=5.0, initial={"x": 2.0})
    assert [j.edge for j in corner.jumps] == ["leap"] and corner.jumps[0].t == 0.0
    point = hybrid.load_text(CORNER.replace("[0, 2]", "1"))  # the nominal point alone
    assert {f.rule for f in check(point).findings} == {"unreachable-location", "dead-edge"}


GATE = """
automaton: gate
state: {x: {initial: 0}}
inputs: {u: {range: RANGE}}
locations: {closed: {flow: {x: 1}}, open: {}}
edges:
  - {name: lift, from: closed, to: open, guard: u > 0.5}
"""


def test_an_input_range_makes_an_edge_dead_or_live() -> None:
    dead = check(hybrid.load_text(GATE.replace("RANGE", "[0, 0.4]")))
    assert {f.where for f in dead.by_rule("dead-edge")} == {"lift"}
    assert "with inputs within their ranges (u in [0, 0.4])" in dead.by_rule("dead-edge")[0].message
    live = hybrid.load_text(GATE.replace("RANGE", "[0, 1]"))
    assert not check(live).findings
    # u = 0.75 (the midpoint... of [0.5, 1]) fires at once; any constant <= 0.5 never does
    run = hybrid.simulate(live, t_end=1.0, inputs={"u": lambda t: 0.75})
    assert [j.edge for j in run.jumps] == ["lift"]
    unbounded = hybrid.load_text(GATE.replace("{range: RANGE}", "{}"))
    assert not check(unbounded).by_rule("dead-edge")  # an input with no range is anything


URGENT = """
automaton: relay
state: {x: {initial: 0, bounds: [0, 10]}}
locations:
  charge: {flow: {x: 1}, invariant: x <= 1}
  decide: {urgent: true, flow: {x: 1}}
  fire: {}
edges:
  - {name: full, from: charge, to: decide, guard: x >= 1}
  - {name: go, from: decide, to: fire, guard: GUARD}
"""


def test_an_urgent_location_never_flows() -> None:
    # x enters decide at 1; flowing would take it to 2, but no time passes there
    report = check(hybrid.load_text(URGENT.replace("GUARD", "x >= 2")))
    assert ("dead-edge", "go") in _rules(report)
    lazy = URGENT.replace("GUARD", "x >= 2").replace("urgent: true, ", "")
    assert not check(hybrid.load_text(lazy)).findings  # flowing, decide would reach 2
    (sink,) = report.by_rule("sink-location")
    assert sink.severity == "error" and "urgent location 'decide' is a sink" in sink.message
    run = hybrid.simulate(hybrid.load_text(URGENT.replace("GUARD", "x >= 2")), t_end=5.0)
    assert run.termination.cause == "blocked" and run.termination.t == pytest.approx(1.0)
    fine = hybrid.load_text(
        URGENT.replace("GUARD", "x >= 0.5") + "properties: {deadlock_free: true}\n"
    )
    assert not check(fine).findings
    assert [j.edge for j in hybrid.simulate(fine, t_end=5.0).jumps] == ["full", "go"]


def test_an_urgent_location_without_edges_is_an_error_not_a_note() -> None:
    m = hybrid.load_text("automaton: a\nlocations: {l: {urgent: true}}\n")
    (sink,) = check(m).by_rule("sink-location")
    assert sink.severity == "error" and "no edge out" in sink.message
    assert hybrid.simulate(m, t_end=1.0).termination.cause == "blocked"


def test_every_initial_location_is_explored() -> None:
    m = hybrid.load_text(
        """
automaton: two_starts
state: {x: {initial: 0}}
locations: {a: {}, b: {}, c: {}, d: {}}
initial: {location: [a, b]}
edges:
  - {from: b, to: c}
properties: {unreachable: [c]}
"""
    )
    report = check(m)
    assert [f.where for f in report.by_rule("unreachable-location")] == ["d"]
    assert "unreachable from 'a', 'b'" in report.by_rule("unreachable-location")[0].message
    (unproved,) = report.by_rule("property-unproved")
    assert unproved.witness == ((None, "b"), ("b->c#0", "c"))
    alone = hybrid.load_text(
        "automaton: a1\nlocations: {a: {}, b: {}, c: {}}\nedges: [{from: b, to: c}]\n"
    )
    assert [f.where for f in check(alone).by_rule("unreachable-location")] == ["b", "c"]


def test_a_template_bound_twice_is_checked_per_instance(tmp_path: Path) -> None:
    (tmp_path / "valve.yaml").write_text(
        "automaton: valve\nstate: {p: {initial: 0, bounds: [0, 10]}}\ninputs: [q]\n"
        "locations: {shut: {flow: {p: 1}}, open: {}}\n"
        "edges: [{name: vent, from: shut, to: open, guard: q > 0 and p >= 5}]\n"
    )
    (tmp_path / "src.yaml").write_text(
        "automaton: src\nstate: {a: {initial: 1, bounds: [1, 1]}, b: {initial: -1, bounds: [-1, -1]}}\n"
        "locations: {on: {}}\n"
    )
    (tmp_path / "sys.yaml").write_text(
        "system: pair\ncomponents:\n  - {spec: src.yaml}\n"
        "  - {spec: valve.yaml, as: v1, rename: {q: a, p: p1}}\n"
        "  - {spec: valve.yaml, as: v2, rename: {q: b, p: p2}}\n"
        "properties: {reachable: [v1.open]}\n"
    )
    m = hybrid.load(tmp_path / "sys.yaml")
    report = check(m)
    # each instance reads another state variable, within its bounds: a = 1 opens v1 at
    # p1 = 5; b = -1 never lets v2 vent
    assert _rules(report) == [("unreachable-location", "v2.open"), ("dead-edge", "v2.vent")]
    run = hybrid.simulate(m, t_end=6.0)
    assert [j.edge for j in run.jumps] == ["v1.vent"] and run.jumps[0].t == pytest.approx(5.0)


def test_graphs_mark_every_initial_location_and_the_urgent_ones(tmp_path: Path) -> None:
    from hybrid.analysis import system_graph
    from hybrid.export.diagrams import to_dot, to_mermaid

    m = hybrid.load_text(
        "automaton: g\nlocations: {a: {}, b: {urgent: true}, c: {}}\n"
        "initial: {location: [a, c]}\nedges: [{from: a, to: b}, {from: b, to: c}]\n"
    )
    graph = system_graph(m)
    assert {n for n, d in graph.nodes(data=True) if d["initial"]} == {"a", "c"}
    dot = to_dot(graph)
    assert '"__start__" -> "a";' in dot and '"__start__" -> "c";' in dot
    assert '"b" [label="b\\nurgent", peripheries=2];' in dot
    mermaid = to_mermaid(graph)
    assert "[*] --> s0" in mermaid and "[*] --> s2" in mermaid and "s1 : urgent" in mermaid
    (tmp_path / "g.yaml").write_text(
        "automaton: g\nlabels: [go]\nlocations: {a: {}, b: {urgent: true}}\n"
        "initial: {location: [a, b]}\nedges: [{from: a, to: b, label: go}, {from: b, to: a, label: go}]\n"
    )
    (tmp_path / "s.yaml").write_text(
        "system: s\ncomponents: [{spec: g.yaml, as: one}, {spec: g.yaml, as: two}]\n"
    )
    product = system_graph(hybrid.load(tmp_path / "s.yaml"))
    assert {n for n, d in product.nodes(data=True) if d["initial"]} == {
        "one.a|two.a",
        "one.a|two.b",
        "one.b|two.a",
        "one.b|two.b",
    }
    assert product.nodes["one.a|two.b"]["urgent"] and not product.nodes["one.a|two.a"]["urgent"]


def test_more_initial_modes_than_the_cap_make_an_incomplete_exploration() -> None:
    from hybrid.analysis.product import MAX_INITIAL_MODES

    comp = (
        "automaton: c{i}\nlabels: [go]\nlocations: {{a: {{}}, b: {{}}}}\n"
        "initial: {{location: [a, b]}}\nedges: [{{from: a, to: b, label: go}}]\n"
    )
    # 17 components sharing a label, each starting in a or b: 2**17 initial modes
    parts = [hybrid.load_text(comp.format(i=i)) for i in range(17)]
    assert MAX_INITIAL_MODES < 2**17
    (note,) = check(hybrid.compose(*parts)).findings
    assert note.rule == "analysis-incomplete" and note.severity == "note"
    assert f"more than {MAX_INITIAL_MODES:,} initial modes" in note.message


def test_a_cycle_through_urgent_locations_takes_no_time() -> None:
    m = hybrid.load_text(
        """
automaton: ping
state: {x: {initial: 0, bounds: [0, 10]}}
locations:
  wait: {flow: {x: 1}, invariant: x <= 1}
  ping: {urgent: true}
  pong: {urgent: true}
edges:
  - {name: go, from: wait, to: ping, guard: x >= 1}
  - {name: there, from: ping, to: pong}
  - {name: back, from: pong, to: ping, guard: x >= 0.5}
"""
    )
    (cycle,) = check(m).by_rule("zero-time-cycle")
    assert cycle.where == "there" and [t for t, _ in cycle.witness[1:]] == ["there", "back"]
    run = hybrid.simulate(m, t_end=5.0, max_jumps_per_instant=50)
    assert run.termination.cause == "zeno" and run.termination.zeno_time == pytest.approx(1.0)
    calm = hybrid.load_text(
        "automaton: ping\nstate: {x: {initial: 0, bounds: [0, 10]}}\nlocations:\n"
        "  wait: {flow: {x: 1}, invariant: x <= 1}\n  ping: {urgent: true}\n"
        "edges:\n  - {name: go, from: wait, to: ping, guard: x >= 1}\n"
        "  - {name: reset, from: ping, to: wait, reset: {x: 0}}\n"
    )
    assert not check(calm).findings  # the reset lets time pass again before `go`
    assert len(hybrid.simulate(calm, t_end=3.5).jumps) == 6  # at t = 1, 1, 2, 2, 3, 3
