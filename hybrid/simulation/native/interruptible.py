"""Ctrl-C during a compiled run: the loop stops at the step where the first Ctrl-C came.

Compiled code cannot be interrupted by a Python signal handler (handlers run
between bytecodes, and the loop returns only when it is done), so with
``handle_sigint`` in the main thread the loop reads a flag at every step and
something other than the main thread's Python code must set it:

- A plain run (no ``tick``) runs in the main thread itself, while Python's
  signal wake-up file descriptor (:func:`signal.set_wakeup_fd`) points to a
  pipe that the process's watcher thread (:func:`_watcher`) reads: Python's C
  signal handler writes a byte there on every Ctrl-C, whichever thread holds
  the GIL, and the watcher sets the flag of the run in progress (numba
  releases the GIL). The Python-level handler (the command's
  :class:`~hybrid.simulation.interrupts.Interrupts`) runs as the loop returns,
  as it would after any blocking call. Handing the loop to another thread and
  back cost a short run's time again; this costs two system calls. A byte
  meant for a wake-up descriptor installed before (asyncio's) is passed on.
- A run that reports progress (``tick``) runs on the process's one worker
  thread while the main thread waits, turning the first Ctrl-C into the flag
  and calling ``tick()`` (as :func:`hybrid.simulation.interrupts.sigint_watch`
  does for the reference engine).

The watcher and the worker are started once per process (again after a fork).
"""

from __future__ import annotations

import contextlib
import importlib
import os
import queue
import signal
import threading
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hybrid.simulation.interrupts import _ACTIVE, note_interrupt, sigint_watch

__all__ = ["TICK", "run_here", "run_in_worker"]

TICK = 0.05
"""Seconds between the waiting thread's looks at Ctrl-C and at the run's progress."""


def run_in_worker(
    call: Callable[[NDArray[np.int64]], None],
    handle_sigint: bool,
    flag: NDArray[np.int64] | None = None,
    tick: Callable[[], None] | None = None,
) -> bool:
    """Run ``call(flag)``; with ``handle_sigint`` a first Ctrl-C sets ``flag``. True if it did.

    With ``handle_sigint`` in the main thread and no ``tick``, ``call`` runs
    here while the watcher thread turns Ctrl-C into the flag (:func:`run_here`).
    With ``tick`` in the main thread, ``call`` runs on the
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
    if tick is None:
        return run_here(call, flag)
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


def run_here(call: Callable[[NDArray[np.int64]], None], flag: NDArray[np.int64]) -> bool:
    """``call(flag)`` in the main thread, a Ctrl-C meanwhile setting ``flag`` (the watcher).

    What :func:`run_in_worker` does with ``handle_sigint`` in the main thread and
    no ``tick``; a caller that knows it is there calls it directly. True if a
    Ctrl-C came.

    Inside a command's :class:`~hybrid.simulation.interrupts.Interrupts` its
    handler sees each Ctrl-C as the loop returns; outside one a handler of
    this run's own counts them (what :func:`~hybrid.simulation.interrupts.sigint_watch`
    does, without its context managers: they cost more than a short run's signal handling).
    The handler is swapped with ``_signal.signal`` (what ``signal.signal``
    wraps): the wrapper converts every handler to and from an enum, which cost
    three times the swap itself.
    """
    active = _ACTIVE[-1] if _ACTIVE else None
    if active is not None and active.requested:
        flag[0] = 1
    write_end = _watcher()
    previous: Any = None
    if active is None:
        _PRESSES[0] = 0
        previous = _SET_HANDLER(_SIGINT, _count)
    try:
        _WATCHED[0] = flag
        try:
            before = signal.set_wakeup_fd(write_end, warn_on_full_buffer=False)
        except ValueError:  # not the main interpreter: no wake-up descriptor to borrow
            _WATCHED[0] = None
            call(flag)
        else:
            _FORWARD[0] = before
            try:
                call(flag)
            finally:
                signal.set_wakeup_fd(before, warn_on_full_buffer=False)
                _FORWARD[0] = -1
                _WATCHED[0] = None
    finally:
        if active is None:
            _SET_HANDLER(_SIGINT, previous)
    if (active is None and _PRESSES[0]) or (active is not None and active.requested):
        flag[0] = 1  # the handler has run by now
    return bool(flag[0])


_SIGINT = int(signal.SIGINT)
_SET_HANDLER: Callable[[int, Any], Any] = importlib.import_module("_signal").signal
"""``signal.signal`` without its conversions to and from enums (the C function it wraps)."""
_PRESSES: list[int] = [0]
"""Ctrl-C presses seen by :func:`_count` during the run in progress in the main thread."""


def _count(signum: int, frame: Any) -> None:
    """The SIGINT handler of a run outside a command: count the press (no KeyboardInterrupt)."""
    _PRESSES[0] += 1
    note_interrupt()


_WATCHED: list[NDArray[np.int64] | None] = [None]
"""The flag of the run in progress in the main thread, which the watcher sets on Ctrl-C."""
_FORWARD: list[int] = [-1]
"""The wake-up descriptor installed before the run's (asyncio's, say): bytes passed on to it."""
_WATCHER: list[tuple[int, int, int]] = []
"""``(pid, read end, write end)`` of this process's watcher's pipe."""


def _watcher() -> int:
    """The write end of the pipe whose bytes the watcher thread turns into the run's flag."""
    started = _WATCHER[0] if _WATCHER else None  # without the lock: one tuple, set at once
    if started is not None:  # this process's: a fork's child clears it (_reset_after_fork)
        return started[2]
    with _WORKER_LOCK:
        if _WATCHER and _WATCHER[0][0] == os.getpid():
            return _WATCHER[0][2]
        read_end, write_end = os.pipe()
        os.set_blocking(write_end, False)
        threading.Thread(target=_watch, args=(read_end,), name="hybrid-sigint", daemon=True).start()
        _WATCHER[:] = [(os.getpid(), read_end, write_end)]
        return write_end


def _watch(read_end: int) -> None:
    """The watcher: each byte is a signal; set the flag of the run in progress."""
    while True:
        try:
            data = os.read(read_end, 64)
        except OSError:
            return
        if not data:
            return
        if signal.SIGINT in data:
            flag = _WATCHED[0]
            if flag is not None:
                flag[0] = 1
        forward = _FORWARD[0]
        if forward >= 0:
            with contextlib.suppress(OSError):
                os.write(forward, data)


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
    for _, read_end, write_end in _WATCHER:  # the parent's; the child makes its own
        for end in (read_end, write_end):
            with contextlib.suppress(OSError):
                os.close(end)
    _WATCHER.clear()
    _WATCHED[0] = None
    _FORWARD[0] = -1


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
