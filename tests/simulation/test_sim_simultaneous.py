"""Jumps of several components at one instant: every one due there fires, in the documented order.

Three defects of composed systems, each pinned by a hand computation, on both backends:

1. Two components whose equality guards hold at the same instant: after one of
   them jumps, the other's guard is decided at the new point, on its level and
   moving away. It used to be decided as at the start of a stay (a state that
   starts on a level and leaves it has not reached it), so it never fired and
   its clock ran on for ever. A level the flow reached at an instant is still
   reached after jumps at that instant that leave it where it is
   (docs/semantics.md, "Several components at one instant").
2. Components simulated apart (the scipy backend runs independent groups on
   their own) must take the jumps of one instant in the product's order
   (priority, then component, then edge order) and list every group's enabled
   transitions in each jump, as the compiled backend (which runs the product)
   does.
3. A stuck component (its invariant false at the start) beside one that loops
   without time passing: the product jumps while something is enabled, so the
   run ends as ``zeno`` (or ``max_jumps``), never ``blocked``.
"""

from __future__ import annotations

from pathlib import Path

import pytest
from support import assert_no_traceback, read_json, run_cli

import hybrid
from hybrid.simulation.apart import independent_groups

TIMER = """
automaton: timer
description: x counts up at unit rate and wraps to 0 when it reaches 20.
state: {{x: {{initial: 0.0}}}}
{labels}
locations:
  run: {{flow: {{x: 1}}}}
edges:
  - {{name: wrap, from: run, to: run, guard: x == 20, reset: {{x: 0}}, priority: {priority}}}
"""

TIMERS = """
system: timers
components:
  - {{spec: {a}, as: a, rename: {{x: xa}}}}
  - {{spec: {b}, as: b, rename: {{x: xb}}}}
  - {{spec: {c}, as: c, rename: {{x: xc}}}}
"""


def timers(tmp_path: Path, coupled: bool, c_first: bool) -> Path:
    """Three 20 s timers; ``coupled``: one group (a label they all declare); ``c_first``: c's
    edge has priority 1."""
    labels = "labels: [tick]" if coupled else ""
    (tmp_path / "timer.yaml").write_text(TIMER.format(labels=labels, priority=0))
    (tmp_path / "urgent_timer.yaml").write_text(TIMER.format(labels=labels, priority=1))
    c = "urgent_timer.yaml" if c_first else "timer.yaml"
    (tmp_path / "timers.yaml").write_text(TIMERS.format(a="timer.yaml", b="timer.yaml", c=c))
    return tmp_path / "timers.yaml"


def expected_timers(c_first: bool) -> list[tuple[float, str, tuple[str, ...], str]]:
    """By hand: every timer reaches 20 at t = 20, 40, 60 (before t_end = 70) and wraps there.

    At each instant all three are enabled; the highest priority fires (c with
    priority 1), else the first in the file; each jump leaves the others on
    their levels, so they fire next, at the same t, in the same order.
    """
    order = ["c", "a", "b"] if c_first else ["a", "b", "c"]
    rows = []
    for t in (20.0, 40.0, 60.0):
        left = ["a", "b", "c"]
        for k, who in enumerate(order):
            enabled = tuple(f"{n}.wrap" for n in left)
            how = "only" if len(left) == 1 else "priority" if c_first and k == 0 else "file order"
            rows.append((t, f"{who}.wrap", enabled, how))
            left.remove(who)
    return rows


@pytest.mark.parametrize("coupled", [True, False], ids=["one-group", "apart"])
@pytest.mark.parametrize("c_first", [False, True], ids=["file-order", "priority"])
def test_timers_reaching_their_levels_at_one_instant_all_wrap_there(
    tmp_path: Path, backend: str, coupled: bool, c_first: bool
) -> None:
    model = hybrid.load(timers(tmp_path, coupled, c_first))
    assert isinstance(model, hybrid.System)
    assert len(independent_groups(model)) == (1 if coupled else 3)  # the premise of the case
    run = hybrid.simulate(model, t_end=70.0, backend=backend)
    assert run.termination.cause == "t_end"
    want = expected_timers(c_first)
    got = [(j.t, j.edge, j.enabled, j.chosen_by) for j in run.jumps]
    assert [g[1:] for g in got] == [w[1:] for w in want]
    for (t, *_), (t_want, *_) in zip(got, want, strict=True):
        assert abs(t - t_want) <= 1e-9
    assert [j.j for j in run.jumps] == list(range(9))
    # each timer is 10 s past its last wrap at t_end
    for name in ("xa", "xb", "xc"):
        assert abs(run[name][-1] - 10.0) <= 1e-9


def test_the_events_file_lists_every_components_enabled_edges(
    tmp_path: Path, backend: str
) -> None:
    spec = timers(tmp_path, coupled=False, c_first=True)
    events = tmp_path / "events.json"
    result = run_cli(
        "simulate", spec, "--t-end", "70", "--events", events, "--backend", backend,
        timeout=300,
    )  # fmt: skip
    assert result.returncode == 0, result.stderr
    assert_no_traceback(result.stderr)
    jumps = read_json(events)["jumps"]
    want = expected_timers(c_first=True)
    assert [(j["edge"], tuple(j["enabled"]), j["chosen_by"]) for j in jumps] == [
        w[1:] for w in want
    ]
    assert [j["j"] for j in jumps] == list(range(9))


RING = """
automaton: ring
description: The token goes round, station 1 then station 2; it is handed on at once.
labels: [tt1, rt1, tt2, rt2]
locations:
  give1: {urgent: true}
  at1: {}
  give2: {urgent: true}
  at2: {}
initial: {location: give1}
edges:
  - {name: hand1, from: give1, to: at1, label: tt1}
  - {name: back1, from: at1, to: give2, label: rt1}
  - {name: hand2, from: give2, to: at2, label: tt2}
  - {name: back2, from: at2, to: give1, label: rt2}
"""

STATION = """
automaton: station
description: >
  A station of a token ring (after FDDI): it holds the token for `hold` seconds
  (clock z); its token rotation timer trt expires every `rotation` seconds.
parameters: {hold: 20.0, rotation: 40.0}
state:
  z: {initial: 0.0}
  trt: {initial: 0.0}
labels: [tt, rt]
locations:
  idle: {flow: {z: 0, trt: 1}}
  holding: {flow: {z: 1, trt: 1}, invariant: z <= hold}
initial: {location: idle}
edges:
  - {name: take, from: idle, to: holding, label: tt, reset: {z: 0}}
  - {name: release, from: holding, to: idle, label: rt, guard: z == hold}
  - {name: expire_idle, from: idle, to: idle, guard: trt == rotation, reset: {trt: 0}}
  - {name: expire_holding, from: holding, to: holding, guard: trt == rotation, reset: {trt: 0}}
"""

TOKEN_RING = """
system: token_ring
components:
  - {spec: ring.yaml}
  - {spec: station.yaml, as: s1, rename: {z: z1, trt: trt1, tt: tt1, rt: rt1}}
  - spec: station.yaml
    as: s2
    rename: {z: z2, trt: trt2, tt: tt2, rt: rt2}
    initial: {state: {trt: 20.0}}
"""


def expected_ring(trt1: float, trt2: float, t_end: float) -> list[tuple[float, str]]:
    """By hand. The ring hands the token to station 1 at t = 0; each station holds it
    20 s, so at t = 20 k station 1 (k odd) or 2 (k even) releases it and the other takes
    it at once (two jumps). Station i's timer expires at ``rotation - trt_i(0) + 40 n``,
    in the location it is in then (holding on [20 k, 20 (k + 1)] for the station that
    took it at 20 k). At a shared instant the ring's jumps come first (component 0 is
    in them), then the expiry, whose level is still reached after them.
    """
    rows: list[tuple[float, int, str]] = [(0.0, 0, "ring.hand1+s1.take")]
    k = 1
    while 20.0 * k < t_end:
        giver, taker = (1, 2) if k % 2 else (2, 1)
        rows.append((20.0 * k, 0, f"ring.back{giver}+s{giver}.release"))
        rows.append((20.0 * k, 1, f"ring.hand{taker}+s{taker}.take"))
        k += 1
    for station, start in ((1, trt1), (2, trt2)):
        t = 40.0 - start
        while t < t_end:
            slot = int(t // 20.0)  # the token is with station 1 on even slots
            holder = 1 if slot % 2 == 0 else 2
            where = "holding" if holder == station else "idle"
            rows.append((t, 2, f"s{station}.expire_{where}"))
            t += 40.0
    return [(t, edge) for t, _, edge in sorted(rows)]


@pytest.mark.parametrize(
    ("initial", "starts"),
    [({}, (0.0, 20.0)), ({"trt1": 5.0, "trt2": 15.0}, (5.0, 15.0))],
    ids=["coinciding", "staggered"],
)
def test_a_token_ring_jumps_every_twenty_seconds_as_derived_by_hand(
    tmp_path: Path, backend: str, initial: dict[str, float], starts: tuple[float, float]
) -> None:
    for name, text in (("ring", RING), ("station", STATION), ("token_ring", TOKEN_RING)):
        (tmp_path / f"{name}.yaml").write_text(text)
    model = hybrid.load(tmp_path / "token_ring.yaml")
    run = hybrid.simulate(model, t_end=150.0, initial=initial, backend=backend)
    assert run.termination.cause == "t_end"
    want = expected_ring(*starts, t_end=150.0)
    assert len(want) == 22  # 1 + 7 hand-overs of 2 jumps + 7 expiries (either variant)
    assert [j.edge for j in run.jumps] == [edge for _, edge in want]
    for jump, (t, _) in zip(run.jumps, want, strict=True):
        assert abs(jump.t - t) <= 1e-9, (jump.edge, jump.t, t)
    # no timer ever runs past its rotation: every expiry was taken
    assert max(run["trt1"].max(), run["trt2"].max()) <= 40.0 + 1e-9


STUCK = """
automaton: stuck
description: Its invariant is false from the start, and it has no edge.
state: {s: {initial: 0.0}}
locations:
  wait: {flow: {s: 1}, invariant: s <= -1}
"""

LOOPER = """
automaton: looper
description: Two locations and two unguarded edges between them, a cycle that takes no time.
state: {y: {initial: 0.0}}
locations:
  p: {flow: {y: 1}}
  q: {flow: {y: 1}}
edges:
  - {name: there, from: p, to: q}
  - {name: back, from: q, to: p}
"""


@pytest.mark.parametrize("stuck_first", [True, False], ids=["stuck-first", "stuck-second"])
@pytest.mark.parametrize(("max_jumps", "cause", "count"), [
    (10_000, "zeno", 1000),    # the cap of 1000 jumps at one instant
    (50, "max_jumps", 50),     # fewer jumps allowed than the cap
])  # fmt: skip
def test_a_stuck_component_beside_a_zero_time_loop_ends_as_the_loop_does(
    tmp_path: Path, backend: str, stuck_first: bool, max_jumps: int, cause: str, count: int
) -> None:
    (tmp_path / "stuck.yaml").write_text(STUCK)
    (tmp_path / "looper.yaml").write_text(LOOPER)
    names = ["stuck.yaml", "looper.yaml"] if stuck_first else ["looper.yaml", "stuck.yaml"]
    (tmp_path / "both.yaml").write_text(
        "system: both\ncomponents:\n" + "".join(f"  - {{spec: {n}}}\n" for n in names)
    )
    model = hybrid.load(tmp_path / "both.yaml")
    run = hybrid.simulate(model, t_end=10.0, max_jumps=max_jumps, backend=backend)
    # by hand: at t = 0 an edge of the looper is always enabled, so the product jumps
    # (there, back, there, ...) until a jump is refused; nothing is ever blocked
    assert run.termination.cause == cause
    assert run.termination.t == 0.0 and run.termination.j == count
    assert [j.edge for j in run.jumps] == ["looper.there", "looper.back"] * (count // 2)
    assert all(j.t == 0.0 for j in run.jumps)
    if cause == "zeno":
        assert run.termination.zeno_time == 0.0
        assert "1000 jumps at the same instant" in run.termination.message


ONE_LEVEL = """
automaton: one_level
description: Two edges and a self-loop on one level x == 1 of one component; x never returns.
state: {x: {initial: 0.0}, y: {initial: 0.0}}
locations:
  p: {flow: {x: 1, y: 0}}
  n: {flow: {x: 1, y: 0}}
edges:
  - {name: count, from: p, to: p, guard: x == 1, reset: {y: y + 1}, priority: 1}
  - {name: over, from: p, to: n, guard: x == 1}
  - {name: back, from: n, to: p, guard: x == 1}
"""

WATCHER = """
automaton: watcher
description: It reads the other component's x and leaves when x reaches 1.
inputs: [x]
locations:
  before: {}
  after: {}
edges:
  - {name: seen, from: before, to: after, guard: x == 1}
"""


def test_a_level_is_used_by_the_jump_that_reads_it_in_its_component_only(
    tmp_path: Path, backend: str
) -> None:
    # by hand: at t = 1 the level x == 1 is reached; `count` (priority 1) fires and uses it
    # for its component, so neither `over` nor (later) `back` fires there, and x never
    # comes back to 1; the watcher's guard reads the same x but is another component's
    # level: it fires at the same instant, after `count`
    (tmp_path / "one_level.yaml").write_text(ONE_LEVEL)
    (tmp_path / "watcher.yaml").write_text(WATCHER)
    alone = hybrid.load(tmp_path / "one_level.yaml")
    run = hybrid.simulate(alone, t_end=3.0, backend=backend)
    assert [(j.edge, j.enabled) for j in run.jumps] == [("count", ("count", "over"))]
    assert abs(run.jumps[0].t - 1.0) <= 1e-9 and run["y"][-1] == 1.0
    assert run.termination.cause == "t_end" and run.termination.location == "p"
    (tmp_path / "both.yaml").write_text(
        "system: both\ncomponents:\n  - {spec: one_level.yaml, as: a}\n"
        "  - {spec: watcher.yaml, as: w}\n"
    )
    both = hybrid.load(tmp_path / "both.yaml")
    run = hybrid.simulate(both, t_end=3.0, backend=backend)
    assert [(j.edge, j.enabled) for j in run.jumps] == [
        ("a.count", ("a.count", "a.over", "w.seen")),
        ("w.seen", ("w.seen",)),
    ]
    assert all(abs(j.t - 1.0) <= 1e-9 for j in run.jumps)
    assert run.termination.location == "a.p|w.after"
