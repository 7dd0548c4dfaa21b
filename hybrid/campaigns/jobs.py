"""What runs inside a worker: jobs against the model it unpacked once.

A **job** is ``(index, task, argument)``: ``task`` names a function of this
package (``"run"``: one run at a point, :func:`hybrid.campaigns.runs.run_point`;
``"search"``: a local search of falsification,
:func:`hybrid.campaigns.local_search.local_search`), so a job pickles as a few names
and numbers. :func:`execute` runs a batch of jobs anywhere (this process, a
local worker process, a Dask worker); :func:`serve` is the loop of a local
worker process, which ignores Ctrl-C (the campaign's own process decides when
to stop) and answers each job as soon as it is done.

Examples
--------
>>> import hybrid
>>> from hybrid.campaigns.payload import pack
>>> from hybrid.campaigns.runs import RunPlan
>>> payload = pack(hybrid.load("specs/bouncing_ball.yaml"))
>>> [(i, row["cause"]) for i, row in execute(payload, RunPlan(t_end=1.0), [(0, "run", {"e": 0.5})])]
[(0, 't_end')]
"""

from __future__ import annotations

import signal
from collections.abc import Sequence
from multiprocessing.connection import Connection
from typing import Any

import numpy as np

from hybrid.campaigns.payload import Payload, unpack
from hybrid.campaigns.runs import RunPlan, run_point, run_points
from hybrid.compose import System, as_system

__all__ = ["Job", "execute", "serve"]

Job = tuple[int, str, Any]
"""``(index, task, argument)``."""


def _model(payload: Payload) -> System:
    """The campaign's model, as the system every task takes (once per process: unpack's)."""
    return as_system(unpack(payload))


def _task(name: str) -> Any:
    if name == "run":
        return run_point
    if name == "search":
        from hybrid.campaigns.local_search import local_search

        return local_search
    raise ValueError(f"unknown task {name!r}")


def execute(payload: Payload, plan: RunPlan, jobs: Sequence[Job]) -> list[tuple[int, Any]]:
    """Run ``jobs`` here; their results, in order (the batch function of a Dask task)."""
    model = _model(payload)
    with np.errstate(all="ignore"):
        if _together(plan, jobs):
            return _runs_together(model, plan, jobs)
        return [(index, _task(task)(model, index, arg, plan)) for index, task, arg in jobs]


def _together(plan: RunPlan, jobs: Sequence[Job]) -> bool:
    """A batch of runs on the compiled backend: one ensemble call (:func:`run_points`)."""
    return plan.backend == "compiled" and len(jobs) > 1 and all(t == "run" for _, t, _ in jobs)


def _runs_together(model: System, plan: RunPlan, jobs: Sequence[Job]) -> list[tuple[int, Any]]:
    rows = run_points(model, [(index, arg) for index, _, arg in jobs], plan)
    return [(index, row) for (index, _, _), row in zip(jobs, rows, strict=True)]


def serve(conn: Connection, payload: Payload, plan: RunPlan) -> None:
    """A local worker process: receive batches of jobs, send back each result when done."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    model = _model(payload)
    try:
        while True:
            batch = conn.recv()
            if batch is None:
                return
            if _together(plan, batch):
                with np.errstate(all="ignore"):
                    for answer in _runs_together(model, plan, batch):
                        conn.send(answer)
                continue
            for index, task, arg in batch:
                with np.errstate(all="ignore"):
                    result = _task(task)(model, index, arg, plan)
                conn.send((index, result))
    except (EOFError, BrokenPipeError, KeyboardInterrupt):
        return
