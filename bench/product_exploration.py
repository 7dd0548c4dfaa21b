"""Product exploration at scale: 12 copies of a 3-location automaton (3**12 = 531,441 modes).

Each copy is a cyclic timer a -> b -> c -> a on its own clock (``x_i' = 1``,
invariant ``x_i <= 2``, guard ``x_i >= 1``, reset ``x_i := 0``); the copies take
``a -> b`` together (a shared label, so they form one group of interacting
components and their product is explored whole), then ``b -> c -> a`` each on
its own and wait in ``a`` (no invariant there) for the others, so every
combination of locations is reachable. (Copies sharing no
label would be explored one by one: see bench/scaling_components.py.) The whole of
``hybrid.check`` runs on the composition, with properties asking for
reachability of every location, deadlock freedom and determinism: the
exploration visits every mode once.

Run ``python -m bench.product_exploration [--copies N]``. Prints modes
explored, modes per second, the time of the whole check and peak memory
(resident set size, from ``resource.getrusage``).
"""

from __future__ import annotations

import argparse
import dataclasses
import time
from collections.abc import Sequence

import hybrid
from bench.resident import peak_mb, reset_peak
from hybrid.analysis import analyse, run_checks
from hybrid.compose import System
from hybrid.model import Automaton, Properties

__all__ = ["build_system", "copy", "main", "run"]


def copy(i: int) -> Automaton:
    """Copy ``i`` of the 3-location timer, with its own clock ``x{i}``."""
    x = f"x{i}"
    model = hybrid.load_text(
        f"""
automaton: timer{i}
state: {{{x}: {{initial: 0, bounds: [0, 10]}}}}
labels: [go]
locations:
  a: {{flow: {{{x}: 1}}}}
  b: {{flow: {{{x}: 1}}, invariant: {x} <= 2}}
  c: {{flow: {{{x}: 1}}, invariant: {x} <= 2}}
edges:
  - {{from: a, to: b, guard: {x} >= 1, reset: {{{x}: 0}}, label: go}}
  - {{from: b, to: c, guard: {x} >= 1, reset: {{{x}: 0}}}}
  - {{from: c, to: a, guard: {x} >= 1, reset: {{{x}: 0}}}}
""",
        file=f"<timer{i}>",
    )
    assert isinstance(model, Automaton)
    return model


def build_system(copies: int) -> System:
    """``copies`` timers in parallel, with properties that need the whole product."""
    system = hybrid.compose(*[copy(i) for i in range(copies)], name=f"timers_{copies}")
    reachable = tuple(f"timer{i}.{loc}" for i in range(copies) for loc in "abc")
    props = Properties(reachable=reachable, deadlock_free=True, deterministic=True)
    return dataclasses.replace(system, properties=props)


def run(copies: int = 12) -> dict[str, float | int | bool]:
    """Check ``copies`` timers in parallel; the numbers of the run."""
    reset_peak()  # the peak of the benchmarks run before it in this process is not its own
    before = peak_mb()
    start = time.perf_counter()
    system = build_system(copies)
    analysis = analyse(system)
    findings = run_checks(analysis)
    total = time.perf_counter() - start
    exploration = analysis.exploration
    return {
        "copies": copies,
        "modes": exploration.states,
        "expected_modes": 3**copies,
        "complete": exploration.complete,
        "findings": len(findings),
        "exploration_s": exploration.seconds,
        "modes_per_s": exploration.states / exploration.seconds if exploration.seconds else 0.0,
        "check_s": total,
        "peak_rss_mb": peak_mb(),
        "rss_before_mb": before,
    }


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m bench.product_exploration")
    parser.add_argument("--copies", type=int, default=12)
    args = parser.parse_args(argv)
    r = run(args.copies)
    print(f"copies:             {r['copies']}")
    print(f"modes explored:     {r['modes']} (expected {r['expected_modes']})")
    print(f"exploration:        {r['exploration_s']:.2f} s, {r['modes_per_s']:,.0f} modes/s")
    print(f"whole check:        {r['check_s']:.2f} s ({r['findings']} findings)")
    print(f"peak memory (RSS):  {r['peak_rss_mb']:.0f} MB (before: {r['rss_before_mb']:.0f} MB)")
    ok = r["modes"] == r["expected_modes"] and r["complete"] and not r["findings"]
    print("result:            ", "ok" if ok else "UNEXPECTED")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
