"""Ctrl-C during a compiled run: the loop runs on a worker thread, the main thread watches.

Compiled code cannot be interrupted by a Python signal handler (handlers run
between bytecodes), so with ``handle_sigint`` in the main thread the loop runs
on the process's one worker thread (numba releases the GIL) while the main
thread waits, turning the first Ctrl-C into a flag the loop reads at every
step, as :func:`hybrid.simulation.interrupts.sigint_watch` does for the
reference engine. The worker is started once per process (again after a fork):
starting a thread per run cost as much as a short run, numba setting up each
new thread besides.
"""

from __future__ import annotations

import os
import queue
import threading
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from hybrid.simulation.interrupts import sigint_watch

__all__ = ["TICK", "run_in_worker"]

TICK = 0.05
"""Seconds between the waiting thread's looks at Ctrl-C and at the run's progress."""


def run_in_worker(
    call: Callable[[NDArray[np.int64]], None],
    handle_sigint: bool,
    flag: NDArray[np.int64] | None = None,
    tick: Callable[[], None] | None = None,
) -> bool:
    """Run ``call(flag)``; with ``handle_sigint`` a first Ctrl-C sets ``flag``. True if it did.

    With ``handle_sigint`` or ``tick`` in the main thread, ``call`` runs on the
    process's worker thread (:func:`_worker_jobs`) while the main thread waits,
    turning Ctrl-C into the flag (see the module's docstring) and calling
    ``tick()`` every :data:`TICK` seconds (progress read from the run's arrays).
    With ``tick`` in another thread (only the main thread sees Ctrl-C), ``call``
    runs on a thread of its own while the calling thread ticks
    (:func:`_run_beside`): threads that run at once each keep their own loop.
    """
    flag = np.zeros(1, dtype=np.int64) if flag is None else flag
    main = threading.current_thread() is threading.main_thread()
    if tick is not None and not main:
        _run_beside(call, flag, tick)
        return False
    if not (handle_sigint or tick is not None) or not main:
        call(flag)
        return False
    done: _Done = queue.SimpleQueue()
    with sigint_watch(handle_sigint) as interrupted:
        _worker_jobs().put((call, flag, done))
        try:
            while True:
                try:
                    error = done.get(timeout=TICK)
                    break
                except queue.Empty:
                    if interrupted.requested:
                        flag[0] = 1
                    if tick is not None:
                        tick()
            if interrupted.requested:
                flag[0] = 1
        except KeyboardInterrupt:
            flag[0] = 1  # a second Ctrl-C: stop the loop too, and abandon the run
            _retire_worker()  # the next run gets a new worker, not a wait for this one
            raise
    if error is not None:
        raise error
    return bool(flag[0])


def _run_beside(
    call: Callable[[NDArray[np.int64]], None], flag: NDArray[np.int64], tick: Callable[[], None]
) -> None:
    """``call(flag)`` on a new thread while this one calls ``tick()`` every :data:`TICK` seconds.

    A thread per run costs about a short run; a run that reports progress is not short.
    """
    done: _Done = queue.SimpleQueue()
    threading.Thread(target=_run_into, args=(call, flag, done), name="hybrid-compiled-run",
                     daemon=True).start()  # fmt: skip
    while True:
        try:
            error = done.get(timeout=TICK)
            break
        except queue.Empty:
            tick()
    if error is not None:
        raise error


_Done = queue.SimpleQueue[BaseException | None]
_Job = tuple[Callable[[NDArray[np.int64]], None], NDArray[np.int64], _Done]
_WORKER: list[tuple[int, threading.Thread, queue.SimpleQueue[_Job]]] = []
_WORKER_LOCK = threading.Lock()


def _worker_jobs() -> queue.SimpleQueue[_Job]:
    """The job queue of this process's worker thread (started on first use, again after a fork)."""
    with _WORKER_LOCK:
        if _WORKER:
            pid, thread, jobs = _WORKER[0]
            if pid == os.getpid() and thread.is_alive():
                return jobs
        jobs = queue.SimpleQueue()
        thread = threading.Thread(target=_serve, args=(jobs,), name="hybrid-compiled", daemon=True)
        thread.start()
        _WORKER[:] = [(os.getpid(), thread, jobs)]
        return jobs


def _retire_worker() -> None:
    """Start a new worker for the next job; the current one ends after its job."""
    with _WORKER_LOCK:
        _WORKER.clear()


def _reset_after_fork() -> None:
    """In a forked child: no worker (threads do not survive a fork), and a lock nobody holds."""
    global _WORKER_LOCK
    _WORKER_LOCK = threading.Lock()
    _WORKER.clear()


os.register_at_fork(after_in_child=_reset_after_fork)


def _run_into(
    call: Callable[[NDArray[np.int64]], None], flag: NDArray[np.int64], done: _Done
) -> None:
    """``call(flag)``, then None or its exception into ``done`` (re-raised by the waiting thread)."""
    try:
        call(flag)
    except BaseException as exc:
        done.put(exc)
    else:
        done.put(None)


def _serve(jobs: queue.SimpleQueue[_Job]) -> None:
    """The worker: each job's ``call(flag)``, then None or its exception into its ``done`` queue.

    It ends after a job once it is no longer the process's worker (retired).
    """
    while True:
        call, flag, done = jobs.get()
        _run_into(call, flag, done)
        del call, flag, done  # hold nothing of a finished run while waiting for the next
        with _WORKER_LOCK:
            if not _WORKER or _WORKER[0][1] is not threading.current_thread():
                return
