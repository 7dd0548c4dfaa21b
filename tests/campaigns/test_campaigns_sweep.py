"""Sweeps: the bouncing ball over its restitution, against closed forms, on every executor.

A ball dropped from h0 = 10 under g = 9.81 first hits the floor at
t1 = sqrt(2 h0 / g), whatever e; its bounces accumulate at the Zeno time
t1 (1 + e) / (1 - e). A 5-point grid over e gives one row per e with both; the
table is the same in this process, with one and two local worker processes,
and on a Dask LocalCluster (threads, and processes).
"""

from __future__ import annotations

import math
from typing import Any

import pytest

import hybrid
from hybrid.errors import UsageError
from hybrid.simulation import engine

H0, G = 10.0, 9.81
T1 = math.sqrt(2 * H0 / G)
E_GRID = [0.5, 0.6, 0.7, 0.8, 0.9]
SETTINGS: dict[str, Any] = {"rtol": 1e-10, "atol": 1e-12, "summaries": ["jump_t:1", "max:v"]}


def _ball_sweep(**where: Any) -> hybrid.SweepTable:
    ball = hybrid.load("specs/bouncing_ball.yaml")
    return hybrid.sweep(ball, t_end=30.0, grid={"e": E_GRID}, **SETTINGS, **where)


@pytest.fixture(scope="module")
def here() -> hybrid.SweepTable:
    return _ball_sweep(workers=0)


def test_each_row_matches_the_closed_forms(here: hybrid.SweepTable) -> None:
    assert [row["e"] for row in here.rows] == E_GRID
    for row in here.rows:
        assert row["jump_t:1"] == pytest.approx(T1, rel=1e-9)
        assert row["cause"] == "zeno"
        zeno = T1 * (1 + row["e"]) / (1 - row["e"])
        assert row["zeno_time"] == pytest.approx(zeno, rel=1e-6)
        assert row["t"] <= zeno and row["jumps"] == row["j"]
        assert row["max:v"] == pytest.approx(G * T1 * row["e"], rel=1e-8)  # up after bounce 1


@pytest.mark.parametrize("workers", [1, 2])
def test_the_same_table_with_local_workers(here: hybrid.SweepTable, workers: int) -> None:
    assert _ball_sweep(workers=workers).rows == here.rows


@pytest.mark.parametrize("processes", [False, True])
def test_the_same_table_on_a_dask_local_cluster(here: hybrid.SweepTable, processes: bool) -> None:
    distributed = pytest.importorskip(
        "distributed", reason="dask[distributed] is in the test extra"
    )
    with (
        distributed.LocalCluster(
            n_workers=2 if processes else 1,
            threads_per_worker=1,
            processes=processes,
            dashboard_address=None,
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        table = _ball_sweep(scheduler=client, batch=2)
    assert table.rows == here.rows


def test_samples_are_seeded_and_combine_with_a_grid() -> None:
    ball = hybrid.load("specs/bouncing_ball.yaml")
    first = hybrid.sweep(
        ball, t_end=1.0, grid={"e": [0.5, 0.7]}, vary={"init.h": (1.0, 5.0)}, samples=3,
        seed=7, workers=0,
    )  # fmt: skip
    again = hybrid.sweep(
        ball, t_end=1.0, grid={"e": [0.5, 0.7]}, vary={"init.h": (1.0, 5.0)}, samples=3,
        seed=7, workers=0,
    )  # fmt: skip
    assert first.rows == again.rows and len(first) == 6
    assert first.columns[:3] == ["run", "e", "init.h"]
    heights = [row["init.h"] for row in first.rows]
    assert heights[:3] == heights[3:] and all(1.0 <= h <= 5.0 for h in heights)
    # the first bounce follows the initial height: t1 = sqrt(2 h / g)
    for row in first.rows:
        expected = math.sqrt(2 * row["init.h"] / G)
        assert (row["jumps"] > 0) == (expected <= 1.0)


def test_inputs_held_constant_and_parameters_held() -> None:
    tank = hybrid.load_text(
        """
automaton: tank
inputs: [u]
parameters: {k: 1.0}
state: {x: {initial: 0.0}}
locations: {filling: {flow: {x: k*u}}}
"""
    )
    table = hybrid.sweep(
        tank, t_end=2.0, grid={"input.u": [0.5, 1.5]}, parameters={"k": 2.0}, workers=0,
        summaries=["last:x", "mean:x"],
    )  # fmt: skip
    assert [row["last:x"] for row in table.rows] == pytest.approx([2.0, 6.0])
    assert [row["mean:x"] for row in table.rows] == pytest.approx([1.0, 3.0])


def test_a_failing_run_is_a_row_and_the_campaign_goes_on(monkeypatch: pytest.MonkeyPatch) -> None:
    real = engine.simulate  # what a campaign's scipy run calls

    def flaky(model: Any, **kwargs: Any) -> Any:
        if model.components[0].automaton.parameters["e"] == 0.7:
            raise RuntimeError("boom")
        return real(model, **kwargs)

    monkeypatch.setattr(engine, "simulate", flaky)
    ball = hybrid.load("specs/bouncing_ball.yaml")
    table = hybrid.sweep(ball, t_end=1.0, grid={"e": [0.5, 0.7, 0.9]}, workers=0, backend="scipy")
    assert [row["cause"] for row in table.rows] == ["t_end", "error", "t_end"]
    assert table.rows[1]["message"] == "internal error: RuntimeError: boom"
    assert table.rows[1]["t"] is None and len(table.failed()) == 1


# x' = cos(w t): the solver's steps shrink as 1 / w, so w = 1e5 takes millions of steps
WAVE = """
automaton: wave
parameters: {w: 1.0}
state: {x: {initial: 0.0}}
locations: {on: {flow: {x: cos(w*t)}}}
"""


def test_a_run_over_the_timeout_is_a_row() -> None:
    wave = hybrid.load_text(WAVE)
    table = hybrid.sweep(wave, t_end=10.0, grid={"w": [1.0, 1e5, 2.0]}, workers=0, run_timeout=0.5,
                         backend="scipy")  # the scipy run is the slow one
    assert [row["cause"] for row in table.rows] == ["t_end", "timeout", "t_end"]
    assert "longer than the run timeout of 0.5 s" in table.rows[1]["message"]


def test_loading_the_scipy_engine_is_not_a_runs_time() -> None:
    """A fresh process loads the scipy engine (0.45 to 0.75 s) before a run's clock starts.

    Counted, it made the first run of a campaign (or of each new worker) time out under a
    short ``run_timeout``: a run of 10 ms here, a timeout of 0.3 s.
    """
    import subprocess
    import sys

    code = (
        "import hybrid\n"
        "ball = hybrid.load('specs/bouncing_ball.yaml')\n"
        "t = hybrid.sweep(ball, t_end=1.0, grid={'e': [0.5, 0.7]}, workers=0, run_timeout=0.3,"
        " backend='scipy')\n"
        "print([row['cause'] for row in t.rows])\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True)  # fmt: skip
    assert done.stdout.strip().splitlines()[-1] == "['t_end', 't_end']"


def test_a_worker_that_does_not_answer_is_stopped_and_replaced() -> None:
    # two independent components are simulated apart, without progress reports, so only
    # the hard limit of the local pool (1.5 timeout + 2 s) can stop the slow run
    pair = hybrid.compose(
        hybrid.load_text(WAVE), hybrid.load_text(WAVE.replace("wave", "twin").replace("x", "y"))
    )
    table = hybrid.sweep(
        pair, t_end=10.0, grid={"wave.w": [1.0, 1e5, 2.0]}, workers=1, run_timeout=0.5
    )
    assert [row["cause"] for row in table.rows] == ["t_end", "timeout", "t_end"]
    assert "the worker was stopped" in table.rows[1]["message"]


def test_bad_names_and_options_are_refused_before_anything_runs() -> None:
    ball = hybrid.load("specs/bouncing_ball.yaml")
    with pytest.raises(UsageError, match="no state variable 'z'"):
        hybrid.sweep(ball, t_end=1.0, grid={"init.z": [1.0]}, workers=0)
    with pytest.raises(UsageError, match="unknown parameter 'f'"):
        hybrid.sweep(ball, t_end=1.0, grid={"f": [1.0]}, workers=0)
    with pytest.raises(UsageError, match="summary 'max:w'"):
        hybrid.sweep(ball, t_end=1.0, grid={"e": [0.5]}, summaries=["max:w"], workers=0)
    with pytest.raises(UsageError, match="rtol"):
        hybrid.sweep(ball, t_end=1.0, grid={"e": [0.5]}, rtol=2.0, workers=0)
    with pytest.raises(UsageError, match="nothing to vary"):
        hybrid.sweep(ball, t_end=1.0, workers=0)
    # before: the held value was dropped without a word (the grid's values ran)
    with pytest.raises(UsageError, match="e is varied and also held by parameters"):
        hybrid.sweep(ball, t_end=1.0, grid={"e": [0.5, 0.9]}, parameters={"e": 0.3}, workers=0)
    with pytest.raises(UsageError, match="e is varied and also held by parameters"):
        hybrid.sweep(ball, t_end=1.0, points=[{"e": 0.5}], parameters={"e": 0.3}, workers=0)
    with pytest.raises(UsageError, match="e is varied and also held by parameters"):
        hybrid.falsify(ball, t_end=1.0, vary={"e": (0.5, 0.9)}, parameters={"e": 0.3},
                       requirement="any", workers=0)  # fmt: skip
    with pytest.raises(UsageError, match="not both"):
        hybrid.sweep(ball, t_end=1.0, grid={"e": [0.5]}, workers=2, scheduler="tcp://x:1")
