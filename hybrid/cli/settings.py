"""The run settings of a command, built from its flags in one place.

``simulate``, ``sweep`` and ``falsify`` share the flags of the simulator's
options (``--t-end``, ``--max-jumps``, ``--rtol``, ``--atol``, ``--max-step``,
``--method``, ``--dt``, ``--backend``): :func:`add_settings_flags` declares
them once for every such command, and :func:`settings_from` turns them into the
one :class:`~hybrid.simulation.settings.Settings` the command passes on, so
that a flag means what the keyword of the same name means in Python (and is
checked by the same code, with the same messages). ``--backend`` is declared by
each command (``auto`` is chosen per command).

Examples
--------
>>> import argparse
>>> args = argparse.Namespace(t_end=2.0, max_jumps=10_000, rtol=1e-9, atol=1e-9,
...                           max_step=None, method="RK45", dt=None, backend="auto")
>>> s = settings_from(args)
>>> s.t_end, s.rtol, s.max_step, s.backend is None  # auto: the command's to resolve
(2.0, 1e-09, inf, True)
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Iterable
from typing import TypeVar

from hybrid.errors import UsageError
from hybrid.simulation.settings import BACKENDS, DEFAULTS, METHODS, Settings, merged

V = TypeVar("V")

__all__ = ["add_settings_flags", "given_once", "settings_from"]


def add_settings_flags(
    p: argparse.ArgumentParser,
    positive: Callable[[str], float],
    count: Callable[[str], int],
    *,
    each_run: bool = False,
) -> None:
    """Declare ``--t-end`` and the solver's flags on ``p``, with the defaults of :class:`Settings`.

    ``each_run``: the command runs many (a campaign), and the help says so.
    """
    runs = " of each run" if each_run else ""
    p.add_argument("--t-end", type=positive, required=True, help=f"end time{runs}")
    p.add_argument("--max-jumps", type=count, default=DEFAULTS["max_jumps"],
                   help=f"stop{' each run' if each_run else ''} after this many jumps")  # fmt: skip
    p.add_argument("--rtol", type=positive, default=DEFAULTS["rtol"],
                   help="relative tolerance of the solver")  # fmt: skip
    p.add_argument("--atol", type=positive, default=DEFAULTS["atol"],
                   help="absolute tolerance of the solver")  # fmt: skip
    p.add_argument("--max-step", type=positive, default=None,
                   help="largest solver step; lower it to catch narrow guard windows")  # fmt: skip
    p.add_argument("--method", default=DEFAULTS["method"], choices=METHODS, help="solve_ivp method")
    p.add_argument("--dt", type=positive, default=None, help="store points on a uniform grid")


def settings_from(args: argparse.Namespace) -> Settings:
    """The settings the flags of ``args`` give; a flag left out keeps the default.

    ``--backend auto`` is not a setting (each command resolves it: one run, or a
    campaign's choice); it leaves the default backend here.
    """
    backend = getattr(args, "backend", None)
    return merged(
        None,
        args.t_end,
        max_jumps=args.max_jumps,
        rtol=args.rtol,
        atol=args.atol,
        max_step=args.max_step,
        method=args.method,
        dt=args.dt,
        backend=backend if backend in BACKENDS else None,
    )


def given_once(pairs: Iterable[tuple[str, V]], flag: str) -> dict[str, V]:
    """The ``NAME=VALUE`` pairs of a repeated flag as a mapping; a name given twice is refused.

    Without the check the last value won silently (``--param e=0.5 --param e=0.7``).

    Examples
    --------
    >>> given_once([("e", 0.5), ("g", 9.81)], "--param")
    {'e': 0.5, 'g': 9.81}
    >>> given_once([("e", 0.5), ("e", 0.7)], "--param")
    Traceback (most recent call last):
    ...
    hybrid.errors.UsageError: --param e is given twice (0.5 and 0.7): give it once
    """
    found: dict[str, V] = {}
    for name, value in pairs:
        if name in found:
            raise UsageError(f"{flag} {name} is given twice ({found[name]} and {value}): give it once")
        found[name] = value
    return found
