"""Falsification finds the violating region of a threshold requirement, and nothing where none is.

The heater x' = -k x from x = 20 must stay above 20 e^(-5 * 0.95) over 5 s:
x(5) = 20 e^(-5 k), so it fails exactly when k > 0.95. Over k in [0, 1] (and an
irrelevant c in [0, 1]) the violating region is 5 % of the box. Within a budget
of 30 runs every seed of ten finds a counterexample, with k > 0.95; a
requirement that always holds is reported as not violated after the whole
budget.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from support import assert_no_traceback, main_in_process

import hybrid

THRESHOLD = 0.95
BUDGET = 30
HEATER = f"""
automaton: heater
parameters: {{k: 0.1, c: 0.0}}
state: {{x: {{initial: 20.0}}}}
locations: {{cooling: {{flow: {{x: -k*x}}}}}}
requirements:
  - {{name: warm, always: "x >= 20*exp(-5*{THRESHOLD}) + 0*c"}}
  - {{name: positive, always: "x >= 0"}}
"""
VARY = {"k": (0.0, 1.0), "c": (0.0, 1.0)}


@pytest.fixture(scope="module")
def heater() -> hybrid.Automaton:
    model = hybrid.load_text(HEATER)
    assert isinstance(model, hybrid.Automaton)
    return model


def test_ten_seeds_of_ten_find_the_violating_region(heater: hybrid.Automaton) -> None:
    # measured: 9 seeds find it in the global phase (15 runs), seed 1 in a local search (23)
    for seed in range(10):
        result = hybrid.falsify(
            heater, "warm", VARY, t_end=5.0, budget=BUDGET, seed=seed, workers=0
        )
        assert result.found, (seed, result)
        assert result.values["k"] > THRESHOLD and result.robustness < 0
        assert result.evaluations <= BUDGET
        # the counterexample's run is there, and violates the requirement where x crosses
        warm = result.run.requirements["warm"]
        k = result.values["k"]
        assert not warm.holds
        assert warm.violated_at == pytest.approx(THRESHOLD * 5 / k, abs=1e-5)


def test_the_local_phase_finds_it_when_the_global_one_does_not(heater: hybrid.Automaton) -> None:
    result = hybrid.falsify(
        heater, "warm", VARY, t_end=5.0, budget=BUDGET, seed=3, global_share=0.1, workers=0
    )
    assert [h["phase"] for h in result.history[:3]] == ["global"] * 3
    assert not any(h["violated"] for h in result.history[:3])
    assert result.found and result.history[-1]["phase"].startswith("local")
    assert result.values["k"] > THRESHOLD


def test_none_is_reported_for_a_requirement_that_always_holds(heater: hybrid.Automaton) -> None:
    result = hybrid.falsify(heater, "positive", VARY, t_end=5.0, budget=20, seed=0, workers=0)
    assert not result.found and result.evaluations == 20
    # the lowest robustness is x(5) at the largest k tried: 20 e^(-5 k) > 0
    k = result.values["k"]
    assert result.robustness == pytest.approx(20 * math.exp(-5 * k), rel=1e-5)


def test_the_search_does_not_depend_on_the_executor(heater: hybrid.Automaton) -> None:
    here = hybrid.falsify(heater, "warm", VARY, t_end=5.0, budget=BUDGET, seed=5, workers=0)
    pool = hybrid.falsify(heater, "warm", VARY, t_end=5.0, budget=BUDGET, seed=5, workers=2)
    assert here.history == pool.history and here.values == pool.values


def test_the_command_writes_the_counterexample(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    spec = tmp_path / "heater.yaml"
    spec.write_text(HEATER)
    out = tmp_path / "found"
    code = main_in_process(
        "falsify", spec, "--t-end", "5", "--requirement", "warm", "--vary", "k=0:1",
        "--vary", "c=0:1", "--budget", str(BUDGET), "--seed", "1", "--workers", "0",
        "--out", out, "--quiet",
    )  # fmt: skip
    captured = capsys.readouterr()
    assert code == 1, captured.err
    assert "violated at k=" in captured.out
    document = json.loads((out / "falsification.json").read_text())
    assert document["found"] and document["values"]["k"] > THRESHOLD
    events = json.loads((out / "events.json").read_text())
    assert events["requirements"]["warm"]["holds"] is False
    header = (out / "trajectory.csv").read_text().splitlines()[0]
    assert header == "t,j,location,x"
    # the same folder again, every run failing: no run to show, and none of the last
    # search's left beside a result that says nothing was found
    code = main_in_process(
        "falsify", spec, "--t-end", "5", "--requirement", "warm", "--vary", "k=0:1",
        "--budget", "3", "--workers", "0", "--out", out, "--quiet", "--max-step", "1e-6",
        "--run-timeout", "0.05", "--backend", "scipy",
    )  # fmt: skip
    assert code == 1 and "3 of them failed" in capsys.readouterr().out
    assert sorted(p.name for p in out.iterdir()) == ["falsification.json"]
    assert not json.loads((out / "falsification.json").read_text())["found"]
    code = main_in_process(
        "falsify", spec, "--t-end", "5", "--requirement", "positive", "--vary", "k=0:1",
        "--budget", "5", "--workers", "0", "--quiet",
    )  # fmt: skip
    assert code == 0 and "no violation of 'positive' in 5 runs" in capsys.readouterr().out
    code = main_in_process(
        "falsify", spec, "--t-end", "5", "--requirement", "nope", "--vary", "k=0:1",
        "--workers", "0",
    )  # fmt: skip
    err = capsys.readouterr().err
    assert code == 2 and "no requirement 'nope'" in err and "warm, positive" in err
    assert_no_traceback(err)
