"""``backend="auto"`` for campaigns: compiled when cached or when the runs pay for the compile."""

from __future__ import annotations

import re
import warnings
from pathlib import Path
from typing import Any

import pytest
from support import SPECS, read_csv, run_cli

import hybrid
from hybrid.campaigns.choosing import BackendNote
from hybrid.simulation.native import choice
from hybrid.simulation.native.choice import (
    KERNEL_COMPILE_CPU_S,
    LOAD_S,
    SCIPY_LOAD_S,
    SCIPY_RUN_FLOOR_S,
    cached,
    choose,
)

pytest.importorskip("numba")
THERMO = hybrid.load(SPECS / "thermostat.yaml")


def test_the_choice_weighs_the_runs_against_loading_and_compiling(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    ten_ms = lambda: 0.01  # noqa: E731 (one scipy run's CPU seconds)
    monkeypatch.setattr(choice, "machine_factor", lambda: 1.0)  # the benchmark machine's speed
    monkeypatch.setattr(choice, "cached", lambda model: ("missing", "cached", 1.0))
    # 1000 runs of 10 ms save 1000 * 0.01 * (1 - 1/50) = 9.8 s > LOAD_S + 1.0 s
    chosen = choose(THERMO, 1000, run_s=ten_ms)
    assert chosen.backend == "compiled" and chosen.reason.startswith("1000 runs would save about 9.8 s")
    assert choose(THERMO, 100, run_s=ten_ms).backend == "scipy"  # 0.98 s < LOAD_S + 1.0 s
    monkeypatch.setattr(choice, "cached", lambda model: ("missing", "missing", 1.0))
    runs = int((LOAD_S + KERNEL_COMPILE_CPU_S + 1.0) / (0.01 * (1 - 1 / 50))) + 1
    assert choose(THERMO, runs, run_s=ten_ms).backend == "compiled"
    assert choose(THERMO, runs - 2, run_s=ten_ms).backend == "scipy"
    monkeypatch.setattr(choice, "cached", lambda model: ("cached", "cached", 1.0))
    assert choose(THERMO, 1).backend == "scipy"  # one run of unknown length: loading costs more
    enough = int(LOAD_S / (0.01 * (1 - 1 / 50))) + 1
    assert choose(THERMO, enough, run_s=ten_ms).backend == "compiled"
    assert choose(THERMO, enough - 2, run_s=ten_ms).backend == "scipy"
    monkeypatch.setattr(choice, "cached", lambda model: ("loaded", "loaded", 1.0))
    timed: list[int] = []
    loaded = choose(THERMO, 1, run_s=lambda: timed.append(1) or 0.0)
    assert loaded.backend == "compiled" and not timed  # nothing to load: nothing timed


def test_near_the_break_even_the_costs_are_scaled_by_the_machines_speed(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The constants are the benchmark machine's; the timed run is this machine's. On a
    machine three times slower a run saves three times as much, and compiling costs three
    times as much: the choice is the benchmark machine's."""
    asked: list[int] = []

    def three() -> float:
        asked.append(1)
        return 3.0

    monkeypatch.setattr(choice, "machine_factor", three)
    monkeypatch.setattr(choice, "cached", lambda model: ("missing", "missing", 1.0))
    cost = LOAD_S + KERNEL_COMPILE_CPU_S + 1.0  # 19.9 s at the benchmark machine's speed
    share = 1 - 1 / 50
    # 1,000 runs of 13 ms on the benchmark machine save 12.7 s < 19.9 s: scipy there; here
    # they take 39 ms and save 38.2 s, above 19.9 s but below 3 * 19.9 = 59.7 s
    chosen = choose(THERMO, 1000, run_s=lambda: 0.039)
    assert chosen.backend == "scipy" and asked == [1]
    assert chosen.reason == (f"1000 runs would save about {1000 * 0.039 * share:.1f} s; "
                             f"compiling and loading (about {3 * cost:.1f} s of CPU here, "
                             "3.0 times the benchmark machine's)")  # fmt: skip
    runs = int(3 * cost / (0.039 * share)) + 1  # just past the scaled break-even
    assert choose(THERMO, runs, run_s=lambda: 0.039).backend == "compiled"
    # far from the break-even (more than NEAR times either way) the speed is not asked
    del asked[:]
    assert choose(THERMO, 100_000, run_s=lambda: 0.039).backend == "compiled"
    assert choose(THERMO, 10, run_s=lambda: 0.039).backend == "scipy"
    assert asked == []


def test_the_machine_factor_tracks_a_slower_engine(monkeypatch: pytest.MonkeyPatch) -> None:
    """The factor is a reference scipy run over its time on the benchmark machine: a
    machine on which that run takes twice as long reads twice the factor."""
    from hybrid.simulation import reference

    real = reference.simulate_reference
    clock = {"t": 0.0}

    def simulate(*args: Any, **kwargs: Any) -> Any:
        clock["t"] += 2 * choice.PROBE_S  # each run of the reference: twice its time there
        return real(*args, **kwargs)

    monkeypatch.setattr(reference, "simulate_reference", simulate)
    monkeypatch.setattr("time.process_time", lambda: clock["t"])
    assert choice.machine_factor() == pytest.approx(2.0, rel=1e-5)


def test_a_campaign_too_long_for_scipy_at_its_cheapest_is_not_timed(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Timing one scipy run would load the scipy engine: not when no run can be cheap enough."""
    timed: list[int] = []

    def run_s() -> float:
        timed.append(1)
        return SCIPY_RUN_FLOOR_S

    monkeypatch.setattr(choice, "cached", lambda model: ("cached", "cached", 1.0))
    monkeypatch.setattr(choice, "_scipy_loaded", lambda: False)
    # 1000 * 0.6 ms + 0.4 s of loading scipy = 1.0 s > LOAD_S (0.9 s)
    runs = int((LOAD_S - SCIPY_LOAD_S) / SCIPY_RUN_FLOOR_S) + 1
    chosen = choose(THERMO, runs, run_s=run_s)
    assert chosen.backend == "compiled" and not timed
    assert chosen.reason.startswith(f"{runs} runs would cost at least")
    assert choose(THERMO, runs - 2, run_s=run_s).backend == "scipy" and timed == [1]
    monkeypatch.setattr(choice, "_scipy_loaded", lambda: True)  # no import to spare
    assert choose(THERMO, runs, run_s=run_s).backend == "scipy" and timed == [1, 1]
    assert runs <= 1000  # the benchmark's sweep of 1,000 points is past it


def test_the_cache_is_read_from_the_manifests(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    from hybrid.simulation.native import cache

    monkeypatch.setenv(cache.CACHE_ENV, str(tmp_path))
    monkeypatch.setattr(cache, "_LOADED", {})
    assert cached(THERMO)[:2] == ("missing", "missing")
    from importlib.metadata import version

    from hybrid.simulation.native.kernel_text import kernel_module

    kernel = tmp_path / cache.cache_key(kernel_module(), version("numba"))
    kernel.mkdir()
    (kernel / cache.MANIFEST).write_text("{}")
    assert cached(THERMO)[:2] == ("missing", "cached")


def test_a_short_sweep_with_an_empty_cache_runs_on_scipy_and_says_so(tmp_path: Path) -> None:
    with warnings.catch_warnings(record=True) as notes:
        warnings.simplefilter("always")
        with pytest.MonkeyPatch.context() as m:
            from hybrid.simulation.native import cache

            m.setenv("HYBRID_NATIVE_CACHE", str(tmp_path / "empty"))
            m.setattr(cache, "_LOADED", {})  # as in a process that has loaded nothing compiled
            auto = hybrid.sweep(THERMO, 50.0, grid={"T_high": [21.0, 22.0]}, workers=0,
                                summaries=("jump_t:1",), backend="auto", handle_sigint=False)  # fmt: skip
    said = [n for n in notes if issubclass(n.category, BackendNote)]
    assert len(said) == 1 and str(said[0].message).startswith("backend auto: scipy (2 runs would save")
    assert said[0].filename == __file__  # the user's call, not a line inside hybrid
    # named: the default (auto) runs compiled in a process with the compiled code loaded
    scipy = hybrid.sweep(THERMO, 50.0, grid={"T_high": [21.0, 22.0]}, workers=0,
                         summaries=("jump_t:1",), handle_sigint=False, backend="scipy")  # fmt: skip
    assert auto.rows == scipy.rows


def test_the_command_line_takes_auto_and_prints_its_choice(tmp_path: Path) -> None:
    out = tmp_path / "sweep.csv"
    done = run_cli("sweep", SPECS / "thermostat.yaml", "--t-end", "20", "--grid", "T_high=21:22:2",
                   "--backend", "auto", "--method", "LSODA", "--out", out)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "hybrid: note: backend auto: scipy (method 'LSODA' is the scipy backend's)" in done.stderr
    _, rows = read_csv(out)
    assert len(rows) == 2


def test_quiet_leaves_out_the_note_of_the_choice(tmp_path: Path) -> None:
    """``--quiet`` printed no progress but still the backend note, on every sweep."""
    swept = run_cli("sweep", SPECS / "thermostat.yaml", "--t-end", "20", "--grid",
                    "T_high=21:22:2", "--backend", "auto", "--method", "LSODA", "--quiet",
                    "--out", tmp_path / "sweep.csv")  # fmt: skip
    one = run_cli("simulate", SPECS / "thermostat.yaml", "--t-end", "20", "--backend", "auto",
                  "--quiet")  # fmt: skip
    for done in (swept, one):
        assert done.returncode == 0, done.stderr
        assert "backend auto" not in done.stderr and "note" not in done.stderr, done.stderr


def test_the_timed_run_does_not_count_loading_the_scipy_engine(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A fresh process loads the scipy engine (about 0.5 s) before it times a run: counted,
    it would make every run look half a second long, and 1,000 of them pay for a compile."""
    monkeypatch.setenv("HYBRID_NATIVE_CACHE", str(tmp_path / "empty"))
    done = run_cli("sweep", SPECS / "thermostat.yaml", "--t-end", "20", "--grid",
                   "T_high=21:22:10", "--backend", "auto", "--out", tmp_path / "s.csv")  # fmt: skip
    assert done.returncode == 0, done.stderr
    (note,) = [line for line in done.stderr.splitlines() if "backend auto:" in line]
    found = re.search(r"backend auto: scipy \(10 runs would save about ([\d.]+) s", note)
    assert found is not None, note
    assert float(found.group(1)) / 10 < 0.1  # a thermostat run of 20 s: about 10 ms


def test_simulate_auto_runs_one_run_on_scipy_unless_loaded(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("HYBRID_NATIVE_CACHE", str(tmp_path / "cache"))
    args = ("simulate", SPECS / "thermostat.yaml", "--t-end", "30")
    auto = run_cli(*args, "--backend", "auto", "--events", tmp_path / "auto.json")
    assert auto.returncode == 0, auto.stderr
    assert "note: backend auto: scipy (one run: loading compiled code" in auto.stderr
    assert run_cli(*args, "--events", tmp_path / "scipy.json").returncode == 0
    assert (tmp_path / "auto.json").read_text() == (tmp_path / "scipy.json").read_text()
    assert not (tmp_path / "cache").exists()  # nothing compiled


def test_a_compiled_campaign_on_local_workers_runs_in_this_process() -> None:
    from hybrid.campaigns.choosing import settle
    from hybrid.campaigns.executors import InProcess, LocalPool
    from hybrid.campaigns.runs import RunPlan

    pool = LocalPool(2)
    plan, executor = settle(THERMO, [{"T_high": 22.0}], RunPlan(t_end=1.0, backend="compiled"), pool)
    assert plan.backend == "compiled" and isinstance(executor, InProcess)
    plan, executor = settle(THERMO, [{"T_high": 22.0}], RunPlan(t_end=1.0), pool)
    assert plan.backend == "scipy" and executor is pool  # scipy runs keep their processes
    # the same rows either way (each point one ensemble row in this process)
    grid = {"T_high": [21.0, 22.0, 23.0]}
    tables = [hybrid.sweep(THERMO, 60.0, grid=grid, summaries=("jump_t:2",), workers=w,
                           backend="compiled", handle_sigint=False) for w in (0, 2)]  # fmt: skip
    assert tables[0].rows == tables[1].rows
    # T_high = 22: cooling 20 -> 18 in 10 ln(10/8), heating 18 -> 22 in 10 ln(12/8)
    import math

    assert abs(tables[0].rows[1]["jump_t:2"] - 10 * (math.log(10 / 8) + math.log(12 / 8))) < 1e-5


BROKEN_NUMBA = """
import sys, types, warnings
import importlib.machinery
class Broken(importlib.machinery.PathFinder):
    @classmethod
    def find_spec(cls, name, path=None, target=None):
        if name != "numba":
            return None
        spec = importlib.machinery.ModuleSpec("numba", cls)
        return spec
    @staticmethod
    def create_module(spec):
        raise ImportError("numpy 9 is not supported")
    @staticmethod
    def exec_module(module):
        pass
sys.meta_path.insert(0, Broken)
import hybrid
from hybrid.simulation.native.choice import choose
th = hybrid.load({spec!r})
print(choose(th, 100000, run_s=lambda: 1.0))
try:
    hybrid.simulate(th, t_end=10.0, backend="compiled")
except hybrid.UsageError as e:
    print(e)
"""


def test_a_numba_that_is_installed_but_does_not_import_is_said_and_not_chosen() -> None:
    # said "numba, which is not installed", and auto chose compiled: every run failed
    import subprocess
    import sys

    code = BROKEN_NUMBA.format(spec=str(SPECS / "thermostat.yaml"))
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    chosen, said = done.stdout.splitlines()[:2]
    assert chosen == "Choice(backend='scipy', reason='numba is installed but does not import')"
    assert said.startswith(
        "the compiled backend needs numba, which is installed but does not import: numpy 9 is "
        "not supported; reinstall it ("
    )
