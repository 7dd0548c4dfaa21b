"""Progress of long work: throttled status reports, drawn on a terminal line.

Three small pieces, for any long task (a simulation, writing a large file,
checking a large product, a sweep of many runs):

- :class:`Status`: what is known at one moment: the task, how much is done of
  how much (``done``, ``total``, ``unit``), wall time, counters (jumps, points,
  violations...), and derived ``fraction``, ``rate`` and ``eta``.
- :class:`Tracker`: fed with ``update(done, **counters)`` as often as the work
  likes (every solver step, every finished run); it builds a :class:`Status`
  and calls its reporter at most every ``interval`` seconds, and always once
  from :meth:`Tracker.finish`.
- :class:`TerminalLine`: a reporter that redraws one line of a stream
  (stderr), only when that stream is a terminal, so logs and pipes stay clean.
- :class:`Bar`: a reporter drawn as a tqdm progress bar (``tqdm.auto``: the
  notebook's widget in Jupyter with ipywidgets, a text bar elsewhere), and
  :func:`reporter`, which turns a campaign's ``progress=`` into a reporter: by
  default a bar in a Jupyter kernel when tqdm is installed, nothing elsewhere.
  tqdm is optional (the ``notebook`` extra) and imported only when a bar is drawn.

A sweep reports runs done of runs planned, with the count of violations::

    tracker = Tracker("sweep", total=len(runs), unit="runs", report=TerminalLine())
    for k, run in enumerate(runs, 1):
        ...
        tracker.update(k, violations=violated)
    tracker.finish()

Examples
--------
>>> seen = []
>>> clock = iter([0.0, 0.5, 2.0]).__next__
>>> tracker = Tracker("simulate", total=10.0, unit="s", report=seen.append, interval=1.0, clock=clock)
>>> tracker.update(2.5, jumps=3)   # 0.5 s after the start: too early, not reported
>>> tracker.update(5.0, jumps=7)   # 2.0 s after the start: reported
>>> seen[-1].fraction, seen[-1].rate, seen[-1].eta, seen[-1].counters
(0.5, 2.5, 2.0, (('jumps', 7),))
>>> print(seen[-1].text())
simulate: 5/10 s (50%), 7 jumps, 2.5 s per second, 2 s left
"""

from __future__ import annotations

import math
import sys
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import Any, TextIO

__all__ = [
    "Bar",
    "Progress",
    "Reporter",
    "Status",
    "TerminalLine",
    "Tracker",
    "in_notebook",
    "reporter",
    "terminal_reporter",
]


@dataclass(frozen=True)
class Status:
    """A task's progress at one moment.

    ``done`` and ``total`` count ``unit`` from ``start`` (a simulation counts
    simulated seconds from ``t_start``); ``elapsed`` is wall time in seconds;
    ``counters`` are extra named counts, in the order given; ``final`` marks the
    last report of the task.
    """

    task: str
    done: float
    total: float | None = None
    unit: str = ""
    elapsed: float = 0.0
    counters: tuple[tuple[str, float], ...] = ()
    start: float = 0.0
    final: bool = False

    @property
    def fraction(self) -> float | None:
        """Share of the work done, in ``[0, 1]`` (None without a total)."""
        if self.total is None or not self.total > self.start:
            return None
        return min(1.0, max(0.0, (self.done - self.start) / (self.total - self.start)))

    @property
    def rate(self) -> float | None:
        """Units done per wall second, on average since the start (None before any time)."""
        if not self.elapsed > 0.0:
            return None
        return (self.done - self.start) / self.elapsed

    @property
    def eta(self) -> float | None:
        """Estimated wall seconds left (None without a total or a rate)."""
        rate = self.rate
        if self.total is None or rate is None or not rate > 0.0:
            return None
        return max(0.0, (self.total - self.done) / rate)

    def text(self) -> str:
        """One line for a person: ``task: done/total unit (pct), counters, rate, time left``."""
        unit = f" {self.unit}" if self.unit else ""
        parts = [f"{self.task}: {_number(self.done)}"]
        if self.total is not None:
            parts[0] += f"/{_number(self.total)}{unit}"
            fraction = self.fraction
            if fraction is not None:
                parts[0] += f" ({fraction:.0%})"
        else:
            parts[0] += unit
        parts.extend(f"{_number(value)} {name}" for name, value in self.counters)
        rate = self.rate
        if rate is not None:
            parts.append(f"{_number(rate)}{unit} per second")
        eta = self.eta
        if eta is not None and not self.final:
            parts.append(f"{_duration(eta)} left")
        if self.final:
            parts.append(f"done in {_duration(self.elapsed)}")
        return ", ".join(parts)


Reporter = Callable[[Status], object]
"""Anything that receives statuses: :class:`TerminalLine`, a list's ``append``, a callback."""

Progress = Reporter | bool | None
"""What a campaign's ``progress=`` takes: a reporter, True or False (see :func:`reporter`)."""


class Tracker:
    """Turns frequent ``update`` calls into at most one report per ``interval`` seconds."""

    def __init__(
        self,
        task: str,
        *,
        total: float | None = None,
        unit: str = "",
        start: float = 0.0,
        report: Reporter | None = None,
        interval: float = 0.2,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.report = report
        self.interval = interval
        self.clock = clock
        self.started = clock()
        self.next_report = self.started + interval
        self.last = Status(task, start, total, unit, 0.0, (), start)
        if report is not None and getattr(report, "wants_start", False):
            report(self.last)  # a bar is drawn at once, at 0 of its total

    def update(self, done: float, **counters: float) -> None:
        """Record progress; report it if ``interval`` has passed since the last report."""
        now = self.clock()
        if now < self.next_report:
            return
        self.next_report = now + self.interval
        self.last = replace(
            self.last, done=done, elapsed=now - self.started, counters=tuple(counters.items())
        )
        if self.report is not None:
            self.report(self.last)

    def finish(
        self, done: float | None = None, *, total: float | None = None, **counters: float
    ) -> Status:
        """Report the final status (always) and return it.

        ``total``: the work that was to be done after all, when it ended early by
        design (a falsification that found its counterexample); an interrupted
        task keeps its total, and its final ``done`` falls short of it.
        """
        now = self.clock()
        status = replace(
            self.last,
            done=self.last.done if done is None else done,
            total=self.last.total if total is None else total,
            elapsed=now - self.started,
            counters=tuple(counters.items()) if counters else self.last.counters,
            final=True,
        )
        self.last = status
        if self.report is not None:
            self.report(status)
        return status


class TerminalLine:
    """Draws each status over the previous one on one line of ``stream`` (stderr).

    It draws only when ``stream`` is a terminal (or ``enabled=True``); a final
    status is cleared away by default (``keep_final=True`` leaves it, with a
    newline), so the command's own output starts on a clean line.
    """

    def __init__(
        self,
        stream: TextIO | None = None,
        *,
        enabled: bool | None = None,
        keep_final: bool = False,
        width: int = 100,
    ) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.enabled = _is_terminal(self.stream) if enabled is None else enabled
        self.keep_final = keep_final
        self.width = width
        self.drawn = 0

    def __call__(self, status: Status) -> None:
        if not self.enabled:
            return
        text = status.text()[: self.width]
        pad = " " * max(0, self.drawn - len(text))
        if status.final and not self.keep_final:
            self.clear()
            return
        end = "\n" if status.final else ""
        self.stream.write(f"\r{text}{pad}{end}")
        self.stream.flush()
        self.drawn = 0 if status.final else len(text)

    def message(self, text: str) -> None:
        """Print a line of text, clearing the status line first (it is redrawn on the next report)."""
        self.clear()
        self.stream.write(text + "\n")
        self.stream.flush()

    def clear(self) -> None:
        """Erase the status line, if one is drawn."""
        if self.enabled and self.drawn:
            self.stream.write("\r" + " " * self.drawn + "\r")
            self.stream.flush()
        self.drawn = 0


class Bar:
    """Draws statuses as a tqdm progress bar: ``done`` of ``total`` ``unit``, counters after.

    The bar is made at the first status, which a :class:`Tracker` sends when it
    starts (``factory(total=, desc=, unit=, **options)``; tqdm's class from
    ``tqdm.auto`` by default), and closed at the final one, which sets its count
    to the work done.

    Examples
    --------
    >>> import io
    >>> from tqdm import tqdm
    >>> out = io.StringIO()
    >>> bar = Bar(tqdm, file=out, ascii=True)
    >>> bar(Status("sweep", 2, 4, "runs", 1.0))
    >>> bar(Status("sweep", 4, 4, "runs", 2.0, (("violations", 1),), final=True))
    >>> out.getvalue().rsplit("\\r", 1)[-1].split(" [")[0]
    'sweep: 100%|##########| 4/4'
    """

    wants_start = True
    """A :class:`Tracker` reports its start to a bar (drawn at 0 before any work)."""

    def __init__(self, factory: Callable[..., Any] | None = None, **options: Any) -> None:
        self.factory = factory
        self.options = options
        self.bar: Any = None

    def __call__(self, status: Status) -> None:
        if self.bar is None:
            factory = self.factory if self.factory is not None else _tqdm()
            if factory is None:
                return
            total = None if status.total is None else _count(status.total)
            self.bar = factory(
                total=total, desc=status.task, unit=status.unit or "it", **self.options
            )
        if status.total is not None and self.bar.total != _count(status.total):
            self.bar.total = _count(status.total)
        self.bar.set_postfix(dict(status.counters), refresh=False)
        self.bar.update(_count(status.done) - self.bar.n)
        if status.final:
            self.bar.close()
            self.bar = None


def reporter(progress: Progress) -> Reporter | None:
    """The reporter a campaign's ``progress=`` asks for.

    ``None`` (the default): a :class:`Bar` when this is a Jupyter kernel
    (:func:`in_notebook`) and tqdm is installed, else nothing; ``True``: a bar
    wherever tqdm is installed, else the :class:`TerminalLine` on stderr when it
    is a terminal; ``False``: nothing; a callable: itself.

    Examples
    --------
    >>> reporter(False) is None, reporter(print) is print
    (True, True)
    """
    if progress is None:
        return Bar() if in_notebook() and _tqdm() is not None else None
    if progress is True:
        return Bar() if _tqdm() is not None else terminal_reporter()
    if progress is False:
        return None
    return progress


def in_notebook() -> bool:
    """Whether this runs in a Jupyter kernel (IPython's, as tqdm.auto tells it).

    IPython is not imported here: a kernel has imported it already.
    """
    ipython = sys.modules.get("IPython")
    get_ipython = getattr(ipython, "get_ipython", None)
    shell = get_ipython() if callable(get_ipython) else None
    return shell is not None and "IPKernelApp" in getattr(shell, "config", {})


def _tqdm() -> Callable[..., Any] | None:
    """tqdm's bar class from ``tqdm.auto``, or None without tqdm."""
    try:
        with warnings.catch_warnings():  # without ipywidgets tqdm.auto says so: a text bar
            warnings.simplefilter("ignore")
            from tqdm.auto import tqdm
    except ImportError:
        return None
    return tqdm  # type: ignore[no-any-return]


def _count(value: float) -> float:
    """A whole number as an int (tqdm prints ``4/4``, not ``4.0/4.0``)."""
    return int(value) if float(value).is_integer() else value


def terminal_reporter(quiet: bool = False, stream: TextIO | None = None) -> TerminalLine | None:
    """A :class:`TerminalLine` on ``stream`` (stderr) if it is a terminal and not ``quiet``."""
    if quiet:
        return None
    line = TerminalLine(stream)
    return line if line.enabled else None


def _is_terminal(stream: TextIO) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


def _number(value: float) -> str:
    """``5``, ``2.5``, ``0.0123``, ``1,234``, ``3.2e+15``: what a person reads at a glance."""
    if not math.isfinite(value):
        return str(value)
    if abs(value) >= 1e15:
        return f"{value:.3g}"
    if value == int(value) or abs(value) >= 100:
        return f"{value:,.0f}"
    return f"{value:.3g}"


def _duration(seconds: float) -> str:
    if seconds < 60:
        return f"{seconds:.0f} s" if seconds >= 10 else f"{seconds:.2g} s"
    minutes, secs = divmod(round(seconds), 60)
    if minutes < 60:
        return f"{minutes} min {secs:02d} s"
    hours, minutes = divmod(minutes, 60)
    return f"{hours} h {minutes:02d} min"
