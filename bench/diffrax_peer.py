"""``simulate_many`` of 10,000 thermostat runs against diffrax's ``vmap`` ensemble, per run.

diffrax runs in the interpreter ``HYBRID_BENCH_DIFFRAX`` names (one with ``jax``
and ``diffrax``: ``pip install jax diffrax``), or in this one if it imports
diffrax; without either the row is left out. ``bench/diffrax_driver.py`` builds
the same runs by hand (20 switches each and the 21st located, where
``max_jumps=20`` ends hybrid's run; Dopri5 at the same tolerances, each
switch located by an event; see its docstring), compiles them once, and times
them; here ``simulate_many`` of the same initial temperatures is timed after
each of its calls, so the two alternate. Both are CPU seconds per run (diffrax
over all its XLA threads). Both runs' event times are compared with the closed
form.

    python -m bench.diffrax_peer [N]
"""

from __future__ import annotations

import importlib.util
import json
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

import hybrid
from bench.diffrax_driver import ATOL, RTOL, STAYS, SWITCHES, closed_form
from bench.harness import Comparison, paired

__all__ = ["interpreter", "run"]

ROOT = Path(__file__).resolve().parent.parent
DRIVER = Path(__file__).with_name("diffrax_driver.py")


def interpreter() -> str | None:
    """The Python that runs diffrax: ``HYBRID_BENCH_DIFFRAX``, else this one if it has it."""
    named = os.environ.get("HYBRID_BENCH_DIFFRAX")
    if named:
        return named
    return sys.executable if importlib.util.find_spec("diffrax") is not None else None


def _theirs(python: str, n: int, repeats: int) -> dict[str, Any]:
    out = subprocess.run(
        [python, str(DRIVER), str(n), str(repeats)],
        capture_output=True, text=True, check=True, env={**os.environ, "JAX_PLATFORMS": "cpu"},
    )  # fmt: skip
    return dict(json.loads(out.stdout.strip().splitlines()[-1]))


def run(n: int = 10_000, rounds: int = 3, python: str | None = None) -> Comparison | None:
    """The comparison, or None when no interpreter has diffrax."""
    python = python or interpreter()
    if python is None:
        return None
    thermo = hybrid.load(ROOT / "specs" / "thermostat.yaml")
    starts = np.linspace(18.5, 21.5, n)
    kwargs: dict[str, Any] = {"t_end": 1e4, "max_jumps": SWITCHES, "rtol": RTOL, "atol": ATOL,
                              "handle_sigint": False}  # fmt: skip

    def ours() -> Any:
        return hybrid.simulate_many(thermo, parameters={"init.T": starts}, **kwargs)

    runs = ours()  # compiled and loaded, as diffrax's first call is not timed either
    mine: list[float] = []
    theirs: list[float] = []
    reported: dict[str, Any] = {}
    for _ in range(rounds):
        reported = _theirs(python, n, 3)
        begun = time.process_time()
        ours()
        mine.append((time.process_time() - begun) / n)
        theirs.append(float(reported["per_run_s"]))
    truth = np.array([closed_form(float(s), STAYS) for s in starts])
    ours_error = max(  # the switches taken and the one located where max_jumps ends the run
        float(np.max(np.abs(np.append(r.jump_times, r.termination.t) - t)))
        for r, t in zip(runs, truth, strict=True)
    )
    return paired(
        f"simulate_many / diffrax vmap ensemble: {n:,} thermostat runs, per run, rtol 1e-10",
        "simulate_many (compiled)",
        str(reported["tool"]),
        mine,
        theirs,
        {
            "runs": n,
            "event_time_error_s": ours_error,
            "diffrax_event_time_error_s": float(reported["max_event_time_error_s"]),
            "diffrax_first_call_s": float(reported["first_call_s"]),
        },
    )


if __name__ == "__main__":
    result = run(int(sys.argv[1]) if len(sys.argv) > 1 else 10_000)
    if result is None:
        raise SystemExit("no interpreter with diffrax: set HYBRID_BENCH_DIFFRAX=PYTHON")
    print(result.line(), json.dumps(result.extra))
