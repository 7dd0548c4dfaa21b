"""One stay in a mode: step the solver, search each step for the first event, record.

The stay owns its solver (one of scipy's ``OdeSolver`` classes, stepped one
accepted step at a time, as :func:`scipy.integrate.solve_ivp` does inside) so
that every step can be searched for the first crossing of the watch
(:mod:`~hybrid.simulation.crossing`) before it is accepted into the trajectory.
For ``RK45`` and ``RK23`` the run's one stepped solver is restarted at each stay,
as scipy would construct it there (:mod:`~hybrid.simulation.stepper`).
A stay ends at the first event, at ``t_end``, at a Ctrl-C (after the step in
progress has been searched, so the last point is on a valid trajectory), or
when the flow cannot go on:

- the flow fails (an evaluation error, or a non-finite derivative) **at the
  start of the stay**: ``nonfinite`` at once, for every method (a solver would
  otherwise spend minutes shrinking a step, or raise out of its linear algebra);
- the solver gives up, raises, or produces a non-finite state: ``nonfinite`` if
  the flow failed on the way there (at a point the solver tried), else
  ``solver_failure``, at the last accepted point;
- the solver stops advancing (:data:`STALL_STEPS` steps that do not move ``t``):
  ``solver_failure``;
- the solver crawls: over :data:`CRAWL_STEPS` steps its steps averaged less
  than :data:`CRAWL_DROP` times the longest step of the stay, and at that pace
  ``t_end`` is more than :data:`CRAWL_PROJECTION` steps away. A solution that
  nears a singularity (a derivative without bound) and chatters across it does
  this: steps a million times shorter than before, and a run of hours.
  ``solver_failure``.

A flow failure at a trial point of a step the solver then rejected is not an
end: the solver stepped around it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.integrate import BDF, DOP853, LSODA, RK23, RK45, OdeSolver, Radau

from hybrid.simulation.compiled import CompiledMode, CompiledModel
from hybrid.simulation.crossing import HORIZON_SAMPLES, Failed, band, first_event
from hybrid.simulation.dense import step_curve
from hybrid.simulation.events import Watch
from hybrid.simulation.failures import describe_failure
from hybrid.simulation.interrupts import Interrupts
from hybrid.simulation.recorder import Recorder
from hybrid.simulation.settings import Settings
from hybrid.simulation.stepper import stepped

__all__ = [
    "CRAWL_DROP",
    "CRAWL_PROJECTION",
    "CRAWL_STEPS",
    "SOLVERS",
    "STALL_STEPS",
    "StayEnd",
    "StayIntegrator",
    "one_line",
]

SOLVERS: dict[str, type[OdeSolver]] = {
    "RK45": RK45,
    "RK23": RK23,
    "DOP853": DOP853,
    "Radau": Radau,
    "BDF": BDF,
    "LSODA": LSODA,
}
"""The scipy solver class of each method name."""

STALL_STEPS = 50
"""Consecutive accepted steps that do not advance ``t`` before a stay ends as stalled."""

CRAWL_STEPS = 1000
"""Steps over which the pace of the solver is measured (see the module docstring)."""

CRAWL_DROP = 1e-6
"""A pace below this fraction of the longest step of the stay is a crawl..."""

CRAWL_PROJECTION = 1e6
"""... when ``t_end`` is more than this many steps away at that pace."""

_SOLVER_ERRORS = (ValueError, ArithmeticError, np.linalg.LinAlgError)


@dataclass(frozen=True)
class StayEnd:
    """How a stay ended: ``cause`` is ``event``, ``t_end``, ``interrupted``, ``eval_failure``,
    ``nonfinite`` or ``solver_failure``, at ``(t, x)`` (the last good point)."""

    cause: str
    t: float
    x: np.ndarray
    message: str = ""
    kind: str = ""
    """For ``event``: how the search found it, ``crossing`` or ``touch`` (crossing.Found.kind)."""


class StayIntegrator:
    """Integrates the stays of one run (settings, recorder, Ctrl-C and progress are the run's)."""

    restarts = True
    """Whether a stay restarts the run's stepped solver rather than constructing one (the
    same solver to the bit: :meth:`~hybrid.simulation.stepper.SteppedRK45.restart`; off
    only to compare the two)."""

    def __init__(
        self,
        compiled: CompiledModel,
        settings: Settings,
        recorder: Recorder,
        interrupts: Interrupts,
        tick: Callable[[float], None] | None = None,
    ) -> None:
        self.compiled = compiled
        self.settings = settings
        self.recorder = recorder
        self.interrupts = interrupts
        self.tick = tick
        self.solver_class = SOLVERS[settings.method]
        self.stepped_class = stepped(self.solver_class)
        self.spacing = (settings.t_end - settings.t_start) / HORIZON_SAMPLES
        self.last_step: float | None = None
        self.stepped_solver: Any = None
        """The run's stepped solver, restarted at each stay (scipy's would be constructed)."""

    def stay(self, mode: CompiledMode, t0: float, x0: np.ndarray, j: int, watch: Watch) -> StayEnd:
        """Integrate from ``(t0, x0)`` in ``mode`` (whose point is already stored) to the stay's end."""
        record = self.recorder.stay(mode, j, t0)
        ended = self._start(mode, t0, x0)
        if isinstance(ended, StayEnd):
            record.close(None, None)
            return ended
        solver = ended
        flow_failure = self.compiled.flow_failure
        interrupts, tick, spacing = self.interrupts, self.tick, self.spacing
        failure = self.compiled.failure
        w = watch.value(t0, x0) if watch.value is not None else math.inf
        t, x = t0, x0
        stalls = steps = 0
        longest, window_start = 0.0, t0
        t_end = self.settings.t_end

        def arm(ts: float, xs: np.ndarray) -> bool:
            return watch.arm(ts, xs, band(xs))

        while True:
            try:
                message = solver.step()
            except _SOLVER_ERRORS as exc:
                record.close(None, None)
                return self._gave_up(mode, t, x, f"solver stopped: {exc}")
            if solver.status == "failed":
                record.close(None, None)
                return self._gave_up(mode, t, x, f"solver stopped: {one_line(message)}")
            t1 = float(solver.t)
            if not all(map(math.isfinite, solver.y.tolist())):
                record.close(None, None)
                return self._gave_up(mode, t, x, "the state became non-finite", nonfinite=True)
            stalls = stalls + 1 if t1 - t <= 4e-16 * max(1.0, abs(t1)) else 0
            if stalls > STALL_STEPS:
                record.close(None, None)
                peak = max(map(abs, x.tolist()), default=0.0)
                return StayEnd(
                    "solver_failure",
                    t,
                    x,
                    "solver stopped advancing: its step size fell below the spacing of "
                    f"floating-point numbers at t={t:.9g} "
                    f"({solver_advice(t, self.settings, peak)})",
                )
            h = t1 - t
            longest = max(longest, h)
            steps += 1
            if steps % CRAWL_STEPS == 0:
                pace = (t1 - window_start) / CRAWL_STEPS
                window_start = t1
                if pace < CRAWL_DROP * longest and t_end - t1 > CRAWL_PROJECTION * pace:
                    record.close(None, None)
                    return self._crawled(t, x, pace, longest)
            curve = step_curve(solver, x)
            event, w = first_event(
                curve, watch, w, spacing, arm if watch.pending else None, failure
            )
            if isinstance(event, Failed):
                record.step(curve, event.t)
                record.close(event.t, event.x)
                return StayEnd("eval_failure", event.t, event.x)
            if event is not None:
                record.step(curve, event.t)
                record.close(event.t, event.x)
                return StayEnd("event", event.t, event.x, kind=event.kind)
            flow_failure.clear()  # only at trial points the solver rejected: it stepped around them
            finished = solver.status == "finished"
            if finished or interrupts.requested:
                record.step(curve, t1)
                record.close(t1, curve.x1)
                return StayEnd("t_end" if finished else "interrupted", t1, curve.x1)
            record.step(curve, None)
            self.last_step = t1 - t
            t, x = t1, curve.x1
            if tick is not None:
                tick(t)

    def _start(self, mode: CompiledMode, t0: float, x0: np.ndarray) -> StayEnd | OdeSolver:
        """The solver of a stay, or how the stay ends before its first step."""
        flow_failure = self.compiled.flow_failure
        flow_failure.clear()
        derivative = mode.rhs(t0, x0)
        if flow_failure.error is not None:
            message = describe_failure(self.compiled, flow_failure, mode.key)
            return StayEnd("nonfinite", t0, x0, f"{message} (at t={t0:.9g})")
        if not all(map(math.isfinite, derivative)):
            names = self.compiled.state_names
            bad = next(n for n, d in zip(names, derivative, strict=True) if not math.isfinite(d))
            value = derivative[names.index(bad)]
            return StayEnd(
                "nonfinite",
                t0,
                x0,
                f"the flow of {mode.name} gives {bad}' = {value} (at t={t0:.9g})",
            )
        settings = self.settings
        fun = mode.rhs if mode.flow is None else mode.flow
        keeps = mode.flow is not None
        # RK45 and RK23 stepped: the same steps, bit for bit, without scipy's per-step wrapping
        stepped = self.stepped_class if x0.dtype == np.float64 else None
        last = self.stepped_solver
        try:
            if stepped is not None and last is not None and last.n == x0.size:
                # the solver scipy would construct here, without constructing it (stepper)
                last.restart(fun, t0, x0, self._first_step(t0), keeps)
                return last
            solver: OdeSolver = (stepped or self.solver_class)(
                fun,
                t0,
                x0,
                settings.t_end,
                rtol=settings.rtol,
                atol=settings.atol,
                max_step=settings.max_step,
                first_step=self._first_step(t0),
                **({"keeps": keeps} if stepped is not None else {}),
            )
        except _SOLVER_ERRORS as exc:
            return self._gave_up(mode, t0, x0, f"solver could not start: {exc}")
        if stepped is not None and self.restarts:
            self.stepped_solver = solver
        return solver

    def _first_step(self, t0: float) -> float | None:
        """Start a stay with the last full step of the previous one (None: let scipy choose).

        Warm-starting saves the solver's initial-step estimate (two evaluations of
        the right-hand side) at every jump; its error control still accepts or
        shrinks the step as the tolerances require.
        """
        h, t_end = self.last_step, self.settings.t_end
        if h is None or not h > 0.0 or not t_end > t0:
            return None
        return min(h, self.settings.max_step, t_end - t0)

    def _crawled(self, t: float, x: np.ndarray, pace: float, longest: float) -> StayEnd:
        """The end of a stay whose solver crawls (see the module docstring)."""
        peak = max(map(abs, x.tolist()), default=0.0)
        remaining = (self.settings.t_end - t) / pace
        return StayEnd(
            "solver_failure",
            t,
            x,
            f"solver crawls: its last {CRAWL_STEPS} steps averaged {pace:.3g} (it took steps of "
            f"{longest:.3g} before), so t_end is still {remaining:.2g} steps away (largest "
            f"|state| {peak:.3g}); the solution may near a singularity here (a derivative "
            "without bound) and chatter across it",
        )

    def _gave_up(
        self, mode: CompiledMode, t: float, x: np.ndarray, why: str, nonfinite: bool = False
    ) -> StayEnd:
        """The end of a stay whose solver cannot go on, at the last accepted point ``(t, x)``."""
        flow_failure = self.compiled.flow_failure
        if flow_failure.error is not None:
            where = flow_failure.t if flow_failure.t is not None else t
            return StayEnd(
                "nonfinite",
                t,
                x,
                f"{describe_failure(self.compiled, flow_failure, mode.key)} (at t={where:.9g}); "
                f"the solution leaves the domain of the flow after t={t:.9g}",
            )
        peak = max(map(abs, x.tolist()), default=0.0)
        return StayEnd(
            "nonfinite" if nonfinite else "solver_failure",
            t,
            x,
            f"{why} ({solver_advice(t, self.settings, peak)})",
        )


def solver_advice(t: float, settings: Settings, peak: float) -> str:
    """What to say after a solver gave up at ``t`` with ``peak`` the largest ``|state|``.

    Far from 0, time itself is coarse: a run whose clock starts at 1e17 cannot take
    a step shorter than 10 spacings of the doubles there (16 apart), whatever the flow.

    >>> solver_advice(5.0, Settings(t_end=10.0), 3.0)
    'largest |state| 3; the solution may blow up here, or try another method (--method, method=) or tighter tolerances'
    >>> solver_advice(1e17, Settings(t_start=1e17, t_end=1e17 + 1e4), 20.0)  # doctest: +ELLIPSIS
    'largest |state| 20; at t=1e+17 consecutive floating-point times are 16 apart, ...'
    """
    spacing = math.ulp(t)
    if spacing > 1024 * math.ulp(settings.t_end - settings.t_start):
        return (
            f"largest |state| {peak:.3g}; at t={t:.9g} consecutive floating-point times are "
            f"{spacing:.3g} apart, so no step shorter than {10 * spacing:.3g} can be taken: "
            "count time from nearer 0 (a smaller t_start)"
        )
    return (
        f"largest |state| {peak:.3g}; the solution may blow up here, or try another method "
        "(--method, method=) or tighter tolerances"
    )


def one_line(message: Any) -> str:
    """A solver's message in one line."""
    return " ".join(str(message or "the solver failed").split())
