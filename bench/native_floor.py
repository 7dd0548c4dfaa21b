"""(7b) The compiled backend against the floor (:mod:`bench.floor`), in CPU time.

Ratios in one process, each repeat timing the floor and the compiled backend
back to back (the order alternating), CPU time (``time.process_time``: all
threads of the process), medians over the repeats:

- single runs, rtol 1e-10: the bouncing ball for 40 bounces and the thermostat
  for 20 switches, ``hybrid.simulate(..., backend="compiled")`` with the default
  Ctrl-C handling (``handle_sigint=True``) against :func:`bench.floor.single`
  (both a Python call into compiled code; each timing a loop of
  :data:`IN_A_ROW` calls); the same with ``handle_sigint=False`` and the largest
  jump-time difference to the floor are extras; and the floor's own loop with its
  model called through a function pointer, as the compiled loop calls the model
  (:mod:`bench.floor_pointer`), against the floor;
- an ensemble of 10,000 thermostat runs (20 switches each, initial temperatures
  spread), ``hybrid.simulate_many`` against :func:`bench.floor.ensemble`, per run;
- ``hybrid.sweep(..., backend="compiled")`` of 1,000 thermostat points against
  ``simulate_many`` of the same points, with ``workers=0`` and ``workers=2``;
- memory: a compiled run of 100,000 thermostat jumps in a fresh process, its
  resident growth (held ``Run``) against the bytes of its result arrays.

``python -m bench.native_floor`` prints the rows.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

import hybrid
from bench import floor, floor_pointer
from bench.harness import Comparison, compare

__all__ = ["ensemble", "memory", "run", "single_runs", "sweep"]

ROOT = Path(__file__).resolve().parent.parent
RTOL, ATOL = 1e-10, 1e-12
IN_A_ROW = 20
"""Calls of one side timed together (their mean) in each repeat of the single runs."""
THERMO_P = np.array([0.1, 10.0, 30.0, 18.0, 22.0])


def _cpu(fn: Callable[[], Any], inner: int = 1) -> float:
    start = time.process_time()
    for _ in range(inner):
        fn()
    return (time.process_time() - start) / inner


def _compare(name: str, contender: tuple[str, Callable[[], Any]],
             baseline: tuple[str, Callable[[], Any]], repeats: int, inner: int = 1,
             per: int = 1) -> Comparison:  # fmt: skip
    """CPU seconds (per ``per`` runs) of both, interleaved; ratios contender / baseline."""
    return compare(name, contender, baseline, repeats=repeats, inner=inner, timer=_cpu, per=per)


def single_runs(repeats: int = 9) -> list[Comparison]:
    """The ball (40 bounces) and the thermostat (20 switches), compiled / floor."""
    ball = hybrid.load(ROOT / "specs" / "bouncing_ball.yaml", parameters={"e": 0.95})
    thermo = hybrid.load(ROOT / "specs" / "thermostat.yaml")
    cases = (
        ("bouncing ball, 40 bounces", ball, {"t_end": 1e3, "max_jumps": 40},
         floor.BALL, np.array([9.81, 0.95]), np.array([10.0, 0.0])),
        ("thermostat, 20 switches", thermo, {"t_end": 1e4, "max_jumps": 20},
         floor.THERMOSTAT, THERMO_P, np.array([20.0])),
    )  # fmt: skip
    results = []
    for name, model, kwargs, kind, p, x0 in cases:

        def ours(m: Any = model, k: Any = kwargs, watched: bool = True) -> Any:
            return hybrid.simulate(m, rtol=RTOL, atol=ATOL, backend="compiled",
                                   handle_sigint=watched, **k)  # fmt: skip

        def base(kind: int = kind, p: Any = p, x0: Any = x0, k: Any = kwargs) -> Any:
            return floor.single(kind, p, x0, k["t_end"], k["max_jumps"], RTOL, ATOL)

        c = _compare(f"compiled single run / floor: {name}, rtol 1e-10",
                     ("simulate(backend='compiled')", ours), ("bench.floor.single", base),
                     repeats, inner=IN_A_ROW)  # fmt: skip
        quiet = _compare(name, ("handle_sigint=False", lambda o=ours: o(watched=False)),
                         ("bench.floor.single", base), repeats, inner=IN_A_ROW)  # fmt: skip
        run, (_, jumps) = ours(), base()
        c.extra = {
            "jumps": len(run.jumps),
            "max_jump_time_difference_to_floor_s": float(
                np.max(np.abs(run.jump_times - jumps[:, 0]))
            ),
            "without_sigint_ratio_median": quiet.ratio_median,
            "without_sigint_median_s": quiet.contender_median_s,
            "sigint_handling_cost_s": c.contender_median_s - quiet.contender_median_s,
        }
        results.append(c)
        pointer = _compare(f"floor, its model behind a function pointer / floor: {name}",
                           ("bench.floor_pointer.single", lambda k=kind, q=p, x=x0, a=kwargs:
                            floor_pointer.single(k, q, x, a["t_end"], a["max_jumps"], RTOL, ATOL)),
                           ("bench.floor.single", base), repeats, inner=IN_A_ROW)  # fmt: skip
        pointer.extra = {"compiled_over_pointer_floor": c.contender_median_s
                         / pointer.contender_median_s}  # fmt: skip
        results.append(pointer)
    return results


def ensemble(n: int = 10_000, repeats: int = 5) -> Comparison:
    """``simulate_many`` of ``n`` thermostat runs (20 switches) / the floor's ensemble, per run."""
    thermo = hybrid.load(ROOT / "specs" / "thermostat.yaml")
    starts = np.linspace(18.5, 21.5, n)
    kwargs: dict[str, Any] = {"t_end": 1e4, "max_jumps": 20, "rtol": RTOL, "atol": ATOL,
                              "handle_sigint": False}  # fmt: skip

    def ours() -> Any:
        return hybrid.simulate_many(thermo, parameters={"init.T": starts}, **kwargs)

    def base() -> Any:
        return floor.ensemble(THERMO_P, starts, kwargs["t_end"], kwargs["max_jumps"], RTOL, ATOL)

    c = _compare(f"compiled ensemble / floor: {n:,} thermostat runs, per run, rtol 1e-10",
                 ("simulate_many", ours), ("bench.floor.ensemble", base), repeats, per=n)  # fmt: skip
    runs, (times, _) = ours(), base()
    c.extra = {
        "runs": n,
        "last_run_jump_time_difference_to_floor_s": float(
            np.max(np.abs(runs[n - 1].jump_times - times[n - 1]))
        ),
    }
    return c


def sweep(n: int = 1_000, repeats: int = 5) -> list[Comparison]:
    """``hybrid.sweep`` of ``n`` thermostat points, compiled, / ``simulate_many`` of the same.

    With ``workers=0`` and ``workers=2`` (both run in this process now); CPU
    time of this process, after a warm-up of each.
    """
    thermo = hybrid.load(ROOT / "specs" / "thermostat.yaml")
    highs = np.linspace(21.0, 23.0, n // 4)
    grid = {"T_high": list(highs), "init.T": [16.0, 17.0, 19.0, 20.0]}
    points = {"T_high": np.repeat(highs, 4), "init.T": np.tile(grid["init.T"], n // 4)}
    tol: dict[str, Any] = {"rtol": RTOL, "atol": ATOL, "handle_sigint": False}

    def many() -> Any:
        return hybrid.simulate_many(thermo, t_end=200.0, parameters=points, **tol)

    results = []
    for workers in (0, 2):

        def table(w: int = workers) -> Any:
            return hybrid.sweep(thermo, 200.0, grid=grid, summaries=("jump_t:5",), workers=w,
                                backend="compiled", **tol)  # fmt: skip

        c = _compare(f"compiled sweep / simulate_many: {n:,} thermostat points, workers={workers}",
                     ("hybrid.sweep(backend='compiled')", table), ("simulate_many", many),
                     repeats)  # fmt: skip
        rows, runs = table().rows, many()
        c.extra = {"max_jump_t5_difference_s": float(max(
            abs(row["jump_t:5"] - runs[k].jump_times[4]) for k, row in enumerate(rows)
        ))}  # fmt: skip
        results.append(c)
    return results


_MEMORY = """
import json, resource
import numpy as np
import hybrid

def rss():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * resource.getpagesize()

thermo = hybrid.load({spec!r})
kw = dict(rtol=1e-6, atol=1e-9, backend="compiled", handle_sigint=False)
hybrid.simulate(thermo, t_end=100.0, max_jumps=10, **kw)  # compiled code loaded
before = rss()
run = hybrid.simulate(thermo, t_end=1e8, max_jumps={jumps}, **kw)
len(run.jumps)
after = rss()
n = len(run.jumps)
d = len(run.state_names)
arrays = run.t.nbytes + run.j.nbytes + run.states.nbytes + run.signals.nbytes + \\
    n * 8 * (2 + 2 * d) + run.location.nbytes
print(json.dumps({{"jumps": n, "points": int(run.t.size), "growth_bytes": after - before,
                  "result_array_bytes": arrays}}))
"""


def memory(jumps: int = 100_000) -> dict[str, Any]:
    """Resident growth of a held compiled run of ``jumps`` thermostat jumps (a fresh process).

    ``growth_bytes``: resident memory after the run (held) less before it, in
    a process that has run the model once briefly (its compiled code loaded):
    what the run and the room its loop was given cost the process.
    ``result_array_bytes``: its points (``t``, ``j``, states, signals,
    locations) and its jumps as arrays (time, index, state before and after:
    ``8 (2 + 2 d)`` bytes each).
    """
    code = _MEMORY.format(spec=str(ROOT / "specs" / "thermostat.yaml"), jumps=jumps)
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT,
                         check=True)  # fmt: skip
    row: dict[str, Any] = json.loads(out.stdout.splitlines()[-1])
    row["growth_over_arrays"] = row["growth_bytes"] / row["result_array_bytes"]
    row["growth_per_jump_bytes"] = row["growth_bytes"] / row["jumps"]
    return row


def run(repeats: int = 9, ensemble_size: int = 10_000) -> list[Comparison]:
    results = single_runs(repeats)
    results.append(ensemble(ensemble_size, max(3, repeats // 3)))
    results += sweep(1_000, max(3, repeats // 3))
    return results


if __name__ == "__main__":
    quick = sys.argv[1:] == ["--quick"]
    for result in run(5 if quick else 9, 1_000 if quick else 10_000):
        print(result.line(), json.dumps(result.extra))
    print("memory", json.dumps(memory(10_000 if quick else 100_000)))
