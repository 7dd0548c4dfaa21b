"""(4) Load, validate and check generated automata of growing size: time and peak memory.

Each automaton has n locations on a ring, each with about 5 outgoing edges (to the
next 5 locations), one state variable with bounds and simple guards. The growth
exponent between sizes is log(t2/t1)/log(n2/n1): 1 is linear, n log n reads a
little above 1.
"""

from __future__ import annotations

import itertools
import math
import time
import tracemalloc
from typing import Any

import hybrid

__all__ = ["generate", "run"]

SIZES = (10, 100, 1000, 10_000)


def generate(n: int, edges_per_location: int = 5) -> str:
    lines = [
        f"automaton: ring{n}",
        "parameters: {k: 1.0}",
        "state:",
        "  c: {initial: 0.0, bounds: [0, 10]}",
        "labels: [tick]",
        "locations:",
    ]
    lines += [f"  l{i}: {{flow: {{c: k}}, invariant: c <= 10}}" for i in range(n)]
    lines.append("edges:")
    for i in range(n):
        for d in range(1, edges_per_location + 1):
            lines.append(
                f"  - {{from: l{i}, to: l{(i + d) % n}, guard: c >= {d}, reset: {{c: 0}}, priority: {d}}}"
            )
    return "\n".join(lines) + "\n"


def _timed(fn: Any) -> tuple[float, Any]:
    start = time.perf_counter()
    value = fn()
    return time.perf_counter() - start, value


def _peak_mib(fn: Any) -> float:
    """Peak traced allocation of ``fn`` (a separate run: tracing slows code several times)."""
    tracemalloc.start()
    fn()
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    return peak / 2**20


def run() -> dict[str, Any]:
    from hybrid.analysis import check

    rows = []
    for n in SIZES:
        text = generate(n)
        t_load, model = _timed(lambda text=text: hybrid.load_text(text))
        t_check, _ = _timed(lambda model=model: check(model))
        rows.append(
            {
                "locations": n,
                "edges": 5 * n,
                "bytes": len(text),
                "load_s": t_load,
                "check_s": t_check,
                "load_peak_MiB": _peak_mib(lambda text=text: hybrid.load_text(text)),
                "check_peak_MiB": _peak_mib(lambda model=model: check(model)),
            }
        )
    for a, b in itertools.pairwise(rows):
        ratio = b["locations"] / a["locations"]
        for key in ("load_s", "check_s"):
            b[f"{key}_growth_exponent"] = math.log(b[key] / a[key]) / math.log(ratio)
    return {"name": "load/validate/check scaling", "rows": rows}


if __name__ == "__main__":
    for row in run()["rows"]:
        print(row)
