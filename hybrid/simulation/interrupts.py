"""Ctrl-C (SIGINT) of a run or a command: stop cleanly, never lose work by accident.

A command goes through two phases. While it **runs**, every Ctrl-C only sets
:attr:`Interrupts.requested`; the event loop sees it at the end of the solver
step in progress (after the step has been searched for crossings, so the last
point is on a valid trajectory) and the run ends with cause ``interrupted``.
While it **writes** its outputs, a Ctrl-C that follows an interrupted run (or
a second Ctrl-C during writing) abandons the outputs (``KeyboardInterrupt``
is raised in the writer, whose temporary file is removed); a first Ctrl-C
during writing only says that the next one will abandon them.

The handler is installed only in the main thread (signals are delivered
there), and restored when the command or run ends. A command installs one
:class:`Interrupts` for all its phases; a run started inside it uses that one
(:func:`sigint_watch`), so a Ctrl-C between the run and the writing is never
lost.

Examples
--------
>>> stop = Interrupts()
>>> stop.press()          # what the handler does on Ctrl-C while running
>>> stop.requested
True
>>> with stop.writing():
...     try:
...         stop.press()  # after an interrupted run, the next Ctrl-C abandons the outputs
...     except KeyboardInterrupt:
...         print("abandoned")
abandoned
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["ABANDON_HINT", "Interrupts", "immediate", "interrupted", "note_interrupt", "sigint_watch"]

ABANDON_HINT = "press Ctrl-C again to abandon them"

_ACTIVE: list[Interrupts] = []
_SEEN: list[bool] = [False]


def note_interrupt() -> None:
    """Record that this process has seen a Ctrl-C (see :func:`interrupted`)."""
    _SEEN[0] = True


def interrupted() -> bool:
    """Whether this process has seen a Ctrl-C: work it stopped may leave half-made objects
    (a compile's LLVM handles) whose finalizers fail; the command line then keeps quiet
    about them as the process ends."""
    return _SEEN[0]


class Interrupts:
    """Ctrl-C presses of one command, turned into a stop request and, while writing, an abandon.

    ``notify`` receives the one-line messages meant for the user (the CLI prints
    them on stderr).
    """

    def __init__(self, notify: Callable[[str], object] | None = None) -> None:
        self.requested = False
        self.presses = 0
        self.in_writing = False
        self.abandon_armed = False
        self.in_immediate: str | None = None
        self.notify = notify

    def press(self) -> None:
        """One Ctrl-C: request a stop, or (while writing) warn, then abandon."""
        self.presses += 1
        note_interrupt()
        if self.in_immediate is not None:
            raise KeyboardInterrupt(f"interrupted while {self.in_immediate}")
        if not self.in_writing:
            self.requested = True
            return
        if self.abandon_armed:
            raise KeyboardInterrupt
        self.abandon_armed = True
        if self.notify is not None:
            self.notify(f"still writing the outputs; {ABANDON_HINT}")

    @contextmanager
    def writing(self) -> Iterator[Interrupts]:
        """The writing phase: after a stop request, the next Ctrl-C abandons the outputs."""
        self.in_writing, self.abandon_armed = True, self.requested
        try:
            yield self
        finally:
            self.in_writing = False

    def _handler(self, signum: int, frame: Any) -> None:
        self.press()

    @contextmanager
    def installed(self) -> Iterator[Interrupts]:
        """Handle SIGINT with this object (in the main thread) until the block ends."""
        if threading.current_thread() is not threading.main_thread():
            yield self
            return
        previous = signal.getsignal(signal.SIGINT)
        signal.signal(signal.SIGINT, self._handler)
        _ACTIVE.append(self)
        try:
            yield self
        finally:
            _ACTIVE.remove(self)
            signal.signal(signal.SIGINT, previous)


@contextmanager
def immediate(what: str) -> Iterator[None]:
    """Work with no result to keep (``what``: "compiling the model"): Ctrl-C stops it at once.

    Inside a command's :class:`Interrupts`, a Ctrl-C would otherwise only be
    requested and seen by the next run's loop, after a compile of many seconds;
    here it raises ``KeyboardInterrupt`` saying what was stopped (the command
    line prints that and exits 130). A Ctrl-C requested just before (while numba
    was imported, say) stops it as it starts. Outside one, Python's own handler
    raises it.

    Examples
    --------
    >>> stop = Interrupts()
    >>> _ACTIVE.append(stop)
    >>> with immediate("compiling the model"):
    ...     try:
    ...         stop.press()
    ...     except KeyboardInterrupt:
    ...         print("stopped at once")
    stopped at once
    >>> stop.requested = True  # a Ctrl-C came before the work
    >>> try:
    ...     with immediate("compiling the model"):
    ...         print("never printed")
    ... except KeyboardInterrupt as stopped:
    ...     print(stopped)
    interrupted while compiling the model
    >>> _ACTIVE.remove(stop)
    """
    if not _ACTIVE:
        yield
        return
    active = _ACTIVE[-1]
    if active.requested:  # the work would only delay the stop it asked for
        raise KeyboardInterrupt(f"interrupted while {what}")
    before, active.in_immediate = active.in_immediate, what
    try:
        yield
    finally:
        active.in_immediate = before


@contextmanager
def sigint_watch(enabled: bool) -> Iterator[Interrupts]:
    """The interrupts a run watches: the command's if one is installed, else its own.

    With ``enabled`` false (or outside the main thread) SIGINT is left alone and
    the returned object is never pressed.
    """
    if _ACTIVE and enabled:
        yield _ACTIVE[-1]
        return
    own = Interrupts()
    if not enabled:
        yield own
        return
    with own.installed():
        yield own
