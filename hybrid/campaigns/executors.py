"""Where a campaign's jobs run: in this process, or in local worker processes.

Every executor takes the same jobs (:mod:`~hybrid.campaigns.jobs`) and hands
each result to ``on_result(index, result)`` as soon as it exists, in whatever
order the jobs finish; the campaign sorts by index, so the table does not
depend on the executor, the number of workers or the order of completion.

- :class:`InProcess` runs the jobs one after the other here (``workers=0``).
- :class:`LocalPool` runs them in worker processes (``forkserver`` where the
  platform has it, else ``spawn``: never ``fork``, which copies threads and
  locks). A worker never imports the user's ``__main__`` (a script need not be
  guarded by ``if __name__ == "__main__"``: the worker's code is all in this
  package). Each unpacks the model once and keeps it, so the
  simulator's compiled models are reused across its runs. Jobs go out in
  batches (two in flight per worker), smaller as the jobs run out
  (:func:`guided_size`: no worker is left with a long batch at the end while
  the others wait), and come back one by one. A worker that
  has not answered for ``limit`` seconds is stopped (a hard timeout: the job
  in progress becomes ``failed(index, "timeout", ...)``) and replaced; one that
  dies does the same with cause ``error``. The rest of its batches are run by
  the others.
- :class:`hybrid.campaigns.cluster.DaskPool` (another module: Dask is optional)
  runs the same batches on a Dask cluster.

Examples
--------
>>> import hybrid
>>> from hybrid.campaigns.payload import pack
>>> from hybrid.campaigns.runs import RunPlan
>>> payload, plan = pack(hybrid.load("specs/bouncing_ball.yaml")), RunPlan(t_end=1.0)
>>> got = {}
>>> with LocalPool(2) as pool:
...     pool.start(payload, plan)
...     pool.run([(i, "run", {"e": e}) for i, e in enumerate([0.5, 0.7, 0.9])],
...              lambda i, row: got.update({i: row["cause"]}), _failed)
True
>>> got == {0: "t_end", 1: "t_end", 2: "t_end"}
True
"""

from __future__ import annotations

import contextlib
import multiprocessing
import os
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from multiprocessing import spawn
from multiprocessing.connection import Connection, wait
from types import TracebackType
from typing import Any

from hybrid.campaigns.jobs import Job, execute, serve
from hybrid.campaigns.payload import Payload
from hybrid.campaigns.runs import RunPlan

__all__ = ["Executor", "InProcess", "LocalPool", "default_workers", "guided_size"]

OnResult = Callable[[int, Any], None]
Failed = Callable[[Job, str, str], Any]
"""``failed(job, cause, message)``: the result of a job that could not finish."""
Stop = Callable[[], bool]

POLL = 0.2
"""Seconds between looks at Ctrl-C and at timeouts while waiting for results."""
ENSEMBLE_BATCH = 256
"""Runs per ensemble call of the compiled backend when the campaign runs in this process."""


def default_workers() -> int:
    """The cores this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not on Linux
        return max(1, os.cpu_count() or 1)


def guided_size(left: int, workers: int, cap: int = 32) -> int:
    """Runs in the next batch: a share of the runs ``left``, smaller as they run out.

    A quarter of each worker's share of what is left (at most ``cap``, at least 1):
    big batches while there is much to do (few messages), single runs at the end,
    so that no worker is left with a long batch while the others are idle.

    Examples
    --------
    >>> [guided_size(n, 2) for n in (1000, 96, 20, 7, 1)]
    [32, 12, 2, 1, 1]
    """
    return max(1, min(cap, left // (4 * workers)))


def _failed(job: Job, cause: str, message: str) -> dict[str, Any]:
    return {"run": job[0], "cause": cause, "message": message}


class Executor:
    """Runs jobs; see the module docstring. A context manager: ``close`` ends its workers."""

    workers = 1

    def start(self, payload: Payload, plan: RunPlan) -> None:
        """Get ready to run jobs of ``payload``'s model under ``plan``."""
        raise NotImplementedError

    def run(
        self,
        jobs: Sequence[Job],
        on_result: OnResult,
        failed: Failed = _failed,
        should_stop: Stop = lambda: False,
        limit: float | None = None,
    ) -> bool:
        """Run ``jobs``; False if ``should_stop`` ended them early."""
        raise NotImplementedError

    def close(self) -> None:
        """Stop the workers, if any."""

    def __enter__(self) -> Executor:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        value: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


class InProcess(Executor):
    """The jobs one after the other in this process (no hard timeout)."""

    def start(self, payload: Payload, plan: RunPlan) -> None:
        self.payload, self.plan = payload, plan

    def run(
        self,
        jobs: Sequence[Job],
        on_result: OnResult,
        failed: Failed = _failed,
        should_stop: Stop = lambda: False,
        limit: float | None = None,
    ) -> bool:
        # the compiled backend runs a batch in one ensemble call; scipy one run at a time
        size = ENSEMBLE_BATCH if self.plan.backend == "compiled" else 1
        for lo in range(0, len(jobs), size):
            if should_stop():
                return False
            for index, result in execute(self.payload, self.plan, jobs[lo : lo + size]):
                on_result(index, result)
        return True


@dataclass
class _Worker:
    process: Any
    conn: Connection
    assigned: deque[Job] = field(default_factory=deque)
    since: float = 0.0


class LocalPool(Executor):
    """Worker processes on this machine (see the module docstring)."""

    def __init__(self, workers: int | None = None, *, batch: int | None = None) -> None:
        self.workers = workers or default_workers()
        self.batch = batch
        self.pool: list[_Worker] = []
        methods = multiprocessing.get_all_start_methods()
        self.context: Any = multiprocessing.get_context(
            "forkserver" if "forkserver" in methods else "spawn"
        )
        if "forkserver" in methods:
            # the scipy engine too: a compiled campaign runs in this process (choosing.settle),
            # so the workers run scipy, and each would import it (about 0.5 s) on its first run
            self.context.set_forkserver_preload(
                ["hybrid.campaigns.jobs", "hybrid.simulation.reference"]
            )

    def start(self, payload: Payload, plan: RunPlan) -> None:
        self.payload, self.plan = payload, plan
        while len(self.pool) < self.workers:
            self.pool.append(self._spawn())

    def _spawn(self) -> _Worker:
        here, there = self.context.Pipe(duplex=True)
        process = self.context.Process(
            target=serve, args=(there, self.payload, self.plan), daemon=True
        )
        with _without_main():
            process.start()
        there.close()
        return _Worker(process, here)

    def run(
        self,
        jobs: Sequence[Job],
        on_result: OnResult,
        failed: Failed = _failed,
        should_stop: Stop = lambda: False,
        limit: float | None = None,
    ) -> bool:
        queue: deque[Job] = deque(jobs)
        while queue or any(w.assigned for w in self.pool):
            if should_stop():
                self._kill_all()
                return False
            now = time.monotonic()
            for w in self.pool:
                size = self.batch or guided_size(len(queue), self.workers)
                if queue and len(w.assigned) <= size:
                    batch = [queue.popleft() for _ in range(min(size, len(queue)))]
                    if not w.assigned:
                        w.since = now
                    w.assigned.extend(batch)
                    try:
                        w.conn.send(batch)
                    except OSError:  # it died since it last answered (a broken pipe)
                        self._lost(w, queue, on_result, failed)
            busy = {w.conn: w for w in self.pool if w.assigned}
            for conn in wait(list(busy), timeout=POLL):
                self._receive(busy[conn], queue, on_result, failed)  # type: ignore[index]
            if limit is not None:
                now = time.monotonic()
                for w in list(self.pool):
                    if w.assigned and now - w.since > limit:
                        message = f"no answer within {limit:g} s: the worker was stopped"
                        self._replace(w, queue, on_result, failed, "timeout", message)
        return True

    def _receive(self, w: _Worker, queue: deque[Job], on_result: OnResult, failed: Failed) -> None:
        try:
            while w.conn.poll():
                index, result = w.conn.recv()
                while w.assigned and w.assigned[0][0] != index:
                    queue.appendleft(
                        w.assigned.popleft()
                    )  # pragma: no cover - answers are in order
                if w.assigned:
                    w.assigned.popleft()
                w.since = time.monotonic()
                on_result(index, result)
        except (EOFError, OSError):
            self._lost(w, queue, on_result, failed)

    def _lost(self, w: _Worker, queue: deque[Job], on_result: OnResult, failed: Failed) -> None:
        """``w`` died: its run in progress is an error row, the rest go to another worker."""
        w.process.join(timeout=1.0)
        code = w.process.exitcode
        message = f"the worker process died (exit code {code}) during this run"
        self._replace(w, queue, on_result, failed, "error", message)

    def _replace(
        self,
        w: _Worker,
        queue: deque[Job],
        on_result: OnResult,
        failed: Failed,
        cause: str,
        message: str,
    ) -> None:
        """Stop ``w``, report its job in progress as ``cause``, requeue the rest, start another."""
        _stop(w)
        job = w.assigned.popleft()
        queue.extendleft(reversed(w.assigned))
        self.pool[self.pool.index(w)] = self._spawn()
        on_result(job[0], failed(job, cause, message))

    def _kill_all(self) -> None:
        for w in self.pool:
            _stop(w)
        self.pool = []

    def close(self) -> None:
        for w in self.pool:
            with contextlib.suppress(OSError, ValueError):
                w.conn.send(None)
        deadline = time.monotonic() + 2.0
        for w in self.pool:
            w.process.join(timeout=max(0.0, deadline - time.monotonic()))
            _stop(w)
        self.pool = []


@contextlib.contextmanager
def _without_main() -> Iterator[None]:
    """Start processes that do not import the parent's ``__main__``.

    ``spawn`` and ``forkserver`` children import the parent's main script (so that
    functions defined there can be unpickled), which runs an unguarded script's
    campaign again in every worker. The workers run only this package's code, so
    the main module is left out of what they are told to prepare.
    """
    original = spawn.get_preparation_data

    def without_main(name: str) -> dict[str, Any]:
        data: dict[str, Any] = original(name)
        data.pop("init_main_from_name", None)
        data.pop("init_main_from_path", None)
        return data

    with _SPAWNING:
        spawn.get_preparation_data = without_main
        try:
            yield
        finally:
            spawn.get_preparation_data = original


_SPAWNING = threading.Lock()


def _stop(w: _Worker) -> None:
    if w.process.is_alive():
        w.process.kill()
        w.process.join(timeout=5.0)
    w.conn.close()
