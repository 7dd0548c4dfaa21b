"""Campaign jobs on a Dask distributed cluster (the optional extra ``dask``).

:class:`DaskPool` speaks only to a scheduler: a ``dask.distributed.Client`` the
user made (a ``LocalCluster``, ``dask-jobqueue`` on a batch system, a Kubernetes
operator...) or the address of a running scheduler (``tcp://host:8786``). The
model is scattered to every worker once; jobs go as batches, one Dask task per
batch (a task costs about a millisecond of scheduling: a batch of runs keeps
that small against the runs), smaller towards the end
(:func:`~hybrid.campaigns.executors.guided_size`, at least :data:`MIN_DASK_BATCH`
runs) so that the last tasks finish together; each worker unpacks the model once per process
and reuses its compiled model. Results come back as tasks finish and are
ordered by the campaign, so the table is the one a laptop gives.

The workers need ``hybrid`` installed (the same version) and the function
libraries the spec ``uses``. A run's ``run_timeout`` is enforced inside the
run (it stops at the next solver step past the limit); Dask cannot stop a
task that never reaches one, so there is no hard timeout on a cluster.

Examples
--------
>>> from hybrid.campaigns.cluster import DaskPool   # doctest: +SKIP
>>> from dask.distributed import Client, LocalCluster  # doctest: +SKIP
>>> pool = DaskPool(Client(LocalCluster(n_workers=2)))  # doctest: +SKIP
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

from hybrid.campaigns.executors import Executor, Failed, OnResult, Stop, _failed, guided_size
from hybrid.campaigns.jobs import Job, execute
from hybrid.campaigns.payload import Payload
from hybrid.campaigns.runs import RunPlan
from hybrid.errors import UsageError
from hybrid.version import install_hint

__all__ = ["DaskPool"]

MIN_DASK_BATCH = 4
"""Runs per Dask task at least (by default): a task costs about a millisecond."""
POLL_DASK = 0.02
"""Seconds between looks at the tasks (and at Ctrl-C) while none has finished."""


def _client(scheduler: Any) -> tuple[Any, bool]:
    """The client of ``scheduler`` (a Client, or an address to connect to) and whether it is ours."""
    try:
        from distributed import Client
    except ImportError:
        raise UsageError(
            f"a Dask scheduler needs dask.distributed: {install_hint('dask')}"
        ) from None
    if isinstance(scheduler, Client):
        return scheduler, False
    if not isinstance(scheduler, str):
        raise UsageError(
            f"scheduler must be a dask.distributed.Client or an address, got {scheduler!r}"
        )
    try:
        return Client(scheduler, timeout="20s"), True  # type: ignore[no-untyped-call,unused-ignore]
    except Exception as exc:  # distributed raises OSError, TimeoutError, ValueError...
        raise UsageError(f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None


class DaskPool(Executor):
    """Jobs as batches of Dask tasks (see the module docstring)."""

    def __init__(self, scheduler: Any, *, batch: int | None = None) -> None:
        self.client, self.own = _client(scheduler)
        self.batch = batch
        threads = self.client.nthreads()
        self.workers = max(1, sum(threads.values()) if threads else 1)

    def start(self, payload: Payload, plan: RunPlan) -> None:
        self.plan = plan
        self.payload = self.client.scatter(payload, broadcast=True)

    def run(
        self,
        jobs: Sequence[Job],
        on_result: OnResult,
        failed: Failed = _failed,
        should_stop: Stop = lambda: False,
        limit: float | None = None,
    ) -> bool:
        batches: list[list[Job]] = []
        k = 0
        while k < len(jobs):
            size = self.batch or max(
                MIN_DASK_BATCH, guided_size(len(jobs) - k, self.workers, cap=256)
            )
            batches.append(list(jobs[k : k + size]))
            k += size
        futures = {
            self.client.submit(execute, self.payload, self.plan, batch, pure=False): batch
            for batch in batches
        }
        pending = set(futures)
        while pending:
            if should_stop():
                self.client.cancel(list(pending))
                return False
            done = {f for f in pending if f.done()}
            if not done:
                time.sleep(POLL_DASK)
                continue
            pending -= done
            for future in sorted(done, key=lambda f: futures[f][0][0]):
                try:
                    results = future.result()
                except Exception as exc:  # a worker lost, a task that raised: rows say so
                    message = f"the Dask task failed: {type(exc).__name__}: {exc}"
                    results = [(job[0], failed(job, "error", message)) for job in futures[future]]
                for index, result in results:
                    on_result(index, result)
        return True

    def close(self) -> None:
        if self.own:
            self.client.close()
