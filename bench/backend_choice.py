"""(9) The default backend choice, as a user meets it: whole processes, cold and warm cache.

What a user waits for is a whole command, compile and numba import included. Each row
is the CPU time (user + system, of the process and every process it starts) of one
``hybrid`` command, the median of ``repeats`` interleaved runs:

- ``hybrid simulate`` of the thermostat (2 s): the default, ``--backend auto``, and
  ``--backend scipy`` (the baseline);
- ``hybrid sweep`` of 1,000 thermostat points (a grid of ``a``) over 100 s, in the
  command's own process (``--workers 0``: the CPU of pool workers started through a
  fork server is not counted by ``RUSAGE_CHILDREN``, which would flatter the scipy
  sweep): the default, ``--backend scipy`` and ``--backend compiled``.

**Cold** is an empty compiled cache (a new ``XDG_CACHE_HOME`` for each run: the
kernel and the model are compiled in it); **warm** is a cache one compiled run has
filled. The bars for the default: its ``simulate`` within 1.1 of scipy's, and its
sweep never more than 10 % slower than both explicit backends. Both readings of the
last are reported: against the faster backend (``default_over_best``, the strict one)
and against the slower (``default_over_worst``).
"""

from __future__ import annotations

import os
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parent.parent
SPEC = ROOT / "specs" / "thermostat.yaml"
POINTS = 1_000
SIMULATE = ["simulate", str(SPEC), "--t-end", "2"]
SWEEP_T_END = "100"


def _sweep(out: Path) -> list[str]:
    return [
        "sweep", str(SPEC), "--t-end", SWEEP_T_END, "--grid", f"a=0.05:0.2:{POINTS}",
        "--summary", "max:T", "--quiet", "--workers", "0", "--out", str(out),
    ]  # fmt: skip


def _cpu(args: list[str], cache: Path) -> float:
    """CPU seconds of ``python -m hybrid ARGS`` and its children, with ``cache`` as its cache."""
    env = {**os.environ, "XDG_CACHE_HOME": str(cache)}
    env.pop("HYBRID_NATIVE_CACHE", None)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    done = subprocess.run(
        [sys.executable, "-m", "hybrid", *args], cwd=ROOT, env=env, capture_output=True, text=True
    )
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise RuntimeError(f"hybrid {' '.join(args)} failed: {done.stderr.strip()[-500:]}")
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def _rows(work: Path, repeats: int) -> dict[str, dict[str, float]]:
    commands: dict[str, list[str]] = {
        "simulate default": SIMULATE,
        "simulate auto": [*SIMULATE, "--backend", "auto"],
        "simulate scipy": [*SIMULATE, "--backend", "scipy"],
        "sweep default": _sweep(work / "default.csv"),
        "sweep scipy": [*_sweep(work / "scipy.csv"), "--backend", "scipy"],
        "sweep compiled": [*_sweep(work / "compiled.csv"), "--backend", "compiled"],
    }
    warm = work / "warm-cache"
    _cpu([*_sweep(work / "fill.csv"), "--backend", "compiled"], warm)  # kernel and model
    _cpu([*SIMULATE, "--backend", "compiled"], warm)
    times: dict[str, dict[str, list[float]]] = {"cold": {}, "warm": {}}
    names = list(commands)
    for k in range(repeats):
        # interleaved, so that load drifts hit every row alike, and each round starting at
        # another row: in a fixed order the row after the heaviest command (a cold compiled
        # sweep, 20 s) always ran first after it
        for name in names[k % len(names):] + names[: k % len(names)]:
            args = commands[name]
            cold = work / f"cold-{k}-{name.replace(' ', '-')}"
            times["cold"].setdefault(name, []).append(_cpu(args, cold))
            times["warm"].setdefault(name, []).append(_cpu(args, warm))
    return {
        state: {name: statistics.median(values) for name, values in rows.items()}
        for state, rows in times.items()
    }


def run(repeats: int = 3) -> dict[str, Any]:
    """The rows and their ratios, cold and warm (CPU seconds, medians of ``repeats``)."""
    with tempfile.TemporaryDirectory(prefix="hybrid-bench-choice-") as folder:
        medians = _rows(Path(folder), repeats)
    result: dict[str, Any] = {"repeats": repeats, "points": POINTS, "cpu_s": medians}
    for state, rows in medians.items():
        sweeps = (rows["sweep scipy"], rows["sweep compiled"])
        result[state] = {
            "simulate_default_over_scipy": rows["simulate default"] / rows["simulate scipy"],
            "simulate_auto_over_scipy": rows["simulate auto"] / rows["simulate scipy"],
            "sweep_default_over_best": rows["sweep default"] / min(sweeps),
            "sweep_default_over_worst": rows["sweep default"] / max(sweeps),
        }
    return result


if __name__ == "__main__":
    import json

    print(json.dumps(run(int(sys.argv[1]) if len(sys.argv) > 1 else 3), indent=2))
