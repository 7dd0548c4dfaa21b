"""``make bench``: run every benchmark, print a summary, write bench/results.json.

``python -m bench [--quick]``: --quick uses fewer repeats (for a smoke run).
``HYBRID_BENCH_HYLAA=PYTHON``: an interpreter with Hylaa installed, run beside
reach on the ARCH-COMP Building instances (bench/reach_building.py; not with --quick).
``HYBRID_BENCH_DIFFRAX=PYTHON``: an interpreter with jax and diffrax, whose ``vmap``
ensemble of the thermostat is timed beside ``simulate_many`` (bench/diffrax_peer.py;
also when this interpreter imports diffrax; not with --quick).
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path
from typing import Any

from bench import (
    engine_overhead,
    import_time,
    native_backend,
    native_floor,
    peers,
    rhs_call,
    spec_scaling,
    step_search,
    uvms_realtime,
)
from bench.harness import machine

RESULTS = Path(__file__).resolve().parent / "results.json"


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    quick = "--quick" in args
    repeats = 3 if quick else 15
    started = time.perf_counter()
    report: dict[str, Any] = {"machine": machine(), "comparisons": []}
    for module, kwargs in (
        (import_time, {"repeats": repeats}),
        (engine_overhead, {"repeats": repeats}),
        (step_search, {"repeats": repeats}),
        (rhs_call, {"repeats": repeats}),
        (uvms_realtime, {"repeats": max(3, repeats // 2)}),
        (native_backend, {"repeats": repeats, "ensemble_size": 1_000 if quick else 10_000}),
        (native_floor, {"repeats": repeats, "ensemble_size": 1_000 if quick else 10_000}),
    ):
        for result in module.run(**kwargs):
            print(result.line(), json.dumps(result.extra))
            report["comparisons"].append(result.as_dict())
    from bench import diffrax_peer

    peer = None if quick else diffrax_peer.run()
    if peer is not None:
        print(peer.line(), json.dumps(peer.extra))
        report["comparisons"].append(peer.as_dict())
    from bench import product_exploration

    # before the scaling runs, so that its peak resident memory is its own
    product = product_exploration.run(8 if quick else 12)
    print("product exploration", product)
    report["product_exploration"] = product
    from bench import scaling_components

    components = scaling_components.run(3 if quick else 7)
    print("many components", json.dumps(components))
    report["components"] = components
    from bench import scaling_ring

    ring = scaling_ring.run(2 if quick else 5)
    print("coupled ring", json.dumps(ring))
    report["coupled_ring"] = ring
    from bench import sweep_throughput

    campaigns = sweep_throughput.run(2 if quick else 3)
    print("campaigns", json.dumps(campaigns))
    report["campaigns"] = campaigns
    scaling = spec_scaling.run()
    for row in scaling["rows"]:
        print(scaling["name"], row)
    report["scaling"] = scaling
    report["native_memory"] = native_floor.memory(10_000 if quick else 100_000)
    print("compiled backend, memory of a long run", report["native_memory"])
    report["native_compile"] = native_backend.compile_times()
    print("compiled backend, compile times", report["native_compile"])
    from bench import backend_choice

    report["backend_choice"] = backend_choice.run(2 if quick else 5)
    print("backend choice", json.dumps(report["backend_choice"]))
    report["peers"] = peers.run()
    print("peers", report["peers"])
    from bench import reach_building

    # Hylaa (its own interpreter, named by HYBRID_BENCH_HYLAA) takes minutes: not in --quick
    hylaa = None if quick else os.environ.get("HYBRID_BENCH_HYLAA") or None
    report["reach"] = reach_building.run(hylaa)
    for row in report["reach"]["rows"]:
        print("reach", json.dumps(row))
    report["total_s"] = time.perf_counter() - started
    if not quick:
        RESULTS.write_text(json.dumps(report, indent=2) + "\n")
        from bench.report import update_docs

        update_docs(report)
        print(f"written {RESULTS} and the results section of docs/performance.md")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
