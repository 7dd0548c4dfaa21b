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

from hybrid.expr.generated import define

__all__ = ["STALL_CALLS", "Interrupt", "sigint_watch", "watch_factory"]

STALL_CALLS = 50
"""Calls at one step-end time after which the solver counts as stalled."""


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
    earliest, as a hand-written loop with one event would. A term that cannot be
    evaluated (NaN) is left out; the failure is recorded where it happened.

    solve_ivp calls the event at each step end, always at a later time than
    before, and then, to locate a crossing, at times between the last two step
    ends on the step's interpolant. Two rules keep that root finding sound:

    - **Disarmed terms** (a guard or invariant on its boundary at entry) are left
      out until they have been strictly on their safe side *at a step end*; so the
      function root finding sees is the one whose sign change was detected.
    - **The bracket is exact**: the values returned at the last two step ends are
      remembered and returned again when root finding asks for those very times,
      even where the interpolant does not reproduce the step-end state to the last
      bit (LSODA's does not), so brentq never sees two ends of the same sign.

    - **A stalled solver is stopped**: more than :data:`STALL_CALLS` calls at the
      same step-end time mean the solver no longer advances (LSODA can loop on
      ever smaller steps near a finite-time blow-up, where RK45 gives up); the
      watch then sets ``_stalled`` and returns exactly 0, which ends the
      integration there (brentq accepts a zero-length bracket whose value is 0).

    Ctrl-C is read from a flag; once set, the interrupt watch takes over. The
    source comes from this template and the arming pattern only (no user text);
    factories are cached per mode and pattern by the caller.
    """
    lines = [
        "def make(_fns, _flag, _interrupt, _armed, _stalled):",
        *(f"    _f{i} = _fns[{i}]" for i in range(len(signs))),
        "    _m = [None, 0.0, -1.0e308, 0.0, 0]  # last two step ends (t, value); repeats",
        "    def watch(t, x):",
        "        if _flag[0]:",
        "            return _interrupt(t, x)",
        "        if t == _m[2]:",
        "            _m[4] += 1",
        f"            if _m[4] > {STALL_CALLS}:",
        "                _stalled[0] = True",
        "                return 0.0",
        "            return _m[3]",
        "        if t == _m[0]:",
        "            return _m[1]",
        "        step_end = t > _m[2]",
        "        v = 1.0e308",
    ]
    for i, (sign, is_armed) in enumerate(zip(signs, armed, strict=True)):
        term = f"{'-' if sign < 0 else ''}_f{i}(t, x)"
        lines.append(f"        w = {term}")
        if not is_armed:
            lines += [
                f"        if not _armed[{i}]:",
                "            if step_end and w > 0.0:",
                f"                _armed[{i}] = True",
                "            else:",
                "                w = 1.0e308",
            ]
        lines += ["        if w < v:", "            v = w"]
    lines += [
        "        if v >= 1.0e308:",
        "            v = 1.0",
        "        if step_end:",
        "            _m[0] = _m[2]",
        "            _m[1] = _m[3]",
        "            _m[2] = t",
        "            _m[3] = v",
        "            _m[4] = 0",
        "        return v",
        "    watch.terminal = True",
        "    watch.direction = -1.0",
        "    return watch",
    ]
    return define("make", "\n".join(lines) + "\n", {})


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
