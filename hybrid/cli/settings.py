"""The run settings of a command, built from its flags in one place.

``simulate``, ``sweep`` and ``falsify`` share the flags of the simulator's
options (``--t-end``, ``--max-jumps``, ``--rtol``, ``--atol``, ``--max-step``,
``--method``, ``--dt``, ``--backend``); :func:`settings_from` turns them into
the one :class:`~hybrid.simulation.settings.Settings` the command passes on, so
that a flag means what the keyword of the same name means in Python (and is
checked by the same code, with the same messages).

Examples
--------
>>> import argparse
>>> args = argparse.Namespace(t_end=2.0, max_jumps=10_000, rtol=1e-9, atol=1e-9,
...                           max_step=None, method="RK45", dt=None, backend="auto")
>>> s = settings_from(args)
>>> s.t_end, s.rtol, s.max_step, s.backend
(2.0, 1e-09, inf, 'scipy')
"""

from __future__ import annotations

import argparse

from hybrid.simulation.settings import BACKENDS, Settings, merged

__all__ = ["settings_from"]


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
