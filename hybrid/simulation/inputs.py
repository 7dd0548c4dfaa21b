"""External inputs from text: an expression of ``t``, or a time series read from a CSV file.

An automaton's free ``inputs`` are functions of ``t`` (``hybrid.simulate(...,
inputs={"u": f})``). Here they are built from what a command line can carry:

- :class:`ExpressionInput`: an expression of ``t`` in the spec language
  (``sin(2*t)``, ``0.5 * (1 + sign(t - 3))``), parsed and compiled like any spec
  expression, never evaluated as Python;
- :func:`read_series`: a CSV file with a header ``t,NAME,...``; each column
  other than ``t`` is a :class:`TimeSeries` of the input of that name, linear
  between the samples. A series must cover the whole run
  (:meth:`TimeSeries.check_covers`).

And from numbers: :class:`PiecewiseConstant`, an input held at each value
from its start on (the inputs of reach's witnesses and of the falsifier).

Errors a user can make are a :class:`~hybrid.errors.UsageError` (a bad
``NAME=EXPR``) or a :class:`~hybrid.errors.SpecError` at ``file:line:column``
(a bad CSV file).

Examples
--------
>>> u = ExpressionInput("u", "sin(pi * t / 2)")
>>> round(u(1.0), 12)
1.0
>>> ramp = TimeSeries("u", [0.0, 2.0], [0.0, 1.0], "ramp.csv")
>>> ramp(0.5)
0.25
>>> held = PiecewiseConstant(np.array([0.0, 1.0]), np.array([2.0, 3.0]))
>>> held(0.5), held(1.0), held(7.0)
(2.0, 3.0, 3.0)
>>> ExpressionInput("u", "sin(2*x)")
Traceback (most recent call last):
...
hybrid.errors.UsageError: input u = sin(2*x): column 7: unknown name 'x'; an input is an expression of t
"""

from __future__ import annotations

import bisect
import csv
import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from hybrid.errors import Position, SpecError, UsageError
from hybrid.expr.codegen import CodeContext, EvalFailure, compile_function
from hybrid.expr.parse import ExprError, Scope, parse_expression

__all__ = [
    "ExpressionInput",
    "PiecewiseConstant",
    "TimeSeries",
    "parse_assignment",
    "read_series",
]

MAX_SERIES_BYTES = 512 * 1024 * 1024
"""Largest CSV file of input series read."""


def parse_assignment(text: str) -> tuple[str, str]:
    """``NAME=EXPR`` as ``(name, expression)``; a :class:`UsageError` if malformed.

    Examples
    --------
    >>> parse_assignment("u = sin(t)")
    ('u', 'sin(t)')
    """
    name, sep, expression = text.partition("=")
    name, expression = name.strip(), expression.strip()
    if not sep or not name.isidentifier() or not expression:
        raise UsageError(f"expected NAME=EXPR (an expression of t), got '{text}'")
    return name, expression


class ExpressionInput:
    """An input given as an expression of ``t``; calling it gives its value at ``t``.

    A value that cannot be computed (``log(t)`` at ``t = 0``) raises
    ``ValueError`` naming the input, which the simulator reports as a failure of
    the expression that read the input.
    """

    def __init__(self, name: str, source: str) -> None:
        self.name = name
        self.source = source
        try:
            expr = parse_expression(source, Scope(variables={}))
        except ExprError as exc:
            message = exc.message
            if message.startswith("unknown name"):
                message += "; an input is an expression of t"
            raise UsageError(f"input {name} = {source}: column {exc.col + 1}: {message}") from None
        self.failure = EvalFailure()
        self._fn = compile_function(
            f"input_{name}", [expr], CodeContext(states=(), failure=self.failure), shape="scalar"
        )

    def __call__(self, t: float) -> float:
        value = float(self._fn(t, None))
        error = self.failure.error
        if error is not None:
            self.failure.clear()
            raise ValueError(f"input {self.name} = {self.source} failed at t={t:.9g}: {error}")
        return value

    def __repr__(self) -> str:
        return f"ExpressionInput({self.name!r}, {self.source!r})"


class TimeSeries:
    """An input sampled at times ``times`` (strictly increasing), linear in between."""

    def __init__(
        self, name: str, times: Sequence[float], values: Sequence[float], file: str = "<series>"
    ) -> None:
        """Check the samples as :func:`read_series` checks a file's (a :class:`UsageError`).

        Examples
        --------
        >>> TimeSeries("u", times=[0.0, 2.0, 1.0], values=[0, 1, 2])
        Traceback (most recent call last):
        ...
        hybrid.errors.UsageError: TimeSeries 'u': times must increase: t=1 after t=2 (sample 3)
        """
        self.name = name
        self.times = _samples(name, "times", times)
        self.values = _samples(name, "values", values)
        self.file = file
        if len(self.times) != len(self.values):
            raise UsageError(
                f"TimeSeries '{name}': {len(self.times)} times but {len(self.values)} values"
            )
        if len(self.times) < 2:
            raise UsageError(f"TimeSeries '{name}': at least two samples are needed")
        for k in range(1, len(self.times)):
            if not self.times[k] > self.times[k - 1]:
                raise UsageError(
                    f"TimeSeries '{name}': times must increase: t={self.times[k]:g} after "
                    f"t={self.times[k - 1]:g} (sample {k + 1})"
                )

    def __call__(self, t: float) -> float:
        times, values = self.times, self.values
        k = bisect.bisect_right(times, t)
        if k <= 0:
            return values[0]
        if k >= len(times):
            return values[-1]
        t0, t1 = times[k - 1], times[k]
        v0, v1 = values[k - 1], values[k]
        return v0 + (v1 - v0) * (t - t0) / (t1 - t0)

    def check_covers(self, t_start: float, t_end: float) -> None:
        """A :class:`UsageError` unless the samples span ``[t_start, t_end]``."""
        first, last = self.times[0], self.times[-1]
        if first > t_start or last < t_end:
            raise UsageError(
                f"input {self.name} from {self.file} covers t in [{first:g}, {last:g}] but the "
                f"run goes from t={t_start:g} to t={t_end:g}: add samples or shorten the run"
            )

    def __repr__(self) -> str:
        return f"TimeSeries({self.name!r}, {len(self.times)} samples from {self.file})"


def _samples(name: str, what: str, given: Sequence[float]) -> list[float]:
    """``given`` as finite floats, or a :class:`UsageError` naming the sample."""
    try:
        items = list(given)
    except TypeError:
        raise UsageError(f"TimeSeries '{name}': {what} must be a sequence of numbers") from None
    found = []
    for k, item in enumerate(items, start=1):
        try:
            value = float(item)
        except (TypeError, ValueError):
            raise UsageError(
                f"TimeSeries '{name}': {what} sample {k} is not a number: {item!r}"
            ) from None
        if not math.isfinite(value):
            raise UsageError(f"TimeSeries '{name}': {what} sample {k} is not finite: {value}")
        found.append(value)
    return found


@dataclass(frozen=True)
class PiecewiseConstant:
    """An input held at ``values[i]`` from ``starts[i]`` (a callable of ``t`` that pickles)."""

    starts: NDArray[np.float64]
    values: NDArray[np.float64]
    _starts: list[float] = dataclasses.field(init=False, repr=False, compare=False)
    _values: list[float] = dataclasses.field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # as Python floats: read at every evaluation of the flow, where numpy's
        # searchsorted on a scalar cost ten times a bisection of a list
        object.__setattr__(self, "_starts", [float(s) for s in self.starts])
        object.__setattr__(self, "_values", [float(v) for v in self.values])

    def __call__(self, t: float) -> float:
        return self._values[max(bisect.bisect_right(self._starts, t) - 1, 0)]


def read_series(path: str | Path) -> dict[str, TimeSeries]:
    """The input series of a CSV file: a header ``t,NAME,...`` and one row per sample time."""
    file = str(path)
    target = Path(path)
    try:
        size = target.stat().st_size
        if size > MAX_SERIES_BYTES:
            raise SpecError(
                f"file is {size} bytes, over the limit of {MAX_SERIES_BYTES}", Position(file)
            )
        text = target.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise UsageError(f"cannot read input series '{file}': {exc.strerror or exc}") from None
    except UnicodeDecodeError:
        raise SpecError("not a text file (UTF-8 expected)", Position(file)) from None
    lines = text.splitlines()
    rows = list(csv.reader(lines))
    if not rows or not any(cell.strip() for cell in rows[0]):
        raise SpecError("empty file: expected a header t,NAME,...", Position(file))
    header = [cell.strip() for cell in rows[0]]
    if header[0] != "t":
        raise SpecError(f"the first column must be 't', got '{header[0]}'", Position(file, 1, 1))
    if len(header) < 2:
        raise SpecError("no input columns after 't'", Position(file, 1, 1))
    for k, name in enumerate(header[1:], start=1):
        if not name.isidentifier():
            raise SpecError(
                f"'{name}' is not an input name", Position(file, 1, _column(lines[0], k))
            )
        if name in header[1:k]:
            raise SpecError(
                f"column '{name}' appears twice", Position(file, 1, _column(lines[0], k))
            )
    columns: list[list[float]] = [[] for _ in header]
    for line_no, row in enumerate(rows[1:], start=2):
        if not any(cell.strip() for cell in row):
            continue
        if len(row) != len(header):
            raise SpecError(
                f"{len(row)} values, but the header has {len(header)} columns",
                Position(file, line_no, 1),
            )
        for k, cell in enumerate(row):
            where = Position(file, line_no, _column(lines[line_no - 1], k))
            try:
                value = float(cell)
            except ValueError:
                raise SpecError(f"not a number: '{cell.strip()}'", where) from None
            if not math.isfinite(value):
                raise SpecError(f"not a finite number: '{cell.strip()}'", where)
            if k == 0 and columns[0] and not value > columns[0][-1]:
                raise SpecError(
                    f"times must increase: t={value:g} after t={columns[0][-1]:g}", where
                )
            columns[k].append(value)
    if len(columns[0]) < 2:
        raise SpecError("at least two sample rows are needed", Position(file, 1, 1))
    return {
        name: TimeSeries(name, columns[0], columns[k], file)
        for k, name in enumerate(header)
        if k > 0
    }


def _column(line: str, index: int) -> int:
    """1-based column where field ``index`` of a CSV ``line`` starts (plain, unquoted fields)."""
    column = 1
    for k, field in enumerate(line.split(",")):
        if k == index:
            return column + len(field) - len(field.lstrip())
        column += len(field) + 1
    return column
