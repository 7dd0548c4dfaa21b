"""``hybrid.sweep(..., backend="compiled")`` and ``hybrid sweep --backend compiled``: the scipy table."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from support import SPECS, read_csv, run_cli

import hybrid
from hybrid.campaigns import runs

pytest.importorskip("numba")

GRID = {"T_high": [21.0, 22.0, 23.0], "init.T": [16.0, 19.0]}
OPTIONS: dict[str, Any] = {"rtol": 1e-10, "atol": 1e-12, "workers": 0, "handle_sigint": False}
SUMMARIES = ("jump_t:1", "jump_t:3", "jumps:turn_on", "max:T")


def same_tables(compiled: hybrid.SweepTable, reference: hybrid.SweepTable) -> None:
    assert compiled.columns == reference.columns and len(compiled) == len(reference) == 6
    for c, r in zip(compiled.rows, reference.rows, strict=True):
        assert {k: c[k] for k in ("run", "T_high", "init.T", "cause", "j", "jumps")} == {
            k: r[k] for k in ("run", "T_high", "init.T", "cause", "j", "jumps")
        }
        for column in ("jump_t:1", "jump_t:3", "t"):
            np.testing.assert_allclose(c[column], r[column], rtol=1e-10, atol=1e-9)
        np.testing.assert_allclose(c["max:T"], r["max:T"], rtol=1e-8)


def test_sweep_compiled_is_one_ensemble_call_and_gives_the_scipy_table(
    thermostat: hybrid.Automaton, monkeypatch: pytest.MonkeyPatch
) -> None:
    reference = hybrid.sweep(thermostat, 60.0, grid=GRID, summaries=SUMMARIES, **OPTIONS)
    calls: list[int] = []
    through = runs._ensemble_rows

    def counted(model: Any, batch: Any, plan: Any) -> Any:
        calls.append(len(batch))
        return through(model, batch, plan)

    monkeypatch.setattr(runs, "_ensemble_rows", counted)
    compiled = hybrid.sweep(
        thermostat, 60.0, grid=GRID, summaries=SUMMARIES, backend="compiled", batch=6, **OPTIONS
    )
    assert calls == [6]  # the whole grid in one simulate_many call
    same_tables(compiled, reference)


def test_cli_sweep_backend_compiled(tmp_path: Path) -> None:
    tables = {}
    for backend in ("scipy", "compiled"):
        out = tmp_path / f"{backend}.csv"
        done = run_cli("sweep", SPECS / "thermostat.yaml", "--t-end", "60", "--grid", "T_high=21:22:2",
                       "--summary", "jump_t:2", "--workers", "0", "--rtol", "1e-10", "--atol", "1e-12",
                       "--backend", backend, "--out", out)  # fmt: skip
        assert done.returncode in (0, 1), done.stderr
        tables[backend] = read_csv(out)
    (head_c, rows_c), (head_s, rows_s) = tables["compiled"], tables["scipy"]
    assert head_c == head_s and len(rows_c) == len(rows_s) == 2
    for c, s in zip(rows_c, rows_s, strict=True):
        assert c["cause"] == s["cause"] and c["jumps"] == s["jumps"]
        assert float(c["jump_t:2"]) == pytest.approx(float(s["jump_t:2"]), rel=1e-10, abs=1e-9)


def test_sweep_compiled_in_a_worker_process_gives_the_scipy_table(thermostat: hybrid.Automaton) -> None:
    options = {**OPTIONS, "workers": 1, "batch": 3}  # two batches, each one simulate_many call
    reference = hybrid.sweep(thermostat, 60.0, grid=GRID, summaries=SUMMARIES, **OPTIONS)
    compiled = hybrid.sweep(thermostat, 60.0, grid=GRID, summaries=SUMMARIES, backend="compiled", **options)
    same_tables(compiled, reference)


COOLING = """
automaton: heater
parameters: {k: 0.1}
state: {x: {initial: 20.0}}
locations: {cooling: {flow: {x: -k*x}}}
requirements: [{name: warm, always: "x >= 15"}]
"""


def test_requirements_in_a_compiled_sweep_are_monitored_per_run() -> None:
    # the ensemble does not monitor requirements: it says so, and the sweep then runs
    # each point on its own (hybrid.simulate monitors them); x = 20 e^(-k t) over 5 s
    # has robustness 20 e^(-5 k) - 15, violated at ln(4/3) / k where it is negative
    heater = hybrid.load_text(COOLING)
    with pytest.raises(hybrid.UsageError, match=r"does not monitor requirements \(warm\)"):
        hybrid.simulate_many(heater, 5.0, parameters={"k": [0.05, 0.1]})
    rates = [0.03, 0.05, 0.08]
    table = hybrid.sweep(heater, 5.0, grid={"k": rates}, **OPTIONS, backend="compiled")
    for row, k in zip(table.rows, rates, strict=True):
        assert row["warm.robustness"] == pytest.approx(20 * np.exp(-5 * k) - 15, abs=1e-9)
        holds = 20 * np.exp(-5 * k) >= 15
        assert row["warm.holds"] == holds
        if not holds:
            assert row["warm.violated_at"] == pytest.approx(np.log(4 / 3) / k, abs=1e-7)


def test_falsify_on_the_compiled_backend_finds_the_violation(tmp_path: Path) -> None:
    spec = tmp_path / "heater.yaml"
    spec.write_text(COOLING)
    done = run_cli("falsify", spec, "--t-end", "5", "--requirement", "warm", "--vary", "k=0.01:0.1",
                   "--budget", "20", "--workers", "0", "--backend", "compiled")  # fmt: skip
    # violated for k > ln(4/3) / 5 = 0.0575
    assert done.returncode == 1, done.stderr
    assert "requirement 'warm' violated at" in done.stdout
