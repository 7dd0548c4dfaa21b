"""What a campaign varies, and the points it runs: grids, seeded samples, and their names.

A varied name is one of

- a parameter: ``name`` (``comp.name`` in a system, or ``name`` where only one
  component has it);
- an initial value: ``init.x`` for state variable ``x``;
- a free input held constant over the run: ``input.u`` (an automaton's ``inputs``).

A **grid** is the product of its axes, each ``LO:HI:N`` (``N`` values from ``LO``
to ``HI``, ends included), the first axis slowest. **Samples** are ``N`` points
of the box of ranges ``LO:HI``, drawn from a seed: a Latin hypercube (default),
a scrambled Sobol sequence or plain uniform draws (``scipy.stats.qmc`` and
``numpy.random.Generator``), so the same seed gives the same points anywhere.
Grid and samples combine: every grid point with every sample.

:func:`declared_ranges` is where a spec's own declared sets come in (interval
initial sets ``x: {initial: [lo, hi]}`` and bounded inputs ``u: {range: [lo,
hi]}``): samples are drawn from them when no range is given (``--sample N``
alone), or for the names given without one (``--vary init.x``,
``vary={"init.x": None}``), and a grid spans them with a count alone
(``--grid init.x=5``, ``grid={"init.x": 5}``); :func:`declared_axis` makes the
axis of one name.

Examples
--------
>>> grid = [Axis.parse("e=0.5:0.9:3"), Axis.parse("init.h=1:2:2")]
>>> [tuple(round(v, 9) for v in p.values()) for p in grid_points(grid)]
[(0.5, 1.0), (0.5, 2.0), (0.7, 1.0), (0.7, 2.0), (0.9, 1.0), (0.9, 2.0)]
>>> points = sample_points([Axis.parse("e=0:1", grid=False)], 4, seed=1)
>>> sorted(int(p["e"] * 4) for p in points)   # a Latin hypercube: one point per quarter
[0, 1, 2, 3]
>>> points == sample_points([Axis.parse("e=0:1", grid=False)], 4, seed=1)
True
"""

from __future__ import annotations

import itertools
import math
import numbers
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from hybrid.campaigns.samplers import SAMPLERS
from hybrid.campaigns.targets import INITIAL, INPUT, check_names
from hybrid.compose import Model, System
from hybrid.errors import UsageError

__all__ = [
    "SAMPLERS",
    "Axis",
    "Point",
    "checked_seed",
    "combine",
    "declared_axis",
    "declared_ranges",
    "grid_axes",
    "grid_points",
    "parse_grid",
    "parse_range",
    "ranges_axes",
    "sample_points",
]

Point = dict[str, float]
"""Values of the varied names for one run, in the order of the axes."""

MAX_POINTS = 10_000_000
"""A campaign larger than this is refused before anything runs."""


@dataclass(frozen=True)
class Axis:
    """A varied name and its values: a grid of ``count`` values, or a range to sample."""

    name: str
    low: float
    high: float
    count: int | None = None
    given: tuple[float, ...] | None = None
    """Explicit grid values, in their order (instead of ``count`` evenly spaced)."""

    @classmethod
    def parse(cls, text: str, *, grid: bool = True) -> Axis:
        """``NAME=LO:HI:N`` (``grid``) or ``NAME=LO:HI`` (a range), with one clear error."""
        name, sep, rest = text.partition("=")
        name = name.strip()
        shape = "NAME=LO:HI:N" if grid else "NAME=LO:HI"
        parts = rest.split(":")
        if not sep or not name or len(parts) != (3 if grid else 2):
            raise UsageError(f"expected {shape}, got '{text}'")
        try:
            low, high = float(parts[0]), float(parts[1])
        except ValueError:
            raise UsageError(f"'{text}': LO and HI must be numbers") from None
        count = None
        if grid:
            try:
                count = int(parts[2])
            except ValueError:
                raise UsageError(f"'{text}': N must be a whole number{_colon_hint(name, parts)}") from None
            if low > high or (count == 1 and low != high):  # MATLAB's 1:0.1:2, 0:0.1:1
                said = "the range is empty (LO > HI)" if low > high else "N = 1 takes LO alone"
                raise UsageError(f"'{text}': {said}{_colon_hint(name, parts)}")
        return cls.of(name, low, high, count)

    @classmethod
    def listed(cls, name: str, values: Sequence[float]) -> Axis:
        """A grid axis of explicit values (finite numbers), in the order given."""
        if isinstance(values, str | bytes) or not isinstance(values, Iterable):
            raise UsageError(
                f"{name}: a grid gives a list of values or a count, got {values!r}"
            )
        try:
            seq = tuple(float(v) for v in values)
        except (TypeError, ValueError):
            raise UsageError(f"{name}: grid values must be numbers, got {list(values)!r}") from None
        if not seq:
            raise UsageError(f"{name}: the grid has no values")
        if not all(map(math.isfinite, seq)):
            raise UsageError(f"{name}: grid values must be finite numbers, got {list(seq)}")
        return cls(name, min(seq), max(seq), len(seq), seq)

    @classmethod
    def of(cls, name: str, low: float, high: float, count: int | None = None) -> Axis:
        """An axis with its bounds checked (finite, ``low <= high``, ``count >= 1``)."""
        if not (math.isfinite(low) and math.isfinite(high)):
            raise UsageError(f"{name}: the range must be finite, got [{low}, {high}]")
        if low > high:
            raise UsageError(f"{name}: the range [{low}, {high}] is empty (LO > HI)")
        if count is not None and count < 1:
            raise UsageError(f"{name}: N must be >= 1, got {count}")
        if count == 1 and low != high:  # a grid of one value across a range: which one?
            raise UsageError(
                f"{name}: one grid value across [{low:g}, {high:g}] would be LO alone: give "
                "N >= 2 for values from LO to HI, or list the one value"
            )
        return cls(name, float(low), float(high), count)

    def values(self) -> list[float]:
        """The grid values (``count`` of them, ends included; one value: ``low``)."""
        if self.given is not None:
            return list(self.given)
        n = self.count or 1
        if n == 1:
            return [self.low]
        return [float(v) for v in np.linspace(self.low, self.high, n)]


def grid_points(axes: Sequence[Axis]) -> list[Point]:
    """Every combination of the axes' values, the first axis slowest."""
    if not axes:
        return [{}]
    size = math.prod(a.count or 1 for a in axes)
    if size > MAX_POINTS:
        raise UsageError(f"the grid has {size} points, over the limit of {MAX_POINTS}")
    names = [a.name for a in axes]
    return [
        dict(zip(names, combo, strict=True))
        for combo in itertools.product(*(a.values() for a in axes))
    ]


def checked_seed(seed: object) -> int:
    """``seed`` if it is a whole number >= 0 (what numpy's generators take), else a UsageError.

    Examples
    --------
    >>> checked_seed(7)
    7
    """
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise UsageError(f"the seed must be a whole number >= 0, got {seed!r}")
    return int(seed)


def sample_points(axes: Sequence[Axis], n: int, seed: int, sampler: str = "lhs") -> list[Point]:
    """``n`` points of the box of ``axes``' ranges, drawn from ``seed`` (the same anywhere)."""
    if sampler not in SAMPLERS:
        raise UsageError(f"unknown sampler '{sampler}' (choose from {', '.join(SAMPLERS)})")
    if isinstance(n, bool) or not isinstance(n, numbers.Integral):
        raise UsageError(f"the number of samples must be a whole number, got {n!r}")
    if n < 1 or n > MAX_POINTS:
        raise UsageError(f"the number of samples must be from 1 to {MAX_POINTS}, got {n}")
    if not axes:
        raise UsageError(
            "samples need ranges to draw from: give --vary NAME=LO:HI (the spec declares no "
            "initial set or input range)"
        )
    unit = unit_samples(len(axes), n, seed, sampler)
    low = np.array([a.low for a in axes])
    span = np.array([a.high - a.low for a in axes])
    scaled = low + unit * span
    names = [a.name for a in axes]
    return [dict(zip(names, map(float, row), strict=True)) for row in scaled]


def unit_samples(d: int, n: int, seed: int, sampler: str = "lhs") -> np.ndarray:
    """``n`` points of the unit cube ``[0, 1)^d``, one row each, from ``seed``."""
    from scipy.stats import qmc

    rng = np.random.default_rng(checked_seed(seed))
    if sampler == "lhs":
        return np.asarray(qmc.LatinHypercube(d=d, seed=rng).random(n))
    if sampler == "sobol":
        engine = qmc.Sobol(d=d, scramble=True, seed=rng)
        return np.asarray(engine.random_base2(max(0, math.ceil(math.log2(n)))))[:n]
    return rng.random((n, d))


def combine(grid: Sequence[Point], samples: Sequence[Point] | None) -> list[Point]:
    """Every grid point with every sample (the grid alone without samples)."""
    if samples is None:
        return [dict(p) for p in grid]
    size = len(grid) * len(samples)
    if size > MAX_POINTS:
        raise UsageError(
            f"the grid's {len(grid)} points times {len(samples)} samples are {size} runs, "
            f"over the limit of {MAX_POINTS}"
        )
    return [{**g, **s} for g in grid for s in samples]


def declared_ranges(model: Model) -> dict[str, tuple[float, float]]:
    """The ranges a spec declares itself, by varied name: ``init.x`` and ``input.u``.

    Every state variable with an interval initial set (``x: {initial: [lo, hi]}``
    or ``initial: {state: {x: [lo, hi]}}``) and every free input with a range
    (``u: {range: [lo, hi]}``), in state order then input order; one-point sets
    are left out (there is nothing to vary). A sweep with samples and no ranges
    given samples within them; a falsification with no ranges given searches them.

    Examples
    --------
    >>> import hybrid
    >>> m = hybrid.load_text('''
    ... automaton: a
    ... state: {x: {initial: [0, 2]}, y: {initial: 1}}
    ... inputs: {u: {range: [-1, 1]}}
    ... locations: {l: {flow: {x: u, y: 0}}}
    ... ''')
    >>> declared_ranges(m)
    {'init.x': (0.0, 2.0), 'input.u': (-1.0, 1.0)}
    """
    found = {
        f"{INITIAL}{name}": (r.lo, r.hi)
        for name, r in model.initial_set().items()
        if not r.is_point
    }
    found.update(
        {
            f"{INPUT}{name}": (r.lo, r.hi)
            for name, r in model.input_ranges().items()
            if not r.is_point
        }
    )
    return found


def declared_axis(model: System, name: str, count: int | None = None) -> Axis:
    """The axis of ``name`` over the range the spec declares for it (a clear error if none).

    With ``count``, a grid axis of ``count`` values across that range, ends included.

    Examples
    --------
    >>> import hybrid
    >>> from hybrid.compose import as_system
    >>> ball = as_system(hybrid.load("specs/bouncing_ball.yaml"))
    >>> declared_axis(ball, "init.h")
    Traceback (most recent call last):
    ...
    hybrid.errors.UsageError: init.h: bouncing_ball declares one initial value of h (10), not a set: give a range, init.h=LO:HI
    """
    check_names(model, [name])
    shape = "LO:HI" if count is None else "LO:HI:N"
    if name.startswith(INITIAL):
        var = name[len(INITIAL) :]
        r = model.initial_set()[var]
        if r.is_point:
            raise UsageError(
                f"{name}: {model.name} declares one initial value of {var} ({r.lo:g}), not a "
                f"set: give a range, {name}={shape}"
            )
        return Axis.of(name, r.lo, r.hi, count)
    if name.startswith(INPUT):
        var = name[len(INPUT) :]
        found = model.input_ranges().get(var)
        if found is None or found.is_point:
            raise UsageError(
                f"{name}: {model.name} declares no range for input {var}: give one, {name}={shape}"
            )
        return Axis.of(name, found.lo, found.hi, count)
    raise UsageError(f"{name}: a parameter has no declared range: give one, {name}={shape}")


def grid_axes(
    model: System,
    given: Mapping[str, Sequence[float] | int] | Sequence[Axis | tuple[str, int]] | None,
) -> list[Axis]:
    """The axes of ``grid``: ``{name: values}``, Axis, or a count of values (``{name: N}``,
    ``(name, N)``) across the range the spec declares for an ``init.x`` or ``input.u``."""
    if not given:
        return []
    axes: list[Axis] = []
    if isinstance(given, Mapping):
        for name, values in given.items():
            if isinstance(values, int):  # a count (a bool is refused by _count)
                axes.append(declared_axis(model, str(name), _count(str(name), values)))
            else:
                axes.append(Axis.listed(str(name), values))
        return axes
    if isinstance(given, str | bytes) or not isinstance(given, Iterable):
        raise UsageError(f"grid must be a mapping {{name: values or N}} or a list, got {given!r}")
    for item in given:
        if isinstance(item, Axis):
            axes.append(item)
        else:
            if isinstance(item, str | bytes) or not isinstance(item, Sequence) or len(item) != 2:
                raise UsageError(f"a grid item is an Axis or (name, N), got {item!r}")
            name, count = item
            axes.append(declared_axis(model, str(name), _count(str(name), count)))
    return axes


def _count(name: str, count: int) -> int:
    if isinstance(count, bool) or not isinstance(count, int) or count < 1:
        raise UsageError(f"{name}: N must be a whole number >= 1, got {count!r}")
    return count


def _colon_hint(name: str, parts: Sequence[str]) -> str:
    """For ``LO:HI:N`` written as MATLAB's ``start:step:stop``, the grid it meant.

    Examples
    --------
    >>> _colon_hint("e", ["0.5", "0.1", "0.9"])
    " (LO:HI:N: N values from LO to HI; MATLAB's start:step:stop 0.5:0.1:0.9 is e=0.5:0.9:5)"
    >>> _colon_hint("e", ["0", "1", "x"])
    ' (LO:HI:N: N values from LO to HI)'
    """
    said = " (LO:HI:N: N values from LO to HI"
    try:
        start, step, stop = (float(p) for p in parts)
    except ValueError:
        return said + ")"
    if not (math.isfinite(start) and math.isfinite(stop) and step > 0 and stop >= start):
        return said + ")"
    count = math.floor((stop - start) / step * (1 + 1e-12)) + 1
    last = start + (count - 1) * step
    return (f"{said}; MATLAB's start:step:stop {':'.join(p.strip() for p in parts)} is "
            f"{name}={start:g}:{last:.12g}:{count})")  # fmt: skip


def parse_grid(text: str) -> Axis | tuple[str, int]:
    """``NAME=LO:HI:N`` (an Axis), ``NAME=N`` (``N`` values across the declared range), or
    ``NAME=V1,V2,...`` (those values, in that order; brackets around them are allowed).

    Examples
    --------
    >>> parse_grid("init.x=5"), parse_grid("e=0.5:0.9:3").count
    (('init.x', 5), 3)
    >>> parse_grid("e=0.9,0.5,0.7").given, parse_grid("e=[0.5, 0.7]").given
    ((0.9, 0.5, 0.7), (0.5, 0.7))
    """
    name, sep, rest = text.partition("=")
    listed = rest.strip()
    if listed.startswith("[") and listed.endswith("]"):
        listed = listed[1:-1]
    if not (sep and name.strip() and ":" not in rest):
        return Axis.parse(text, grid=True)
    if "," in listed:
        try:
            values = [float(v) for v in listed.split(",")]
        except ValueError:
            raise UsageError(f"'{text}': the listed values must be numbers") from None
        return Axis.listed(name.strip(), values)
    try:
        return name.strip(), int(rest)
    except ValueError:
        raise UsageError(f"expected NAME=LO:HI:N, NAME=N or NAME=V1,V2,..., got '{text}'") from None


def ranges_axes(
    model: System,
    given: Mapping[str, tuple[float, float] | None] | Sequence[Axis | str] | None,
) -> list[Axis]:
    """The axes of ``vary``: ``{name: (lo, hi)}``, Axis, or a name (or ``None`` range) for
    the declared range of an ``init.x`` or ``input.u``; nothing given: every declared range."""
    if not given:
        return [Axis.of(n, lo, hi) for n, (lo, hi) in declared_ranges(model).items()]
    items: list[Axis | str] = []
    if isinstance(given, Mapping):
        for name, bounds in given.items():
            if bounds is None:
                items.append(str(name))
            else:
                low, high = _pair(str(name), bounds)
                items.append(Axis.of(str(name), low, high))
    else:
        if isinstance(given, str | bytes) or not isinstance(given, Iterable):
            raise UsageError(f"vary must be a mapping {{name: (low, high)}} or a list, got {given!r}")
        items = list(given)
        for item in items:
            if not isinstance(item, Axis | str):
                raise UsageError(f"a range to vary is an Axis or a name, got {item!r}")
    return [declared_axis(model, item) if isinstance(item, str) else item for item in items]


def _pair(name: str, bounds: object) -> tuple[float, float]:
    """``(low, high)`` of a range given as two numbers, else a :class:`UsageError` naming it."""
    try:
        pair = np.asarray(bounds, dtype=float)  # a tuple, a list, an array
    except (TypeError, ValueError):
        pair = np.zeros(0)
    if isinstance(bounds, str | bytes) or pair.shape != (2,):
        raise UsageError(f"{name}: a range is two numbers (low, high), got {bounds!r}")
    return float(pair[0]), float(pair[1])


def parse_range(text: str) -> Axis | str:
    """``NAME=LO:HI`` (an Axis), or a bare ``NAME`` (the range its spec declares, resolved later).

    Examples
    --------
    >>> parse_range("init.x"), parse_range("k=0:1")
    ('init.x', Axis(name='k', low=0.0, high=1.0, count=None, given=None))
    """
    name = text.strip()
    if "=" not in name and name and ":" not in name:
        return name
    return Axis.parse(text, grid=False)
