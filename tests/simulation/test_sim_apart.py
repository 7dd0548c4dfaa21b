"""Independent components are simulated apart and merged: the same run as their product."""

from __future__ import annotations

import numpy as np
import pytest

import hybrid
from hybrid.simulation import apart


def thermostat(i: int, start: float) -> str:
    return f"""
automaton: th{i}
state: {{T{i}: {{initial: {start}}}}}
signals: {{p{i}: 2*T{i}}}
locations:
  off: {{flow: {{T{i}: -0.1*(T{i} - 10)}}, invariant: T{i} >= 18}}
  on: {{flow: {{T{i}: 0.1*(30 - T{i})}}, invariant: T{i} <= 22}}
edges:
  - {{name: heat, from: off, to: on, guard: T{i} <= 18}}
  - {{name: rest, from: on, to: off, guard: T{i} >= 22}}
"""


STUCK = """
automaton: stuck
state: {x: {initial: 0}}
locations: {a: {flow: {x: 1}, invariant: x <= 7.5}}
"""


def system(*extra: str) -> hybrid.System:
    texts = [thermostat(i, 18.5 + i) for i in range(3)] + list(extra)
    return hybrid.compose(*[hybrid.load_text(t) for t in texts])


def product_run(model: hybrid.System, monkeypatch: pytest.MonkeyPatch, **kw) -> hybrid.Run:
    with monkeypatch.context() as m:
        m.setattr(apart, "independent_groups", lambda s: [tuple(range(len(s.components)))])
        m.setattr("hybrid.simulation.reference.independent_groups", apart.independent_groups)
        return hybrid.simulate(model, handle_sigint=False, **kw)


def test_groups_follow_labels_and_signals():
    reader = "automaton: r\ninputs: [p0]\nstate: {y: {}}\nlocations: {a: {flow: {y: p0}}}\n"
    model = system(reader)
    assert apart.independent_groups(model) == [(0, 3), (1,), (2,)]


def test_merged_run_is_the_product_run(monkeypatch):
    model = system()
    merged = hybrid.simulate(model, t_end=30.0, rtol=1e-9, atol=1e-11, handle_sigint=False)
    whole = product_run(model, monkeypatch, t_end=30.0, rtol=1e-9, atol=1e-11, dense=True)
    assert merged.termination.cause == whole.termination.cause == "t_end"
    assert [(j.edge, j.source, j.target, j.j) for j in merged.jumps] == [
        (j.edge, j.source, j.target, j.j) for j in whole.jumps
    ]
    assert np.allclose([j.t for j in merged.jumps], [j.t for j in whole.jumps], atol=1e-6)
    for a, b in zip(merged.jumps, whole.jumps, strict=True):
        assert a.before.keys() == b.before.keys()
        assert np.allclose(list(a.before.values()), list(b.before.values()), atol=1e-5)
    # the trajectory: hybrid time ordered, two rows per jump, values on the product's
    assert np.all(np.diff(merged.t) >= 0) and np.all(np.diff(merged.j) >= 0)
    assert set(np.diff(merged.j).tolist()) <= {0, 1}
    assert merged.j[-1] == len(merged.jumps) and merged.t[-1] == 30.0
    # every point of the merged run lies on the product run's dense solution
    checked = 0
    for t, j, x in zip(merged.t.tolist(), merged.j.tolist(), merged.states, strict=True):
        for seg_j, t0, t1, sol in whole.segments:
            if seg_j == j and t0 <= t <= t1:
                assert np.allclose(x, sol(t), atol=1e-6), (t, j)
                checked += 1
                break
    assert checked > len(merged.t) // 2
    assert np.allclose(merged["p1"], 2 * merged["T1"])  # signals computed where interpolated
    assert set(merged.location) <= {
        f"th0.{a}|th1.{b}|th2.{c}"
        for a in ("off", "on")
        for b in ("off", "on")
        for c in ("off", "on")
    }
    # as a product's run, each point refers to its location's one name
    assert len({id(name) for name in merged.location}) == len(set(merged.location))


def test_a_group_that_ends_early_ends_the_run(monkeypatch):
    model = system(STUCK)
    merged = hybrid.simulate(model, t_end=30.0, handle_sigint=False)
    whole = product_run(model, monkeypatch, t_end=30.0)
    assert merged.termination.cause == whole.termination.cause == "blocked"
    assert merged.termination.t == pytest.approx(7.5) and merged.t[-1] == pytest.approx(7.5)
    assert merged.termination.j == len(merged.jumps) == len(whole.jumps)
    assert merged.termination.location == whole.termination.location


def test_max_jumps_counts_the_jumps_of_the_whole_system(monkeypatch):
    model = system()
    merged = hybrid.simulate(model, t_end=60.0, max_jumps=4, handle_sigint=False)
    whole = product_run(model, monkeypatch, t_end=60.0, max_jumps=4)
    assert merged.termination.cause == whole.termination.cause == "max_jumps"
    assert len(merged.jumps) == len(whole.jumps) == 4
    assert merged.termination.t == pytest.approx(whole.termination.t, abs=1e-4)


def test_dense_segments_cover_the_run():
    merged = hybrid.simulate(system(), t_end=20.0, dense=True, handle_sigint=False)
    for j, t0, t1, sol in merged.segments:
        mid = 0.5 * (t0 + t1)
        values = sol(mid)
        assert values.shape == (3,)
        row = np.searchsorted(merged.t, mid)
        assert merged.j[min(row, len(merged.t) - 1)] >= j
    assert merged.segments[0][1] == 0.0 and merged.segments[-1][2] == 20.0


def test_a_component_without_state_is_merged_too(monkeypatch):
    # a controller made of locations only (no state variable), independent of the
    # thermostats: its group has no column to fill (before: ValueError out of simulate)
    timer = """
automaton: ctrl
locations: {idle: {}, busy: {}}
edges:
  - {name: start, from: idle, to: busy, guard: t >= 5}
"""
    model = system(timer)
    merged = hybrid.simulate(model, t_end=10.0, handle_sigint=False)
    whole = product_run(model, monkeypatch, t_end=10.0)
    assert merged.termination.cause == whole.termination.cause == "t_end"
    (start,) = [j for j in merged.jumps if j.edge == "ctrl.start"]
    assert start.t == pytest.approx(5.0, abs=1e-9)
    assert [j.edge for j in merged.jumps] == [j.edge for j in whole.jumps]
    busy = np.array([loc.endswith("ctrl.busy") for loc in merged.location])
    assert not busy[merged.t < 5.0].any() and busy[merged.t > 5.0].all()
