"""The settings of one simulation run, validated once, frozen: ``hybrid.Settings``.

:class:`Settings` is the one options object of the simulator: built once, it can
be given to :func:`hybrid.simulate`, :func:`hybrid.simulate_many`,
:func:`hybrid.sweep`, :func:`hybrid.falsify` and (its ``t_end``)
:func:`hybrid.reach`, and each of them takes the same options as keywords too,
which override the object's (:func:`merged`). Every setting is checked up front, so that a run never starts with a value
that would make it hang or fail later: times and tolerances must be finite
numbers in range, and ``max_step`` and ``dt`` must leave a number of steps or
points a computer can take (see :data:`MAX_STEPS` and :data:`MAX_GRID_POINTS`).

Examples
--------
>>> s = Settings(t_end=10.0)
>>> s.method, s.rtol, s.max_step
('RK45', 1e-06, inf)
>>> Settings(t_end=-1.0)
Traceback (most recent call last):
...
hybrid.errors.UsageError: t_end must be a finite time after t_start=0.0, got -1.0
>>> Settings(t_end=10.0, rtol=float("inf"))
Traceback (most recent call last):
...
hybrid.errors.UsageError: rtol must be a finite number, got inf
"""

from __future__ import annotations

import math
import numbers
import threading
from dataclasses import asdict, dataclass, fields, replace
from typing import Any

from hybrid.errors import UsageError

__all__ = [
    "BACKENDS",
    "CHOICES",
    "DEFAULTS",
    "MATLAB_SOLVERS",
    "MAX_GRID_POINTS",
    "MAX_JUMPS_PER_INSTANT",
    "MAX_STEPS",
    "METHODS",
    "MIN_RTOL",
    "OPTIONS",
    "Settings",
    "finite_number",
    "merged",
    "merged_values",
    "method_hint",
]

METHODS = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")
"""The integration methods of :func:`scipy.integrate.solve_ivp` a run may use."""

MATLAB_SOLVERS = {
    "ode45": ("RK45", "the same Dormand-Prince 5(4) pair"),
    "ode23": ("RK23", "the same Bogacki-Shampine 3(2) pair"),
    "ode78": ("DOP853", "the nearest: an explicit Runge-Kutta pair of order 8"),
    "ode89": ("DOP853", "the nearest: an explicit Runge-Kutta pair of order 8"),
    "ode113": ("LSODA", "the nearest: variable-order Adams, switching to BDF when stiff"),
    "ode15s": ("BDF", "the nearest: variable-order BDF for stiff flows"),
    "ode23s": ("Radau", "the nearest: an implicit one-step method for stiff flows"),
    "ode23t": ("Radau", "the nearest: an implicit one-step method for stiff flows"),
    "ode23tb": ("Radau", "the nearest: an implicit one-step method for stiff flows"),
}
"""MATLAB's solvers and the method to give instead, with why (the message of a MATLAB name)."""


def method_hint(name: str) -> str:
    """What to write for a method that is not one of :data:`METHODS`: MATLAB's solvers named.

    >>> method_hint("ode45")
    "MATLAB's ode45 is 'RK45' here (the same Dormand-Prince 5(4) pair)"
    >>> method_hint("Euler")
    ''
    """
    found = MATLAB_SOLVERS.get(name.lower())
    if found is None:
        return ""
    return f"MATLAB's {name} is '{found[0]}' here ({found[1]})"

BACKENDS = ("scipy", "compiled")
"""``scipy``: the solve_ivp engine (the reference); ``compiled``: hybrid.simulation.native."""

CHOICES = (*BACKENDS, "auto")
"""What ``backend`` may say: a backend, or ``auto`` (the one that pays; docs/backends.md)."""

MAX_JUMPS_PER_INSTANT = 1000
"""Jumps allowed at one instant before a run ends as ``zeno`` (a zero-time cycle)."""

MIN_RTOL = 100 * 2.220446049250313e-16
"""Smallest relative tolerance: scipy's solvers raise smaller ones to it with a warning."""

MAX_STEPS = 1e12
"""Most steps a ``max_step`` may force over the run (months of solver work)."""

MAX_GRID_POINTS = 1e8
"""Most points a ``dt`` grid may give (each is a row of the trajectory in memory)."""


def finite_number(name: str, value: Any) -> float:
    """``value`` as a float, or a :class:`UsageError` naming ``name`` if it is not a finite number.

    Examples
    --------
    >>> finite_number("g", 9.81)
    9.81
    >>> finite_number("g", float("nan"))
    Traceback (most recent call last):
    ...
    hybrid.errors.UsageError: g must be a finite number, got nan
    """
    if not _plain_number(value) and (isinstance(value, bool) or not isinstance(value, numbers.Real)):
        raise UsageError(f"{name} must be a number, got {_shown(value)}")
    try:
        number = float(value)
    except OverflowError:  # an int beyond any float (10**400)
        raise UsageError(f"{name} must be a finite number, got {value:.3e}") from None
    if not math.isfinite(number):
        raise UsageError(f"{name} must be a finite number, got {number}")
    return number


def _finite(value: Any) -> bool:
    """``math.isfinite`` that reads an int beyond any float (10**400) as not finite."""
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def _shown(value: Any) -> str:
    """``value`` as a message shows it; a string is named as one (``t_end="10"``)."""
    if isinstance(value, str):
        return f"the string {value!r}: pass a number, not text"
    if value.__class__ is int and abs(value) >= 10**18:
        return f"an integer of {len(str(abs(value)))} digits"
    return str(value) if _plain_number(value) else repr(value)


def _plain_number(value: Any) -> bool:
    """Whether ``value`` is a float or an int (not a bool): a real number, found without ABCs.

    The checks of :class:`numbers.Real` cost more than the rest of a short
    compiled run's settings; almost every value is one of these two.
    """
    return value.__class__ is float or value.__class__ is int


def _whole(name: str, value: Any, least: int) -> int:
    if value.__class__ is not int and (
        isinstance(value, bool) or not isinstance(value, numbers.Integral)
    ):
        raise UsageError(f"{name} must be a whole number, got {value!r}")
    whole = int(value)
    if whole < least:
        raise UsageError(f"{name} must be >= {least}, got {whole}")
    if whole > MAX_WHOLE:
        raise UsageError(f"{name} must be at most {MAX_WHOLE} (2**62), got {whole}")
    return whole


MAX_WHOLE = 2**62
"""The largest count a setting takes (the compiled loop keeps counts in 64-bit integers)."""


def _flag(name: str, value: Any) -> None:
    if not (value is True or value is False or (_plain_number(value) and value in (0, 1))):
        raise UsageError(f"{name} must be True or False, got {value!r}")


@dataclass(frozen=True)
class Settings:
    """How to integrate and when to stop: the options of a run, checked once, frozen.

    The same object serves :func:`hybrid.simulate`, :func:`hybrid.simulate_many`,
    :func:`hybrid.sweep`, :func:`hybrid.falsify` and :func:`hybrid.reach` (which
    reads its ``t_end`` only); each of them also takes these fields as keywords,
    and a keyword given overrides the field (``hybrid.simulate(model,
    settings=s, rtol=1e-9)``). A value out of range is a
    :class:`~hybrid.errors.UsageError` naming the field, raised when the object
    is made. ``dataclasses.replace(s, dt=None)`` makes a copy with fields
    changed (checked again).

    Parameters
    ----------
    t_end : float
        End time; a run ends there with cause ``t_end`` unless it ends before.
    t_start : float
        Start time (default 0).
    max_jumps : int
        A run stops with cause ``max_jumps`` after this many jumps (default 10 000).
    rtol, atol : float
        Tolerances of the solver (default 1e-6 and 1e-9); ``rtol`` at least
        :data:`MIN_RTOL` and below 1, ``atol`` > 0.
    max_step : float
        Largest solver step (default ``inf``: not limited). Lower it so that a
        guard true only briefly is not stepped over.
    method : str
        One of :data:`METHODS` (default ``"RK45"``; the compiled backend has only that one).
    dt : float, optional
        Store points on a uniform grid of this spacing (jump points always
        stored); default: at the solver's steps.
    dense : bool
        Keep each segment's interpolant in ``run.segments`` (smooth plots).
    zeno : bool
        Detect geometric accumulation of jumps (cause ``zeno``; default on).
    max_jumps_per_instant : int
        Jumps allowed at one instant before a run ends as ``zeno`` (default 1000).
    backend : str, optional
        ``"scipy"`` (the reference engine), ``"compiled"``
        (:mod:`hybrid.simulation.native`) or ``"auto"`` (compiled where it pays for its
        compile: docs/backends.md). Not given (``None``): the entry point's default,
        ``"scipy"`` for :func:`hybrid.simulate`, ``"auto"`` for :func:`hybrid.sweep`
        and :func:`hybrid.falsify`.

    Examples
    --------
    >>> import hybrid
    >>> ball = hybrid.load("specs/bouncing_ball.yaml")
    >>> fine = hybrid.Settings(t_end=3.0, rtol=1e-10, atol=1e-12)
    >>> run = hybrid.simulate(ball, settings=fine)
    >>> round(run.jumps[0].t, 9), run.settings["rtol"]
    (1.427843123, 1e-10)
    >>> hybrid.simulate(ball, settings=fine, t_end=1.0).termination.t  # keywords override
    1.0
    >>> hybrid.Settings(t_end=3.0, atol=0.0)
    Traceback (most recent call last):
    ...
    hybrid.errors.UsageError: atol must be > 0, got 0.0
    """

    t_end: float
    t_start: float = 0.0
    max_jumps: int = 10_000
    rtol: float = 1e-6
    atol: float = 1e-9
    max_step: float = math.inf
    method: str = "RK45"
    dt: float | None = None
    dense: bool = False
    zeno: bool = True
    max_jumps_per_instant: int = MAX_JUMPS_PER_INSTANT
    backend: str | None = None

    def __post_init__(self) -> None:
        t0 = finite_number("t_start", self.t_start)
        if (
            (
                not _plain_number(self.t_end)
                and (isinstance(self.t_end, bool) or not isinstance(self.t_end, numbers.Real))
            )
            or not _finite(self.t_end)
            or self.t_end <= t0
        ):
            raise UsageError(
                f"t_end must be a finite time after t_start={t0}, got {_shown(self.t_end)}"
                + _time_hint(self.t_end)
            )
        span = float(self.t_end) - t0
        _whole("max_jumps", self.max_jumps, 0)
        _whole("max_jumps_per_instant", self.max_jumps_per_instant, 1)
        rtol = finite_number("rtol", self.rtol)
        if not MIN_RTOL <= rtol < 1.0:
            raise UsageError(
                f"rtol must be at least {MIN_RTOL:.3g} (100 machine epsilons) and below 1, "
                f"got {rtol}"
            )
        if not finite_number("atol", self.atol) > 0:
            raise UsageError(f"atol must be > 0, got {self.atol}")
        step = self.max_step
        if step is None:  # as run.settings and the events file write "not limited"
            step = math.inf
            object.__setattr__(self, "max_step", step)
        if (
            not _plain_number(step) and (isinstance(step, bool) or not isinstance(step, numbers.Real))
        ) or not step > 0:
            raise UsageError(f"max_step must be > 0, got {_shown(step)}")
        resolution = 4 * 2.220446049250313e-16 * max(1.0, abs(t0), abs(float(self.t_end)))
        if step < resolution:
            raise UsageError(
                f"max_step={step:g} is below the resolution of time near t_end={self.t_end:g} "
                f"({resolution:.3g}): a step that short cannot advance t"
            )
        if span / step > MAX_STEPS:
            raise UsageError(
                f"max_step={step:g} needs at least {span / step:.3g} steps from t={t0:g} to "
                f"t_end={self.t_end:g} (the limit is {MAX_STEPS:.0e}): raise it"
            )
        if self.dt is not None:
            dt = finite_number("dt", self.dt)
            if not dt > 0:
                raise UsageError(f"dt must be > 0, got {self.dt}")
            if span / dt > MAX_GRID_POINTS:
                raise UsageError(
                    f"dt={dt:g} gives {span / dt:.3g} points from t={t0:g} to "
                    f"t_end={self.t_end:g} (the limit is {MAX_GRID_POINTS:.0e}): raise it"
                )
        if self.method not in METHODS:
            hint = method_hint(str(self.method))
            raise UsageError(
                f"unknown method '{self.method}'"
                + (f": {hint}" if hint else f"; choose one of {', '.join(METHODS)}")
            )
        if self.backend is not None and self.backend not in CHOICES:
            raise UsageError(f"unknown backend '{self.backend}'; choose one of {', '.join(CHOICES)}")
        for flag in ("dense", "zeno"):
            value = getattr(self, flag)
            if value.__class__.__module__ == "numpy" and value.__class__.__name__ in ("bool", "bool_"):
                object.__setattr__(self, flag, bool(value))  # numpy's True: a Python one
            _flag(flag, getattr(self, flag))

    def as_dict(self) -> dict[str, Any]:
        """The settings as the events JSON records them (``max_step`` null when not limited)."""
        record = asdict(self)
        if math.isinf(self.max_step):
            record["max_step"] = None
        return record


def _time_hint(value: Any) -> str:
    """What to write for a time given as MATLAB's ``tspan`` or as an array, else ``""``."""
    size = getattr(value, "size", None)
    if size == 1 and hasattr(value, "item"):
        return ": an array of one value; give its number (float(t) or t.item())"
    if isinstance(value, (list, tuple)) or (size is not None and size > 1):
        return ": for MATLAB's tspan [t0, tf], give t_start=t0, t_end=tf"
    return ""


OPTIONS = tuple(f.name for f in fields(Settings))
"""The fields of :class:`Settings`, in order: the options every entry point takes."""

DEFAULTS: dict[str, Any] = {f.name: f.default for f in fields(Settings) if f.name != "t_end"}
"""Each field's default (every field but ``t_end`` has one)."""


def merged(settings: Settings | None, t_end: Any = None, **options: Any) -> Settings:
    """The settings of one call: ``settings`` with the options given put in.

    An option given as ``None`` is not given (the keywords of the entry points
    default to ``None``); ``t_end`` given overrides the settings' one. Without
    ``settings`` the options are those of a new :class:`Settings`, so a missing
    or bad ``t_end`` is the message of :class:`Settings`.

    Examples
    --------
    >>> s = Settings(t_end=10.0, rtol=1e-9)
    >>> merged(s, rtol=None) is s, merged(s, 5.0, atol=1e-12).t_end
    (True, 5.0)
    >>> merged(None, 2.0, method="BDF").method
    'BDF'
    >>> merged({"t_end": 1.0})
    Traceback (most recent call last):
    ...
    hybrid.errors.UsageError: settings must be a hybrid.Settings, got {'t_end': 1.0}
    """
    given = {k: v for k, v in options.items() if v is not None}
    if settings is None:
        return Settings(t_end=t_end, **given)
    if not isinstance(settings, Settings):
        raise UsageError(f"settings must be a hybrid.Settings, got {settings!r}")
    if t_end is not None:
        given["t_end"] = t_end
    return replace(settings, **given) if given else settings


_MEMO: dict[tuple[int, ...], tuple[tuple[Any, ...], Settings]] = {}
_MEMO_SIZE = 64
_MEMO_LOCK = threading.Lock()
_IMMUTABLE = (float, int, bool, str, type(None))
"""The classes of the values a remembered call may hold: immutable, compared by identity."""


def merged_values(
    settings: Settings | None, t_end: Any, names: tuple[str, ...], values: tuple[Any, ...]
) -> Settings:
    """``merged(settings, t_end, **dict(zip(names, values)))``, remembered by the objects given.

    A loop of runs passes the same objects every time (constants, a held
    ``Settings``): the answer for the same objects (each the very object of an
    earlier call: ``is``, not ``==``) is that call's :class:`Settings` again (it
    is frozen), found without building or checking one. Keyed by identity,
    ``0.0`` and ``-0.0``, ``1``, ``1.0`` and ``True`` never stand for each
    other; only floats, ints, bools, strings and ``None`` (immutable) and a
    ``Settings`` or ``None`` as ``settings`` are remembered, and the memo holds
    each object it keys by (no other object can take its id).

    Examples
    --------
    >>> rtol, names = 1e-9, ("rtol", "dt")
    >>> a = merged_values(None, 10.0, names, (rtol, None))
    >>> merged_values(None, 10.0, names, (rtol, None)).rtol, a.t_end
    (1e-09, 10.0)
    >>> merged_values(None, 10.0, names, (-0.0, None))
    Traceback (most recent call last):
    ...
    hybrid.errors.UsageError: rtol must be at least 2.22e-14 (100 machine epsilons) and below 1, got -0.0
    """
    objects = (settings, t_end, names, *values)
    key = tuple(map(id, objects))
    hit = _MEMO.get(key)  # one lookup needs no lock; the updates below hold it
    if hit is not None:
        return hit[1]
    found = merged(settings, t_end, **dict(zip(names, values, strict=True)))
    if (settings is None or settings.__class__ is Settings) and all(
        v.__class__ in _IMMUTABLE for v in (t_end, *values)
    ) and names.__class__ is tuple and all(n.__class__ is str for n in names):
        with _MEMO_LOCK:
            if len(_MEMO) >= _MEMO_SIZE:
                _MEMO.pop(next(iter(_MEMO)))
            _MEMO[key] = (objects, found)  # holds the objects: their ids stay theirs
    return found
