"""Many components: `simulate` of independent thermostats scales linearly, `check` of 200
components stays within time and memory.

Simulation: ``n`` independent thermostats (one state each, its own initial
temperature, no shared label, no signal read by another) simulated to
``t = 20``, for ``n = 50`` and ``n = 200``, alternately and repeatedly in one
process after a warm-up. Growth exponent: ``log(t200 / t50) / log(4)``
(linear reads 1; the issue asks at most 1.2). Each size runs in its own
subprocess too, for its peak resident memory.

Check: 200 independent thermostats (explored apart: no product), 200
thermostats sharing one label (one group of 2**200 modes: the bounded
explorer stops with a note) and the 3x3 navigation grid (zero-time cycles),
each in a fresh subprocess, for its time and peak resident memory.

Run ``python -m bench.scaling_components``.
"""

from __future__ import annotations

import json
import math
import statistics
import subprocess
import sys
import time
from typing import Any

import hybrid

__all__ = ["check_case", "run", "simulate_case", "thermostats"]

T_END = 20.0


def thermostat_text(i: int, *, shared: bool = False) -> str:
    label = "labels: [sync]\n" if shared else ""
    sync = ", label: sync" if shared else ""
    return f"""
automaton: th{i}
state: {{T{i}: {{initial: {18 + (i % 7) * 0.5}, bounds: [0, 40]}}}}
{label}locations:
  off: {{flow: {{T{i}: -0.1*(T{i} - 10)}}, invariant: T{i} >= 18}}
  on: {{flow: {{T{i}: 0.1*(30 - T{i})}}, invariant: T{i} <= 22}}
edges:
  - {{name: heat, from: off, to: on, guard: T{i} <= 18{sync}}}
  - {{name: rest, from: on, to: off, guard: T{i} >= 22}}
"""


def thermostats(n: int, *, shared: bool = False) -> hybrid.System:
    return hybrid.compose(*[hybrid.load_text(thermostat_text(i, shared=shared)) for i in range(n)])


def simulate_case(n: int) -> dict[str, Any]:
    system = thermostats(n)
    start = time.perf_counter()
    run = hybrid.simulate(system, t_end=T_END, handle_sigint=False)
    return {"n": n, "s": time.perf_counter() - start, "jumps": len(run.jumps), "points": len(run)}


def check_case(name: str) -> dict[str, Any]:
    from hybrid.analysis import check

    if name == "navigation":
        sys.path.insert(0, "tests/analysis")
        from test_analysis_zero_time import navigation

        model: Any = hybrid.load_text(navigation())
    else:
        model = thermostats(200, shared=name == "shared")
    start = time.perf_counter()
    report = check(model)
    return {
        "case": name,
        "s": time.perf_counter() - start,
        "findings": [f.rule for f in report.findings],
    }


def _in_subprocess(call: str) -> dict[str, Any]:
    code = (
        "import json\n"
        "from bench import scaling_components as b\n"
        "from bench.resident import peak_mb\n"
        f"r = b.{call}\n"
        "r['peak_rss_mb'] = peak_mb()\n"
        "print(json.dumps(r))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=600
    )
    result: dict[str, Any] = json.loads(out.stdout.strip().splitlines()[-1])
    return result


def run(repeats: int = 5) -> dict[str, Any]:
    """Timings of both benchmarks (the simulation alternated ``repeats`` times)."""
    small, large = thermostats(50), thermostats(200)
    hybrid.simulate(small, t_end=1.0, handle_sigint=False)  # imports and warm-up
    times: dict[int, list[float]] = {50: [], 200: []}
    for r in range(repeats):
        order = [(50, small), (200, large)] if r % 2 == 0 else [(200, large), (50, small)]
        for n, system in order:
            start = time.perf_counter()
            hybrid.simulate(system, t_end=T_END, handle_sigint=False)
            times[n].append(time.perf_counter() - start)
    t50, t200 = statistics.median(times[50]), statistics.median(times[200])
    exponents = [math.log(b / a) / math.log(4) for a, b in zip(times[50], times[200], strict=True)]
    return {
        "simulate": {
            "t_end": T_END,
            "median_s_50": t50,
            "median_s_200": t200,
            "exponent": math.log(t200 / t50) / math.log(4),
            "exponent_min": min(exponents),
            "exponent_max": max(exponents),
            "fresh_process": [_in_subprocess(f"simulate_case({n})") for n in (50, 200)],
        },
        "check": [
            _in_subprocess(f"check_case({c!r})") for c in ("independent", "shared", "navigation")
        ],
    }


def main() -> int:
    result = run()
    sim = result["simulate"]
    print(
        f"simulate 50 -> 200 thermostats: {sim['median_s_50']:.2f} s -> {sim['median_s_200']:.2f} s,"
        f" exponent {sim['exponent']:.2f} (min {sim['exponent_min']:.2f}, max {sim['exponent_max']:.2f})"
    )
    for case in sim["fresh_process"]:
        print(
            f"  fresh process, n={case['n']}: {case['s']:.2f} s, peak {case['peak_rss_mb']:.0f} MB"
        )
    for case in result["check"]:
        print(
            f"check {case['case']}: {case['s']:.2f} s, peak {case['peak_rss_mb']:.0f} MB, "
            f"findings {case['findings']}"
        )
    ok = sim["exponent"] <= 1.2 and all(
        c["s"] < 30 and c["peak_rss_mb"] < 500 for c in result["check"]
    )
    print("result:", "ok" if ok else "OUT OF BOUNDS")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
