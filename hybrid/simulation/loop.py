"""The event loop: one ``solve_ivp`` call per stay in a mode, jumps in between.

Semantics (docs/semantics.md): as-soon-as-possible firing; among transitions
enabled at one instant the highest priority fires, ties by file order, and the
choice is logged; after a jump the transitions are tested at the new point and
one enabled there fires at once (same ``t``, next ``j``); a guard that sits on
its boundary and moves away is disarmed until it has been strictly false, so
it never fires spuriously; leaving an invariant with nothing enabled ends the
run as ``blocked``. The decisions at a point are :mod:`~hybrid.simulation.boundary`'s.

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
from scipy.integrate import solve_ivp

from hybrid.expr.codegen import EvalFailure
from hybrid.simulation import boundary
from hybrid.simulation.compiled import CompiledMode, CompiledModel, CompiledTransition
from hybrid.simulation.events import Interrupt, watch_factory
from hybrid.simulation.failures import describe_failure
from hybrid.simulation.recorder import Recorder
from hybrid.simulation.result import Termination
from hybrid.simulation.settings import Settings
from hybrid.simulation.zeno import ZenoDetector

__all__ = ["EventLoop"]

Flowed = tuple[float, np.ndarray, CompiledTransition | None, list[CompiledTransition]]


class EventLoop:
    """Runs one simulation of a compiled model; the recorder keeps what it computes."""

    def __init__(
        self, compiled: CompiledModel, settings: Settings, interrupted: list[bool]
    ) -> None:
        self.compiled = compiled
        self.settings = settings
        self.interrupted = interrupted
        self.recorder = Recorder(compiled, settings)
        self.watch_factories: dict[tuple[Any, ...], Callable[..., Any]] = {}
        self.last_step: float | None = None

    def run(self, t: float, x: np.ndarray) -> Termination:
        """Simulate from ``(t, x)`` in the initial mode until the run ends; how it ended."""
        compiled, settings = self.compiled, self.settings
        mode = compiled.mode(compiled.initial_key)
        j = 0
        if not _finite(x):
            return Termination("nonfinite", t, j, "initial state is not finite", location=mode.name)
        self.recorder.points(mode, j, np.array([t]), x.reshape(1, -1))
        zeno = ZenoDetector()
        same_instant, last_jump_t, stalls = 0, math.nan, 0
        max_per_instant = settings.max_jumps_per_instant

        while True:
            if self._failed() is not None:
                return self._eval_failure(t, j, mode)
            if self.interrupted[0]:
                return Termination(
                    "interrupted", t, j, "interrupted by the user", location=mode.name
                )
            chosen, enabled, armed = boundary.enabled_at_entry(mode, t, x)
            if self._failed() is not None:
                return self._eval_failure(t, j, mode)
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
                t, x, chosen, enabled = outcome
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
            mode, x = self._jump(mode, chosen, enabled, t, x, j)
            j += 1
            if self._failed() is not None:
                return self._eval_failure(t, j, mode)
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

    def _eval_failure(self, t: float, j: int, mode: CompiledMode) -> Termination:
        failure = self._failed()
        assert failure is not None
        where = float(failure.t) if failure.t is not None else t
        return Termination(
            "nonfinite",
            where,
            j,
            f"{describe_failure(self.compiled, failure)} (at t={where:.9g})",
            location=mode.name,
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
        """Integrate one stay until the watch event or ``t_end``; what happened at its end."""
        settings = self.settings
        width = boundary.band(x0)
        inv_armed = [inv.rho(t0, x0) < -width for inv in mode.invariants]
        interrupt = Interrupt(self.interrupted, t0)
        functions = [*(tr.rho for tr in mode.transitions), *(inv.rho for inv in mode.invariants)]
        signs = (1.0,) * len(mode.transitions) + (-1.0,) * len(mode.invariants)
        pattern = (*armed, *inv_armed)
        factory = self.watch_factories.get((mode.key, pattern))
        if factory is None:
            factory = self.watch_factories[(mode.key, pattern)] = watch_factory(signs, pattern)
        watch_armed = list(pattern)
        stalled = [False]
        events: list[Any] = [factory(functions, interrupt.flag, interrupt, watch_armed, stalled)]
        self.compiled.flow_failure.clear()
        sol = solve_ivp(
            mode.rhs,
            (t0, settings.t_end),
            x0,
            method=settings.method,
            rtol=settings.rtol,
            atol=settings.atol,
            max_step=settings.max_step,
            first_step=self._first_step(t0),
            events=events,
            dense_output=settings.keeps_interpolants,
        )
        ts, xs = sol.t, sol.y.T
        if ts.size >= 3:  # the last full step (the final one is cut short by the event)
            self.last_step = float(ts[-2] - ts[-3])
        self.recorder.stay(mode, j, ts, xs, sol.sol)
        t, x = float(ts[-1]), xs[-1].copy()
        if self.compiled.failure.error is not None:
            return self._eval_failure(t, j, mode)
        ended = self._solver_end(sol, mode, t, x, xs, j, stalled[0])
        if ended is not None:
            return ended
        if interrupt.at is not None or self.interrupted[0]:
            return Termination("interrupted", t, j, "interrupted by the user", location=mode.name)
        width = boundary.band(x)
        enabled: list[CompiledTransition] = []
        for i, tr in enumerate(mode.transitions):
            # a crossing the solver found still has to pass the boundary rule: rho may
            # reach 0 and stay there while a strict guard never holds (e.g. `0 > 0 and ...`)
            armed_now = watch_armed[i] or tr.rho(t, x) <= width
            if boundary.holds_now(tr, mode, t, x, armed_now, width)[0]:
                enabled.append(tr)
        if self._failed() is not None:
            return self._eval_failure(t, j, mode)
        chosen = boundary.choose(enabled)
        if chosen is None:
            blocked = self._blocked(mode, t, x, j, "is about to be left")
            if blocked is not None:
                return blocked
        return t, x, chosen, enabled

    def _solver_end(
        self,
        sol: Any,
        mode: CompiledMode,
        t: float,
        x: np.ndarray,
        xs: np.ndarray,
        j: int,
        stalled: bool,
    ) -> Termination | None:
        """How the run ends if the solver failed, reached ``t_end`` or stalled; else ``None``."""
        flow_failure = self.compiled.flow_failure
        # a state that becomes non-finite makes the solver fail, so the last row is enough
        # unless it did
        finite = _finite(x) if sol.status != -1 else bool(np.isfinite(xs).all())
        if flow_failure.error is not None and (sol.status == -1 or not finite):
            return Termination(
                "nonfinite",
                t,
                j,
                f"{describe_failure(self.compiled, flow_failure)} (at t={flow_failure.t:.9g}); "
                f"the solution leaves the domain of the flow after t={t:.9g}",
                location=mode.name,
            )
        flow_failure.clear()  # only at trial points the solver rejected: it stepped around them
        if sol.status == -1 or not finite:
            cause = "nonfinite" if not finite else "solver_failure"
            peak = float(np.max(np.abs(xs[-1]))) if xs.size else math.nan
            return Termination(
                cause,
                t,
                j,
                f"solver stopped: {sol.message} (largest |state| {peak:.3g}; the solution may "
                "blow up here, or try another --method or tighter tolerances)",
                location=mode.name,
            )
        if sol.status == 0:
            return Termination("t_end", t, j, "reached t_end", location=mode.name)
        if stalled:
            peak = max(map(abs, x.tolist()), default=0.0)
            return Termination(
                "solver_failure",
                t,
                j,
                f"solver stopped advancing: its step size fell below the spacing of "
                f"floating-point numbers at t={t:.9g} (largest |state| {peak:.3g}; the solution "
                "may blow up here, or try another --method)",
                location=mode.name,
            )
        return None

    def _first_step(self, t0: float) -> float | None:
        """Start a stay with the last full step of the previous one (None: let scipy choose).

        Warm-starting saves the solver's initial-step estimate (two evaluations of
        the right-hand side) at every jump; its error control still accepts or
        shrinks the step as the tolerances require.
        """
        h, t_end = self.last_step, self.settings.t_end
        if h is None or not h > 0.0:
            return None
        return min(h, self.settings.max_step, t_end - t0) if t_end > t0 else None

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
        target = self.compiled.mode(chosen.view.target)
        how = boundary.chosen_by(chosen, enabled)
        self.recorder.jump(mode, target, chosen, enabled, how, t, j, x, x_new)
        return target, x_new


def _finite(x: np.ndarray) -> bool:
    return all(map(math.isfinite, x.tolist()))
