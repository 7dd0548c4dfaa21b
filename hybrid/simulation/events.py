"""The event machinery of a stay in a mode: the watch, Ctrl-C, and its handler.

solve_ivp gets one terminal event per stay, the *watch* built by
:func:`watch_factory`; Ctrl-C reaches it through the flag that
:func:`sigint_watch` sets and :class:`Interrupt` turns into a sign change.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

__all__ = ["Interrupt", "sigint_watch", "watch_factory"]


@contextmanager
def sigint_watch(enabled: bool) -> Iterator[list[bool]]:
    """Turn the first Ctrl-C into a flag the loop sees at its next step."""
    flag = [False]
    if not enabled or threading.current_thread() is not threading.main_thread():
        yield flag
        return
    previous = signal.getsignal(signal.SIGINT)

    def handler(signum: int, frame: Any) -> None:
        if flag[0]:
            raise KeyboardInterrupt
        flag[0] = True

    signal.signal(signal.SIGINT, handler)
    try:
        yield flag
    finally:
        signal.signal(signal.SIGINT, previous)


def watch_factory(signs: tuple[float, ...], armed: tuple[bool, ...]) -> Callable[..., Any]:
    """Source-built factory of the one terminal event of a stay in a mode.

    The event's value is the smallest of: each guard's rho (the guard starts to
    hold when it falls to 0) and each invariant's -rho (the invariant stops
    holding when it falls to 0); so solve_ivp locates one root per crossing, the
    earliest, as a hand-written loop with one event would. A guard or invariant
    on its boundary at entry is disarmed: it is left out until it has been
    strictly on its safe side once (arming changes only at step ends, where time
    moves forward, so root finding inside a step sees one function). Ctrl-C is
    read from a flag; only once set does the interrupt watch take over.

    The source comes from this template and the arming pattern only (no user
    text); factories are cached per mode and pattern by the caller.
    """
    lines = [
        "def make(_fns, _flag, _interrupt, _armed):",
        *(f"    _f{i} = _fns[{i}]" for i in range(len(signs))),
        "    def watch(t, x):",
        "        if _flag[0]:",
        "            return _interrupt(t, x)",
        "        v = 1.0e308",
    ]
    for i, (sign, is_armed) in enumerate(zip(signs, armed, strict=True)):
        term = f"{'-' if sign < 0 else ''}_f{i}(t, x)"
        lines.append(f"        w = {term}")
        if not is_armed:
            lines += [
                f"        if not _armed[{i}]:",
                "            if w > 0.0:",
                f"                _armed[{i}] = True",
                "            else:",
                "                w = 1.0e308",
            ]
        lines += ["        if w < v:", "            v = w"]
    lines += [
        "        return v if v < 1.0e308 else 1.0",
        "    watch.terminal = True",
        "    watch.direction = -1.0",
        "    return watch",
    ]
    scope: dict[str, Any] = {"__builtins__": {}}
    exec(compile("\n".join(lines) + "\n", "<hybrid:watch>", "exec"), scope)
    factory: Callable[..., Any] = scope["make"]
    return factory


class Interrupt:
    """A terminal event that turns Ctrl-C into a step function of ``t``.

    The flag is noticed at the end of a step, at time ``at``; from then on the
    event reads +1 before ``at`` and -1 from it, so solve_ivp's root finding
    between the step's ends sees a sign change (a bare flag would read -1 at
    both ends and make ``brentq`` fail). At the start of a segment it reads +1.
    """

    terminal = True
    direction = 0.0

    def __init__(self, flag: list[bool], t0: float) -> None:
        self.flag = flag
        self.t0 = t0
        self.at: float | None = None

    def __call__(self, t: float, x: Any) -> float:
        if self.at is None:
            if not self.flag[0] or t <= self.t0:
                return 1.0
            self.at = t
        return 1.0 if t < self.at else -1.0
