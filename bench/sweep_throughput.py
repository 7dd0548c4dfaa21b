"""Campaigns: sweep throughput against a hand-written serial loop of ``hybrid.simulate``.

The same 96 runs of the bouncing ball (restitution e from 0.5 to 0.95, 20 s, rtol
1e-9): the baseline is ``[hybrid.simulate(ball, parameters={"e": e}) for e in ...]``
in this process; the contenders are ``hybrid.sweep`` with one and two local worker
processes (each call starts its workers: that cost is in the figures) and on a Dask
``LocalCluster`` (one and two worker processes, started once, outside the timing).
Reported: runs per second of each, the speed-up of two workers over the loop, the
overhead per run of one worker and of Dask (their time less the loop's, per run, as a
share of a run), and the cost of monitoring one requirement (an oscillating trajectory
with and without ``always: x <= 0.5``). The load average of the machine is recorded
before and after: other work on the cores lowers the speed-up.

Run alone: ``python -m bench.sweep_throughput``.
"""

from __future__ import annotations

import json
import os
import statistics
import sys
import time
from typing import Any

import hybrid

__all__ = ["run"]

RUNS = 96
T_END = 20.0
SETTINGS: dict[str, Any] = {"rtol": 1e-9, "atol": 1e-12}
WAVE = """
automaton: wave
parameters: {w: 50.0}
state: {x: {initial: 0.0}}
locations: {on: {flow: {x: cos(w*t)}}}
"""


_CALLS = [0]


def _grid() -> list[float]:
    """The restitutions of one timed call: new values each call (a long-lived worker keeps
    the compiled model of each parameter value it has seen; the loop compiles every run)."""
    _CALLS[0] += 1
    shift = 1e-6 * _CALLS[0]
    return [0.5 + 0.45 * k / (RUNS - 1) + shift for k in range(RUNS)]


def _serial(ball: Any) -> list[float]:
    return [
        hybrid.simulate(ball, t_end=T_END, parameters={"e": e}, **SETTINGS).termination.t
        for e in _grid()
    ]


def _sweep(ball: Any, **where: Any) -> list[float]:
    table = hybrid.sweep(ball, t_end=T_END, grid={"e": _grid()}, **SETTINGS, **where)
    return [row["t"] for row in table.rows]


def _best(fn: Any, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def _say(text: str) -> None:
    print(f"sweep_throughput: {text}", file=sys.stderr, flush=True)


def run(repeats: int = 3) -> dict[str, Any]:
    """Measure; every figure of the result is in seconds, runs per second or a ratio."""
    from dask.distributed import Client, LocalCluster

    ball = hybrid.load("specs/bouncing_ball.yaml")
    load_before = os.getloadavg()
    _CALLS[0] = -1
    first = _serial(ball)
    _CALLS[0] = -1
    assert first == _sweep(ball, workers=2)  # the same runs, the same ends
    serial = _best(lambda: _serial(ball), repeats)
    _say(f"loop {serial:.2f} s")
    one = _best(lambda: _sweep(ball, workers=1), repeats)
    _say(f"1 worker {one:.2f} s")
    two = _best(lambda: _sweep(ball, workers=2), repeats)
    _say(f"2 workers {two:.2f} s")
    dask: dict[str, float] = {}
    for n in (1, 2):
        with (
            LocalCluster(
                n_workers=n, threads_per_worker=1, processes=True, dashboard_address=None
            ) as cluster,
            Client(cluster) as client,
        ):
            _sweep(ball, scheduler=client)  # warm: the workers import hybrid once
            dask[f"dask_{n}_s"] = _best(lambda c=client: _sweep(ball, scheduler=c), repeats)
            _say(f"dask {n} {dask[f'dask_{n}_s']:.2f} s")
    per_run = serial / RUNS
    wave = hybrid.load_text(WAVE)
    watched = hybrid.load_text(WAVE + 'requirements: [{name: low, always: "x <= 0.5"}]\n')
    plain_s = _best(lambda: hybrid.simulate(wave, t_end=10.0), repeats * 3)
    watched_s = _best(lambda: hybrid.simulate(watched, t_end=10.0), repeats * 3)
    return {
        "runs": RUNS,
        "serial_s": serial,
        "workers_1_s": one,
        "workers_2_s": two,
        **dask,
        "serial_runs_per_s": RUNS / serial,
        "workers_1_runs_per_s": RUNS / one,
        "workers_2_runs_per_s": RUNS / two,
        "dask_2_runs_per_s": RUNS / dask["dask_2_s"],
        "speedup_2_workers": serial / two,
        "overhead_per_run_1_worker": (one - serial) / RUNS / per_run,
        "dask_overhead_per_run_ms": (dask["dask_1_s"] - serial) / RUNS * 1e3,
        "dask_overhead_per_run_share": (dask["dask_1_s"] - serial) / RUNS / per_run,
        "run_ms": per_run * 1e3,
        "requirement_monitor_ratio": watched_s / plain_s,
        "load_before": load_before,
        "load_after": os.getloadavg(),
        "cpus": os.cpu_count(),
    }


if __name__ == "__main__":
    print(json.dumps(run(), indent=2))
