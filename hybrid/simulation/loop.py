"""The event loop: stays in modes (:mod:`~hybrid.simulation.stay`), jumps in between.

Semantics (docs/semantics.md): as-soon-as-possible firing; among transitions
enabled at one instant the highest priority fires, ties by file order, and the
choice is logged; after a jump the transitions are tested at the new point and
one enabled there fires at once (same ``t``, next ``j``); a guard that sits on
its boundary and moves away is disarmed until it is strictly false, so it
never fires spuriously; leaving an invariant with nothing enabled ends the
run as ``blocked``. The decisions at a point are
:mod:`~hybrid.simulation.boundary`'s; where a stay ends is the search's
(:mod:`~hybrid.simulation.crossing`).

Evaluation errors (see :mod:`hybrid.simulation.compiled`) end the run as
``nonfinite`` when they happen at a point of the trajectory: a guard,
invariant, signal or reset, or the right-hand side where the simulator itself
evaluates it. A failure of the right-hand side at a trial point of the solver
ends the run only if the solver then gives up; otherwise the solver has
stepped around it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from hybrid.expr.codegen import EvalFailure
from hybrid.simulation import boundary
from hybrid.simulation.compiled import CompiledMode, CompiledModel, CompiledTransition
from hybrid.simulation.events import Watch
from hybrid.simulation.failures import describe_failure
from hybrid.simulation.interrupts import Interrupts
from hybrid.simulation.recorder import Recorder
from hybrid.simulation.result import Termination
from hybrid.simulation.same_instant import InstantMemo
from hybrid.simulation.settings import Settings
from hybrid.simulation.stay import StayIntegrator
from hybrid.simulation.zeno import ZenoDetector

__all__ = ["EventLoop"]

Flowed = tuple[
    float, np.ndarray, CompiledTransition | None, list[CompiledTransition], set[str]
]
Progress = Callable[[float, int, int], None]


class EventLoop:
    """Runs one simulation of a compiled model; the recorder keeps what it computes.

    ``progress(t, jumps, points)`` is called after every accepted step (the caller
    throttles it).
    """

    def __init__(
        self,
        compiled: CompiledModel,
        settings: Settings,
        interrupts: Interrupts,
        progress: Progress | None = None,
    ) -> None:
        self.compiled = compiled
        self.settings = settings
        self.interrupts = interrupts
        self.recorder = Recorder(compiled, settings)
        self.watch_factories: dict[tuple[tuple[float, bool], ...], Any] = {}
        self.progress = progress
        tick = None
        if progress is not None:
            recorder = self.recorder

            def tick(t: float) -> None:
                progress(t, len(recorder.jumps), recorder.count)

        self.integrator = StayIntegrator(compiled, settings, self.recorder, interrupts, tick)

    def run(self, t: float, x: np.ndarray) -> Termination:
        """Simulate from ``(t, x)`` in the initial mode until the run ends; how it ended."""
        compiled, settings = self.compiled, self.settings
        mode = compiled.mode(compiled.initial_key)
        j = 0
        if not _finite(x):
            return Termination("nonfinite", t, j, "initial state is not finite", location=mode.name)
        self.recorder.start(mode, t, x)
        zeno = ZenoDetector()
        same_instant, last_jump_t, stalls = 0, math.nan, 0
        # where the last stay stopped (levels reached at that instant), and the levels used
        # there: read by a guard disarmed in that stay or taken at that instant
        reached: np.ndarray | None = None
        t_reached, used = math.nan, set[str]()
        max_per_instant = settings.max_jumps_per_instant
        # a system built from parts carries the decisions of one instant from jump to jump
        decide = (
            boundary.enabled_at_entry
            if compiled.parts is None
            else InstantMemo(compiled).enabled_at_entry
        )

        while True:
            if self._failed() is not None:
                return self._eval_failure(t, j, mode)
            if self.interrupts.requested:
                return Termination(
                    "interrupted", t, j, "interrupted by the user", location=mode.name
                )
            chosen, enabled, armed = decide(mode, t, x, reached if t == t_reached else None, used)
            if self._failed() is not None:
                return self._eval_failure(t, j, mode)
            if chosen is None and mode.urgent:
                return Termination(
                    "blocked",
                    t,
                    j,
                    f"urgent location {', '.join(mode.urgent)}: no time may pass there and no "
                    "transition is enabled",
                    location=mode.name,
                )
            if chosen is None:
                blocked = self._blocked(mode, t, x, j, "does not hold")
                if blocked is not None:
                    return blocked
                if t >= settings.t_end:  # a jump landed exactly at t_end: nothing left to flow
                    return Termination("t_end", t, j, "reached t_end", location=mode.name)
                outcome = self._flow(mode, t, x, j, armed)
                if isinstance(outcome, Termination):
                    return outcome
                t_before = t
                t, x, chosen, enabled, used = outcome
                reached, t_reached = x, t
                if chosen is None:
                    stalls = stalls + 1 if t == t_before else 0
                    if stalls > max_per_instant:
                        return Termination(
                            "solver_failure",
                            t,
                            j,
                            "events keep firing at the same instant without any transition "
                            "becoming enabled (a guard touching its boundary?)",
                            location=mode.name,
                        )
                    continue
            if j >= settings.max_jumps:
                return Termination(
                    "max_jumps", t, j, f"reached max_jumps={settings.max_jumps}", location=mode.name
                )
            same_instant = same_instant + 1 if t == last_jump_t else 1
            last_jump_t = t
            if same_instant > max_per_instant:
                return Termination(
                    "zeno",
                    t,
                    j,
                    f"{max_per_instant} jumps at the same instant: a cycle of transitions "
                    f"takes no time (last: {chosen.name})",
                    zeno_time=t,
                    location=mode.name,
                )
            source = mode
            mode, x = self._jump(mode, chosen, enabled, t, x, j)
            used.update(chosen.level_keys)
            j += 1
            if self._failed() is not None:  # the reset, evaluated in the source mode
                return self._eval_failure(t, j, mode, source)
            if not _finite(x):
                return Termination(
                    "nonfinite",
                    t,
                    j,
                    f"reset of {chosen.name} gave a non-finite state",
                    location=mode.name,
                )
            estimate = zeno.update(t) if settings.zeno else None
            if estimate is not None and estimate <= settings.t_end:
                return Termination(
                    "zeno",
                    t,
                    j,
                    f"jumps accumulate (gaps shrink geometrically); estimated Zeno time {estimate:.12g}",
                    zeno_time=estimate,
                    location=mode.name,
                )

    # --- evaluation failures ------------------------------------------------------------

    def _failed(self) -> EvalFailure | None:
        """The evaluation failure at a point of the trajectory, if any."""
        for failure in (self.compiled.failure, self.compiled.flow_failure):
            if failure.error is not None:
                return failure
        return None

    def _eval_failure(
        self, t: float, j: int, mode: CompiledMode, failed_in: CompiledMode | None = None
    ) -> Termination:
        """The end of a run after an evaluation failure in ``failed_in`` (default ``mode``)."""
        failure = self._failed()
        assert failure is not None
        where = float(failure.t) if failure.t is not None else t
        what = describe_failure(self.compiled, failure, (failed_in or mode).key)
        return Termination(
            "nonfinite", where, j, f"{what} (at t={where:.9g})", location=mode.name
        )

    def _blocked(
        self, mode: CompiledMode, t: float, x: np.ndarray, j: int, how: str
    ) -> Termination | None:
        """End as ``blocked`` if an invariant is being left here (no transition is enabled)."""
        left = boundary.invariant_left_at(mode, t, x)
        if left is None:
            return None
        message = f"invariant of {left} {how} and no transition is enabled"
        return Termination("blocked", t, j, message, location=mode.name)

    # --- flowing ------------------------------------------------------------------------

    def _flow(
        self, mode: CompiledMode, t0: float, x0: np.ndarray, j: int, armed: list[bool]
    ) -> Termination | Flowed:
        """Integrate one stay until its first event or end; what happened at its end."""
        watch = Watch(mode, armed, t0, x0, boundary.band(x0), self.watch_factories)
        if self.compiled.failure.error is not None:
            return self._eval_failure(t0, j, mode)
        end = self.integrator.stay(mode, t0, x0, j, watch)
        t, x = end.t, end.x
        if end.cause == "eval_failure" or self.compiled.failure.error is not None:
            return self._eval_failure(t, j, mode)
        if end.cause == "t_end":
            return Termination("t_end", t, j, "reached t_end", location=mode.name)
        if end.cause == "interrupted":
            return Termination("interrupted", t, j, "interrupted by the user", location=mode.name)
        if end.cause != "event":
            return Termination(end.cause, t, j, end.message, location=mode.name)
        enabled = boundary.enabled_at_event(mode, t, x, watch.armed)
        if self._failed() is not None:
            return self._eval_failure(t, j, mode)
        chosen = boundary.choose(enabled)
        if chosen is None and end.kind == "crossing":  # a disarmed guard a band beyond holds
            enabled = watch.far_edge_guards(t, x)
            if self._failed() is not None:
                return self._eval_failure(t, j, mode)
            chosen = boundary.choose(enabled)
        if chosen is None and t >= self.settings.t_end:  # at t_end: nothing left to flow
            return Termination("t_end", t, j, "reached t_end", location=mode.name)
        if chosen is None:
            far = watch.far_edge_left(t, x) if end.kind == "crossing" else None
            if far is not None:  # a disarmed invariant reached the far edge of its band: left
                message = f"invariant of {far} is about to be left and no transition is enabled"
                return Termination("blocked", t, j, message, location=mode.name)
            blocked = self._blocked(mode, t, x, j, "is about to be left")
            if blocked is not None:
                return blocked
        disarmed = {
            key for i, tr in enumerate(mode.transitions) if not watch.armed(i)
            for key in tr.level_keys
        }
        return t, x, chosen, enabled, disarmed

    # --- jumping ------------------------------------------------------------------------

    def _jump(
        self,
        mode: CompiledMode,
        chosen: CompiledTransition,
        enabled: list[CompiledTransition],
        t: float,
        x: np.ndarray,
        j: int,
    ) -> tuple[CompiledMode, np.ndarray]:
        x_new = np.array(chosen.reset(t, x), dtype=float)
        target = self.compiled.target(mode, chosen)
        how = boundary.chosen_by(chosen, enabled)
        self.recorder.jump(mode, target, chosen, enabled, how, t, j, x, x_new)
        return target, x_new


def _finite(x: np.ndarray) -> bool:
    return all(map(math.isfinite, x.tolist()))
