"""The local phase of falsification: a bounded Nelder-Mead search, run inside a worker.

One search starts from a point of the global phase and minimises the
requirement's robustness over the box of the varied ranges, in unit
coordinates (each range mapped to [0, 1], so no range dominates the simplex),
with scipy's Nelder-Mead within bounds. Its first simplex spans ``step`` of
each range (turned inwards at a bound). It stops at its first violation (a run
whose requirement does not hold), or when it has run ``budget`` simulations.
A run that fails (an error, a timeout) counts as robustness ``+inf``: it cannot
be a counterexample. Everything is deterministic: the same start, the same
evaluations.

Examples
--------
>>> import hybrid, math
>>> from hybrid.campaigns.runs import RunPlan
>>> heater = hybrid.load_text('''
... automaton: heater
... parameters: {k: 0.1}
... state: {x: {initial: 20.0}}
... locations: {cooling: {flow: {x: -k*x}}}
... requirements: [{name: warm, always: "x >= 15"}]
... ''')
>>> task = {"names": ["k"], "lows": [0.0], "highs": [0.2], "start": [0.1], "budget": 40,
...         "requirement": "warm", "step": 0.1}
>>> result = local_search(heater, 0, task, RunPlan(t_end=5.0))
>>> result["found"], result["values"]["k"] > math.log(4 / 3) / 5   # x(5) < 15 beyond it
(True, True)
"""

from __future__ import annotations

import contextlib
import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from scipy.optimize import minimize

from hybrid.campaigns.runs import RunPlan, run_point
from hybrid.compose import System

__all__ = ["evaluation", "local_search", "objective"]


class _Found(Exception):
    """A violation: the search is over."""


def objective(row: Mapping[str, Any], requirement: str) -> tuple[float, bool]:
    """``(robustness, violated)`` of a run's row (``+inf``, False for a failed run)."""
    holds = row.get(f"{requirement}.holds")
    robustness = row.get(f"{requirement}.robustness")
    if holds is None or robustness is None:
        return math.inf, False
    value = float(robustness)
    if math.isnan(value):
        return math.inf, False
    return value, holds is False


def evaluation(values: Mapping[str, float], row: Mapping[str, Any], requirement: str) -> dict[str, Any]:
    """A search's record of one run: its point, ``robustness`` and ``violated`` (its
    :func:`objective`), and ``failed`` (cause and message) when the run failed: not judged."""
    robustness, violated = objective(row, requirement)
    entry: dict[str, Any] = {**values, "robustness": robustness, "violated": violated}
    if row.get(f"{requirement}.holds") is None:
        entry["failed"] = f"{row.get('cause')}: {row.get('message', '')}"
    return entry


def local_search(
    model: System, index: int, task: Mapping[str, Any], plan: RunPlan
) -> dict[str, Any]:
    """Minimise the robustness from ``task["start"]`` (see the module docstring)."""
    names = list(task["names"])
    lows = np.array(task["lows"], dtype=float)
    spans = np.array(task["highs"], dtype=float) - lows
    budget = int(task["budget"])
    requirement = str(task["requirement"])
    history: list[dict[str, Any]] = []
    best: dict[str, Any] = {"robustness": math.inf, "values": None, "found": False}

    def values_of(unit: np.ndarray) -> dict[str, float]:
        clipped = np.clip(unit, 0.0, 1.0)
        return {n: float(v) for n, v in zip(names, lows + clipped * spans, strict=True)}

    def f(unit: np.ndarray) -> float:
        if len(history) >= budget:
            raise _Found  # out of budget: stop the same way
        values = values_of(unit)
        row = run_point(model, index, values, plan)
        entry = evaluation(values, row, requirement)
        robustness, violated = entry["robustness"], entry["violated"]
        history.append(entry)
        if robustness < best["robustness"] or best["values"] is None:
            best.update(robustness=robustness, values=values, found=violated)
        if violated:
            best.update(robustness=robustness, values=values, found=True)
            raise _Found
        return robustness if math.isfinite(robustness) else 1e300

    start = np.clip(np.array(task["start"], dtype=float), 0.0, 1.0)
    step = float(task.get("step", 0.1))
    simplex = [start]
    for i in range(len(names)):
        vertex = start.copy()
        vertex[i] += step if start[i] + step <= 1.0 else -step
        simplex.append(vertex)
    with contextlib.suppress(_Found):
        minimize(
            f,
            start,
            method="Nelder-Mead",
            bounds=[(0.0, 1.0)] * len(names),
            options={
                "initial_simplex": np.array(simplex),
                "maxfev": budget,
                "xatol": 1e-9,
                "fatol": 1e-12,
            },
        )
    return {
        "found": bool(best["found"]),
        "values": best["values"],
        "robustness": best["robustness"],
        "evaluations": len(history),
        "history": history,
    }
