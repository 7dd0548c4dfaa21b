"""Sweeps and falsification over the sets a spec declares: initial sets and input ranges.

The drift model starts anywhere in its initial set x0 in [1, 3] and is pushed by a
bounded input held constant, u in [-1, 1]: x(t) = x0 + u t, so over [0, T] the
requirement ``always: x >= 0`` has the robustness min(x0, x0 + u T) (the closed form
every row is checked against) and is violated exactly where x0 + u T < 0 (a quarter
of the box at T = 4). Named without
a range (``--vary init.x``, ``vary={"init.x": None}``) a variable is sampled from its
declared set; with no ranges at all, every declared set is.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest
from support import main_in_process

import hybrid
from hybrid.campaigns.space import declared_ranges
from hybrid.errors import UsageError

DRIFT = """automaton: drift
state: {x: {initial: 0.0}, y: {initial: 5.0}}
initial: {state: {x: [1, 3]}}
inputs: {u: {range: [-1, 1]}}
locations: {l: {flow: {x: u, y: 0}}}
requirements:
  - {name: positive, always: "x >= 0"}
  - {name: above_minus_four, always: "x >= -4"}
"""
T = 4.0
X0, U = (1.0, 3.0), (-1.0, 1.0)


def _robustness(x0: float, u: float, floor: float = 0.0) -> float:
    return min(x0, x0 + u * T) - floor


@pytest.fixture(scope="module")
def drift() -> hybrid.Automaton:
    model = hybrid.load_text(DRIFT)
    assert isinstance(model, hybrid.Automaton)
    return model


def test_the_declared_ranges_are_the_spec_s_sets(drift: hybrid.Automaton) -> None:
    assert declared_ranges(drift) == {"init.x": X0, "input.u": U}  # y is a single value
    other = hybrid.load_text(
        "automaton: b\nstate: {h: {initial: [2, 4], nominal: 3}}\nlocations: {l: {}}\n"
    )
    assert declared_ranges(other) == {"init.h": (2.0, 4.0)}
    assert declared_ranges(hybrid.load("specs/bouncing_ball.yaml")) == {}


def test_samples_without_ranges_are_drawn_from_every_declared_set(
    drift: hybrid.Automaton,
) -> None:
    n = 8
    table = hybrid.sweep(drift, t_end=T, samples=n, seed=3, workers=0, rtol=1e-10, atol=1e-12)
    assert table.varied == ["init.x", "input.u"]
    x0s = [row["init.x"] for row in table.rows]
    us = [row["input.u"] for row in table.rows]
    # a Latin hypercube of the declared box: one sample in each n-th of each range
    assert sorted(int((x - X0[0]) / (X0[1] - X0[0]) * n) for x in x0s) == list(range(n))
    assert sorted(int((u - U[0]) / (U[1] - U[0]) * n) for u in us) == list(range(n))
    for row in table.rows:
        expected = _robustness(row["init.x"], row["input.u"])
        assert row["positive.robustness"] == pytest.approx(expected, abs=1e-9)
        assert row["positive.holds"] is (expected >= 0)
    assert any(row["positive.holds"] is False for row in table.rows)
    # the same points as the ranges written out
    given = hybrid.sweep(drift, t_end=T, samples=n, seed=3, workers=0,
                         vary={"init.x": X0, "input.u": U}, rtol=1e-10, atol=1e-12)  # fmt: skip
    assert given.rows == table.rows


def test_a_name_without_a_range_takes_its_declared_set(drift: hybrid.Automaton) -> None:
    table = hybrid.sweep(drift, t_end=T, samples=5, seed=1, workers=0, vary=["input.u"])
    assert table.varied == ["input.u"]
    for row in table.rows:  # x starts at the midpoint of its set, 2
        assert U[0] <= row["input.u"] <= U[1]
        assert row["positive.robustness"] == pytest.approx(_robustness(2.0, row["input.u"]))
    mixed = hybrid.sweep(drift, t_end=T, samples=3, seed=1, workers=0,
                         vary={"init.x": None, "init.y": (0.0, 1.0)})  # fmt: skip
    assert all(X0[0] <= r["init.x"] <= X0[1] and 0 <= r["init.y"] <= 1 for r in mixed.rows)
    # a grid name is not sampled again: the default ranges leave it out
    both = hybrid.sweep(drift, t_end=T, grid={"init.x": [1.0, 3.0]}, samples=2, workers=0)
    assert both.varied == ["init.x", "input.u"] and len(both) == 4


def test_names_with_no_declared_range_are_refused(drift: hybrid.Automaton) -> None:
    with pytest.raises(UsageError, match=r"one initial value of y \(5\), not a set"):
        hybrid.sweep(drift, t_end=T, samples=2, vary=["init.y"], workers=0)
    with pytest.raises(UsageError, match="a parameter has no declared range"):
        hybrid.sweep(hybrid.load("specs/bouncing_ball.yaml"), t_end=T, samples=2, vary=["e"])
    with pytest.raises(UsageError, match="no state variable 'z'"):
        hybrid.sweep(drift, t_end=T, samples=2, vary=["init.z"], workers=0)
    with pytest.raises(UsageError, match="declares no initial set or input range"):
        hybrid.sweep(hybrid.load("specs/bouncing_ball.yaml"), t_end=T, samples=2, workers=0)


def test_a_bounded_input_not_varied_is_held_at_its_nominal_value() -> None:
    model = hybrid.load_text(DRIFT.replace("range: [-1, 1]", "range: [-1, 1], nominal: -0.75"))
    table = hybrid.sweep(model, t_end=T, grid={"init.x": [1.0, 2.0]}, workers=0)
    assert [r["positive.robustness"] for r in table.rows] == pytest.approx([-2.0, -1.0])


def test_falsification_searches_the_declared_sets(drift: hybrid.Automaton) -> None:
    for seed in range(3):
        result = hybrid.falsify(drift, "positive", t_end=T, budget=30, seed=seed, workers=0)
        assert result.found, seed
        x0, u = result.values["init.x"], result.values["input.u"]
        assert X0[0] <= x0 <= X0[1] and U[0] <= u <= U[1]
        assert x0 + u * T < 0
        assert result.robustness == pytest.approx(_robustness(x0, u), abs=1e-6)
    # x >= -4 holds over the whole box (lowest: 1 - 4 = -3), by a margin of 1 at least
    safe = hybrid.falsify(drift, "above_minus_four", t_end=T, budget=30, seed=0, workers=0)
    assert not safe.found and safe.evaluations == 30
    x0, u = safe.values["init.x"], safe.values["input.u"]
    assert safe.robustness == pytest.approx(_robustness(x0, u, floor=-4.0), abs=1e-6)
    assert safe.robustness >= 1.0 - 1e-9 and X0[0] <= x0 <= X0[1] and U[0] <= u <= U[1]


def test_the_commands_take_bare_names(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    Path("drift.yaml").write_text(DRIFT)
    common = ["--t-end", str(T), "--workers", "0", "--quiet"]
    assert main_in_process("sweep", "drift.yaml", "--sample", "6", *common, "--out", "a.csv") == 1
    with open("a.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 6 and list(rows[0])[1:3] == ["init.x", "input.u"]
    assert main_in_process("sweep", "drift.yaml", "--sample", "6", "--vary", "init.x", *common,
                           "--out", "b.csv") == 0  # fmt: skip  # u held at 0: x stays >= 1
    assert Path("b.csv").read_text().splitlines()[0].startswith("run,init.x,cause,")
    assert main_in_process("sweep", "drift.yaml", "--sample", "2", "--vary", "init.y", *common,
                           "--out", "c.csv") == 2  # fmt: skip
    code = main_in_process("falsify", "drift.yaml", "--requirement", "positive", "--budget", "30",
                           *common, "--out", "cex")  # fmt: skip
    assert code == 1
    found = json.loads(Path("cex/falsification.json").read_text())
    assert found["found"] and found["values"]["init.x"] + T * found["values"]["input.u"] < 0


def test_a_system_s_free_input_and_initial_set_are_varied_too(drift: hybrid.Automaton) -> None:
    clock = hybrid.load_text("automaton: clock\nstate: {c: {initial: 0.0}}\nlocations: {l: {flow: {c: 1}}}\n")
    system = hybrid.compose(drift, clock)
    assert declared_ranges(system) == {"init.x": X0, "input.u": U}
    table = hybrid.sweep(system, t_end=T, samples=4, seed=2, workers=0)
    assert table.varied == ["init.x", "input.u"]
    for row in table.rows:
        expected = _robustness(row["init.x"], row["input.u"])
        assert row["drift.positive.robustness"] == pytest.approx(expected, abs=1e-6)


def test_a_grid_count_spans_the_declared_set(drift: hybrid.Automaton) -> None:
    table = hybrid.sweep(drift, t_end=T, grid={"init.x": 3, "input.u": 5}, workers=0)
    assert [(r["init.x"], r["input.u"]) for r in table.rows] == [
        (x0, u) for x0 in (1.0, 2.0, 3.0) for u in (-1.0, -0.5, 0.0, 0.5, 1.0)
    ]
    for row in table.rows:
        assert row["positive.robustness"] == pytest.approx(
            _robustness(row["init.x"], row["input.u"]), abs=1e-9
        )
    with pytest.raises(UsageError, match=r"give a range, init.y=LO:HI:N"):
        hybrid.sweep(drift, t_end=T, grid={"init.y": 3}, workers=0)
    with pytest.raises(UsageError, match="N must be a whole number >= 1"):
        hybrid.sweep(drift, t_end=T, grid={"init.x": 0}, workers=0)


def test_the_command_takes_a_grid_count(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    Path("drift.yaml").write_text(DRIFT)
    common = ["--t-end", str(T), "--workers", "0", "--quiet"]
    code = main_in_process("sweep", "drift.yaml", "--grid", "input.u=3", "--grid", "init.x=1:3:2",
                           *common, "--out", "g.csv")  # fmt: skip
    assert code == 1  # u = -1 from x0 = 1 goes below 0
    with open("g.csv", newline="") as handle:
        rows = list(csv.DictReader(handle))
    assert [(float(r["input.u"]), float(r["init.x"])) for r in rows] == [
        (u, x0) for u in (-1.0, 0.0, 1.0) for x0 in (1.0, 3.0)
    ]
    assert main_in_process("sweep", "drift.yaml", "--grid", "init.x=many", *common,
                           "--out", "h.csv") == 2  # fmt: skip
