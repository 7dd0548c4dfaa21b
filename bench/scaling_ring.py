"""Coupled components: a ring of N thermostats coupled through signals, N = 10 to 200.

The thermostats of :mod:`bench.scaling_components` (the same flows, switching
points and initial temperatures), each now heating faster while its
neighbour's heater is on: thermostat ``i`` defines a signal ``p{i}`` (1 while
on, else 0) and reads ``p{i-1}`` through an input, so no component is
independent of the others and the system is simulated as one product, to
``t = 20``. Each size runs in fresh processes, after an import and a tiny
warm-up simulation: the first ``simulate`` of the ring in the process (its
modes compiled as the run meets them) and the second (all compiled), each
after a full collection of what came before it, in CPU seconds; in another
process the peak of memory allocated while each call runs (tracemalloc, which
slows the calls, so its times are not used). Reported:
medians over ``repeats`` processes and the growth exponent between
consecutive sizes, ``log(v2 / v1) / log(n2 / n1)`` (linear reads 1; the
target is at most 1.15).

Run ``python -m bench.scaling_ring``.
"""

from __future__ import annotations

import itertools
import json
import math
import statistics
import subprocess
import sys
from typing import Any

import hybrid

__all__ = ["SIZES", "TARGET", "measure", "ring", "run"]

SIZES = (10, 50, 100, 200)
TARGET = 1.15
T_END = 20.0


def thermostat_text(i: int, n: int) -> str:
    prev = (i - 1) % n
    flow_off = f"-0.1*(T{i} - 10) + 0.05*p{prev}"
    flow_on = f"0.1*(30 - T{i}) + 0.05*p{prev}"
    return f"""
automaton: th{i}
state: {{T{i}: {{initial: {18 + (i % 7) * 0.5}, bounds: [0, 40]}}}}
signals: {{p{i}: 0}}
inputs: [p{prev}]
locations:
  off: {{flow: {{T{i}: {flow_off}}}, invariant: T{i} >= 18}}
  on: {{flow: {{T{i}: {flow_on}}}, signals: {{p{i}: 1}}, invariant: T{i} <= 22}}
edges:
  - {{name: heat, from: off, to: on, guard: T{i} <= 18}}
  - {{name: rest, from: on, to: off, guard: T{i} >= 22}}
"""


def ring(n: int) -> hybrid.System:
    """``n`` thermostats, each reading its predecessor's heater signal."""
    return hybrid.compose(*[hybrid.load_text(thermostat_text(i, n)) for i in range(n)])


def measure(n: int, memory: bool) -> dict[str, Any]:
    """One process's first and second ``simulate`` of the ring of ``n``: CPU s or peak MB.

    With the CPU times, the part of each spent in the cyclic garbage collector's full
    collections (``gc.callbacks``): each walks every object of the process, the
    imported libraries' included, and how many a call meets depends on how much it
    allocates, in steps. Each call starts after a full collection, so that it
    collects only what it allocated itself: without it, the second call at one size
    and not at another walked the heap for objects the first call had left (the
    functions it compiled), depending only on where the collector's counts stood.
    """
    import gc
    import time
    import tracemalloc

    hybrid.simulate(ring(2), t_end=1.0, handle_sigint=False)  # imports and warm-up
    system = ring(n)
    found: dict[str, Any] = {"n": n}
    full = [0.0, 0.0]  # seconds in full collections, and when the current one started

    def clock(phase: str, info: dict[str, Any]) -> None:
        if info["generation"] == 2:
            if phase == "start":
                full[1] = time.process_time()
            else:
                full[0] += time.process_time() - full[1]

    gc.callbacks.append(clock)
    for call in ("first", "second"):
        gc.collect()  # what earlier calls left is not this call's to collect
        if memory:
            tracemalloc.start()
        full[0] = 0.0
        start = time.process_time()
        run = hybrid.simulate(system, t_end=T_END, handle_sigint=False)
        spent = time.process_time() - start
        if memory:
            found[f"{call}_peak_mb"] = tracemalloc.get_traced_memory()[1] / 1e6
            tracemalloc.stop()
        else:
            found[f"{call}_cpu_s"] = spent
            found[f"{call}_full_gc_s"] = full[0]
        found["jumps"], found["points"] = len(run.jumps), len(run)
    gc.callbacks.remove(clock)
    return found


def _in_subprocess(n: int, memory: bool) -> dict[str, Any]:
    code = (
        "import json\n"
        "from bench import scaling_ring as b\n"
        "from bench.resident import peak_mb\n"
        f"r = b.measure({n}, {memory})\n"
        "r['peak_rss_mb'] = peak_mb()\n"
        "print(json.dumps(r))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=1200
    )
    result: dict[str, Any] = json.loads(out.stdout.strip().splitlines()[-1])
    return result


def _exponents(rows: list[dict[str, Any]], key: str) -> list[float]:
    return [
        math.log(b[key] / a[key]) / math.log(b["n"] / a["n"]) for a, b in itertools.pairwise(rows)
    ]


def run(repeats: int = 5) -> dict[str, Any]:
    """Medians per size over ``repeats`` processes, and the exponents between sizes.

    The sizes take turns (each repeat runs every size once), so that a stretch of time
    when the machine is slower falls on all of them alike, not on one size's processes.
    """
    measured: dict[int, list[dict[str, Any]]] = {n: [] for n in SIZES}
    for _ in range(repeats):
        for n in SIZES:
            measured[n].append(_in_subprocess(n, memory=False))
    rows = []
    for n in SIZES:
        times = measured[n]
        memory = _in_subprocess(n, memory=True)
        rows.append(
            {
                "n": n,
                "jumps": times[0]["jumps"],
                "points": times[0]["points"],
                "first_cpu_s": statistics.median(t["first_cpu_s"] for t in times),
                "second_cpu_s": statistics.median(t["second_cpu_s"] for t in times),
                "first_full_gc_s": statistics.median(t["first_full_gc_s"] for t in times),
                "second_full_gc_s": statistics.median(t["second_full_gc_s"] for t in times),
                **{
                    f"{c}_without_full_gc_s": statistics.median(
                        t[f"{c}_cpu_s"] - t[f"{c}_full_gc_s"] for t in times
                    )
                    for c in ("first", "second")
                },
                "first_peak_mb": memory["first_peak_mb"],
                "second_peak_mb": memory["second_peak_mb"],
                "peak_rss_mb": statistics.median(t["peak_rss_mb"] for t in times),
            }
        )
    keys = ("first_cpu_s", "second_cpu_s", "first_peak_mb", "second_peak_mb")
    exponents = {k: _exponents(rows, k) for k in keys}
    return {
        "t_end": T_END,
        "repeats": repeats,
        "rows": rows,
        "exponents": exponents,
        # where the cyclic collector's full collections fall depends on what the process
        # allocated before them (the steps move between calls and sizes): the time
        # without them says what the simulation itself costs
        "exponents_without_full_collections": {
            f"{c}_cpu_s": _exponents(rows, f"{c}_without_full_gc_s") for c in ("first", "second")
        },
        "target": TARGET,
        "within_target": all(e <= TARGET for v in exponents.values() for e in v),
    }


def main() -> int:
    result = run()
    for row in result["rows"]:
        print(
            f"n={row['n']:4d}: jumps {row['jumps']:5d}, first {row['first_cpu_s']:.3f} s, "
            f"second {row['second_cpu_s']:.3f} s CPU; peak {row['first_peak_mb']:.1f} / "
            f"{row['second_peak_mb']:.1f} MB allocated, {row['peak_rss_mb']:.0f} MB resident"
        )
    for key, values in result["exponents"].items():
        print(f"exponents {key}: {', '.join(f'{v:.2f}' for v in values)}")
    print("result:", "ok" if result["within_target"] else "OUT OF BOUNDS")
    return 0 if result["within_target"] else 1


if __name__ == "__main__":
    raise SystemExit(main())
