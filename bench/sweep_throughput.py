"""Campaigns: sweep throughput against a hand-written serial loop of ``hybrid.simulate``.

The same 96 runs of the bouncing ball (restitution e from 0.5 to 0.95, 20 s, rtol
1e-9): the baseline is ``[hybrid.simulate(ball, parameters={"e": e}) for e in ...]``
in this process; the contenders are ``hybrid.sweep`` with one and two local worker
processes (each call starts its workers: that cost is in the figures) and on a Dask
``LocalCluster`` (one and two worker processes, started once, outside the timing).
Each repeat times all of them back to back (the order rotating), and every ratio is
taken against the loop of the same repeat. Reported: runs per second of each, the
speed-up of two workers over the loop, the overhead per run of one worker and of Dask
(their time less the loop's, per run, as a share of a run), and the cost of
monitoring one requirement (an oscillating trajectory with and without ``always: x
<= 0.5``).

The speed-up of two workers is only as good as the cores the machine gives: a
**parallelism control** in each repeat times a fixed piece of pure Python twice in a
row and then on two processes at once (2.0 with two free cores; 1.0 when other work
holds one of them), and ``speedup_2_workers_of_available`` is the speed-up over the
control. The load average of the machine is recorded before and after.

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
    # the scipy backend, as the serial loop: a sweep's default (auto) would run compiled in a
    # process that has the ball's compiled code loaded (the rows before this one), in place
    table = hybrid.sweep(
        ball, t_end=T_END, grid={"e": _grid()}, backend="scipy", **SETTINGS, **where
    )
    return [row["t"] for row in table.rows]


def _burn(n: int = 2_000_000) -> int:
    """Pure Python work of a fixed size (the parallelism control)."""
    total = 0
    for i in range(n):
        total += i * i
    return total


def _control(pool: Any) -> float:
    """How many cores the machine gives now: two burns one after the other, over two
    burns on two processes at once (2.0 on two free cores, 1.0 when they are taken)."""
    start = time.perf_counter()
    _burn()
    _burn()
    serial = time.perf_counter() - start
    start = time.perf_counter()
    pool.map(_burn, [2_000_000, 2_000_000])
    return serial / (time.perf_counter() - start)


def _say(text: str) -> None:
    print(f"sweep_throughput: {text}", file=sys.stderr, flush=True)


def _spread(values: list[float]) -> dict[str, float]:
    return {"median": statistics.median(values), "min": min(values), "max": max(values)}


def run(repeats: int = 3) -> dict[str, Any]:
    """Measure; every figure of the result is in seconds, runs per second or a ratio.

    Each repeat times the loop and every contender back to back, in an order that
    rotates between repeats, and each ratio is taken against the loop of the same
    repeat (the load of a shared machine drifts between minutes, not within one
    repeat); the figures are the medians of the repeats, with their min and max.
    """
    import multiprocessing

    from dask.distributed import Client, LocalCluster

    ball = hybrid.load("specs/bouncing_ball.yaml")
    load_before = os.getloadavg()
    _CALLS[0] = -1
    first = _serial(ball)
    _CALLS[0] = -1
    assert first == _sweep(ball, workers=2)  # the same runs, the same ends
    cluster_1 = LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                             dashboard_address=None)  # fmt: skip
    cluster_2 = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                             dashboard_address=None)  # fmt: skip
    burners = multiprocessing.get_context("spawn").Pool(2)
    try:
        with Client(cluster_1) as dask_1, Client(cluster_2) as dask_2:
            _sweep(ball, scheduler=dask_1)  # warm: the workers import hybrid once
            _sweep(ball, scheduler=dask_2)
            burners.map(_burn, [10, 10])
            contenders: dict[str, Any] = {
                "serial": lambda: _serial(ball),
                "workers_1": lambda: _sweep(ball, workers=1),
                "workers_2": lambda: _sweep(ball, workers=2),
                "dask_1": lambda: _sweep(ball, scheduler=dask_1),
                "dask_2": lambda: _sweep(ball, scheduler=dask_2),
            }
            names = list(contenders)
            times: dict[str, list[float]] = {n: [] for n in names}
            control: list[float] = []
            for r in range(repeats):
                control.append(_control(burners))
                order = names[r % len(names) :] + names[: r % len(names)]
                for name in order:
                    start = time.perf_counter()
                    contenders[name]()
                    times[name].append(time.perf_counter() - start)
                _say(
                    f"repeat {r + 1}/{repeats}: "
                    + ", ".join(f"{n} {times[n][-1]:.2f} s" for n in names)
                    + f"; parallelism control {control[-1]:.2f}"
                )
    finally:
        burners.terminate()
        cluster_1.close()
        cluster_2.close()
    loop = times["serial"]

    def ratios(name: str) -> list[float]:
        return [t / b for t, b in zip(times[name], loop, strict=True)]

    median = {n: statistics.median(t) for n, t in times.items()}
    speedup = [b / t for t, b in zip(times["workers_2"], loop, strict=True)]
    overhead_1 = [r - 1.0 for r in ratios("workers_1")]
    dask_over = [
        (t - b) / RUNS for t, b in zip(times["dask_1"], loop, strict=True)
    ]  # seconds per run
    wave = hybrid.load_text(WAVE)
    watched = hybrid.load_text(WAVE + 'requirements: [{name: low, always: "x <= 0.5"}]\n')
    monitor = [
        _timed(lambda: hybrid.simulate(watched, t_end=10.0))
        / _timed(lambda: hybrid.simulate(wave, t_end=10.0))
        for _ in range(repeats * 3)
    ]
    per_run = median["serial"] / RUNS
    return {
        "runs": RUNS,
        "repeats": repeats,
        "serial_s": median["serial"],
        "workers_1_s": median["workers_1"],
        "workers_2_s": median["workers_2"],
        "dask_1_s": median["dask_1"],
        "dask_2_s": median["dask_2"],
        "serial_runs_per_s": RUNS / median["serial"],
        "workers_1_runs_per_s": RUNS / median["workers_1"],
        "workers_2_runs_per_s": RUNS / median["workers_2"],
        "dask_1_runs_per_s": RUNS / median["dask_1"],
        "dask_2_runs_per_s": RUNS / median["dask_2"],
        "speedup_2_workers": statistics.median(speedup),
        "speedup_2_workers_spread": _spread(speedup),
        "parallelism_control": statistics.median(control),
        "parallelism_control_spread": _spread(control),
        "speedup_2_workers_of_available": statistics.median(
            [s / c for s, c in zip(speedup, control, strict=True)]
        ),
        "overhead_per_run_1_worker": statistics.median(overhead_1),
        "overhead_per_run_1_worker_spread": _spread(overhead_1),
        "dask_overhead_per_run_ms": statistics.median(dask_over) * 1e3,
        "dask_overhead_per_run_share": statistics.median(dask_over) / per_run,
        "dask_2_speedup": statistics.median(
            [b / t for t, b in zip(times["dask_2"], loop, strict=True)]
        ),
        "run_ms": per_run * 1e3,
        "requirement_monitor_ratio": statistics.median(monitor),
        "load_before": load_before,
        "load_after": os.getloadavg(),
        "cpus": os.cpu_count(),
    }


def _timed(fn: Any) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


if __name__ == "__main__":
    print(json.dumps(run(), indent=2))
