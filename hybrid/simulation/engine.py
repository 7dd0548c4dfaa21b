"""The event loop: one ``solve_ivp`` call per stay in a mode, jumps in between.

Semantics (docs/semantics.md): as-soon-as-possible firing; among transitions
enabled at one instant the highest priority fires, ties by file order, and the
choice is logged; after a jump the transitions are tested at the new point and
one enabled there fires at once (same ``t``, next ``j``); a guard that sits on
its boundary and moves away is disarmed until it has been strictly false, so
it never fires spuriously; leaving an invariant with nothing enabled ends the
run as ``blocked``.

Evaluation errors (see :mod:`hybrid.dynamics`) end the run as ``nonfinite``
when they happen at a point of the trajectory: a guard, invariant, signal or
reset, or the right-hand side where the simulator itself evaluates it. A
failure of the right-hand side at a trial point of the solver ends the run only
if the solver then gives up; otherwise the solver has stepped around it.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

from hybrid.compose import System
from hybrid.dynamics import CompiledCondition, CompiledMode, CompiledTransition, Dynamics
from hybrid.errors import SimulationError
from hybrid.expr.codegen import EvalFailure
from hybrid.model import Automaton
from hybrid.simulation.events import Interrupt, sigint_watch, watch_factory
from hybrid.simulation.result import Jump, Run, Termination
from hybrid.simulation.zeno import ZenoDetector

__all__ = ["METHODS", "simulate"]

METHODS = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")
MAX_JUMPS_PER_INSTANT = 1000


def simulate(
    model: Automaton | System,
    t_end: float,
    *,
    max_jumps: int = 10_000,
    rtol: float = 1e-6,
    atol: float = 1e-9,
    max_step: float | None = None,
    method: str = "RK45",
    parameters: Mapping[str, float] | None = None,
    initial: Mapping[str, float] | None = None,
    initial_location: str | None = None,
    inputs: Mapping[str, Callable[[float], float]] | None = None,
    t_start: float = 0.0,
    dt: float | None = None,
    zeno: bool = True,
    max_jumps_per_instant: int = MAX_JUMPS_PER_INSTANT,
    handle_sigint: bool = True,
    dense: bool = False,
) -> Run:
    """Simulate ``model`` from ``t_start`` to ``t_end``.

    Parameters
    ----------
    model : Automaton or System
        From :func:`hybrid.load`.
    t_end : float
        End time; the run ends there with cause ``t_end`` unless it ends before.
    max_jumps : int
        Stop with cause ``max_jumps`` after this many jumps.
    rtol, atol, max_step, method
        Passed to :func:`scipy.integrate.solve_ivp`. Lower ``max_step`` so that
        a guard that is true only briefly is not stepped over.
    parameters : mapping, optional
        Parameter overrides (``comp.name`` in a system).
    initial : mapping, optional
        Initial values of some state variables.
    initial_location : str, optional
        Start location of an automaton.
    inputs : mapping, optional
        External inputs of an automaton: name to a function of ``t``.
    dt : float, optional
        Store points on a uniform grid (jump points are always stored).
    zeno : bool
        Detect geometric accumulation of jumps (cause ``zeno``).
    max_jumps_per_instant : int
        Jumps allowed at one instant before the run ends as ``zeno``.
    handle_sigint : bool
        Turn Ctrl-C into a clean end (cause ``interrupted``), keeping the output.
    dense : bool
        Keep each segment's interpolant in ``run.segments`` (smooth plots).

    Returns
    -------
    Run
        The trajectory, jumps and termination (``run.termination.cause``).

    Examples
    --------
    >>> import hybrid
    >>> ball = hybrid.load("specs/bouncing_ball.yaml")
    >>> run = hybrid.simulate(ball, t_end=3.0, rtol=1e-10, atol=1e-12)
    >>> round(run.jumps[0].t, 9)  # sqrt(2 * 10 / 9.81)
    1.427843123
    """
    _check_settings(t_start, t_end, max_jumps, rtol, atol, max_step, method, dt)
    model = model.with_parameters(parameters) if parameters else model
    if isinstance(model, Automaton) and (initial or initial_location):
        model = model.with_initial(initial_location, initial)
    elif isinstance(model, System) and initial_location:
        raise SimulationError("initial_location applies to an automaton; set it per component")
    dyn = _dynamics(model, inputs)
    x0 = np.array(_initial_vector(model, dyn, initial), dtype=float)
    settings = {
        "t_start": t_start,
        "t_end": t_end,
        "max_jumps": max_jumps,
        "rtol": rtol,
        "atol": atol,
        "max_step": max_step,
        "method": method,
        "dt": dt,
        "dense": dense,
    }
    loop = _Loop(dyn, settings, zeno, max_jumps_per_instant)
    with sigint_watch(handle_sigint) as interrupted:
        loop.interrupted = interrupted
        termination = loop.run(t_start, x0)
    return loop.result(model.name, termination, settings)


_CACHE = threading.local()
_CACHE_SIZE = 8


def _dynamics(
    model: Automaton | System, inputs: Mapping[str, Callable[[float], float]] | None
) -> Dynamics:
    """Compiled dynamics of ``model``, reused across runs of the same model in a thread.

    Compiling a mode's functions costs far more than a jump; a parameter sweep or
    a benchmark simulates one model many times. Models with external inputs are
    compiled afresh (the inputs are bound into the code).
    """
    if inputs:
        return Dynamics(model, inputs)
    cache: dict[int, tuple[Automaton | System, Dynamics]] = getattr(_CACHE, "models", None) or {}
    _CACHE.models = cache
    hit = cache.get(id(model))
    if hit is not None and hit[0] is model:
        return hit[1]
    dyn = Dynamics(model)
    if len(cache) >= _CACHE_SIZE:
        cache.pop(next(iter(cache)))
    cache[id(model)] = (model, dyn)
    return dyn


def _check_settings(
    t_start: float,
    t_end: float,
    max_jumps: int,
    rtol: float,
    atol: float,
    max_step: float | None,
    method: str,
    dt: float | None,
) -> None:
    if not (math.isfinite(t_start) and math.isfinite(t_end)) or t_end <= t_start:
        raise SimulationError(f"t_end must be a finite time after t_start={t_start}, got {t_end}")
    if max_jumps < 0:
        raise SimulationError(f"max_jumps must be >= 0, got {max_jumps}")
    for name, value in (("rtol", rtol), ("atol", atol)):
        if not value > 0:
            raise SimulationError(f"{name} must be > 0, got {value}")
    if max_step is not None and not max_step > 0:
        raise SimulationError(f"max_step must be > 0, got {max_step}")
    if dt is not None and not dt > 0:
        raise SimulationError(f"dt must be > 0, got {dt}")
    if method not in METHODS:
        raise SimulationError(f"unknown method '{method}'; choose one of {', '.join(METHODS)}")


def _initial_vector(
    model: Automaton | System, dyn: Dynamics, initial: Mapping[str, float] | None
) -> list[float]:
    x0 = model.initial_vector()
    if isinstance(model, System) and initial:
        for name, value in initial.items():
            if name not in dyn.state_names:
                raise SimulationError(f"initial value for unknown state variable '{name}'")
            x0[dyn.state_names.index(name)] = float(value)
    return x0


@dataclass
class _Loop:
    dyn: Dynamics
    settings: dict[str, Any]
    zeno_enabled: bool
    max_per_instant: int
    interrupted: list[bool] = field(default_factory=lambda: [False])
    chunks: list[tuple[CompiledMode, int, np.ndarray, np.ndarray, list[Any]]] = field(
        default_factory=list
    )
    watch_factories: dict[tuple[Any, ...], Callable[..., Any]] = field(default_factory=dict)
    last_step: float | None = None
    jumps: list[Jump] = field(default_factory=list)
    segments: list[tuple[int, float, float, Any]] = field(default_factory=list)

    # --- storing points -----------------------------------------------------------------

    def _store(self, mode: CompiledMode, j: int, ts: np.ndarray, xs: np.ndarray) -> None:
        """Store points ``ts`` (n,) with states ``xs`` (n, d) in ``mode`` at hybrid time ``j``.

        Signals are computed now (a failing one must end the run here) into plain
        lists; the arrays are assembled once, in :meth:`result`.
        """
        if ts.size:
            outputs = mode.outputs
            signals = [outputs(t, x) for t, x in zip(ts.tolist(), xs, strict=True)]
            self.chunks.append((mode, j, ts, xs, signals))

    def result(self, name: str, termination: Termination, settings: dict[str, Any]) -> Run:
        n_states, n_signals = len(self.dyn.state_names), len(self.dyn.columns)
        chunks = self.chunks
        sizes = [c[2].size for c in chunks]
        t = np.concatenate([c[2] for c in chunks]) if chunks else np.empty(0)
        states = np.vstack([c[3] for c in chunks]) if chunks else np.empty((0, n_states))
        j = np.repeat(np.array([c[1] for c in chunks], dtype=np.int64), sizes)
        location = np.repeat(np.array([c[0].name for c in chunks], dtype=np.str_), sizes)
        rows = [row for c in chunks for row in c[4]]
        signals = np.array(rows, dtype=float).reshape(len(rows), n_signals)
        return Run(
            model=name,
            state_names=tuple(self.dyn.state_names),
            signal_names=tuple(self.dyn.columns),
            t=t,
            j=j,
            location=location,
            states=states,
            signals=signals,
            jumps=self.jumps,
            termination=termination,
            settings=settings,
            segments=self.segments,
        )

    # --- the loop -----------------------------------------------------------------------

    def run(self, t: float, x: np.ndarray) -> Termination:
        dyn = self.dyn
        key = dyn.initial_key
        mode = dyn.mode(key)
        j = 0
        t_end: float = self.settings["t_end"]
        max_jumps: int = self.settings["max_jumps"]
        if not _finite(x):
            return Termination("nonfinite", t, j, "initial state is not finite", location=mode.name)
        self._store(mode, j, np.array([t]), x.reshape(1, -1))
        zeno = ZenoDetector()
        same_instant, last_jump_t, stalls = 0, math.nan, 0

        while True:
            if self._failed() is not None:
                return self._eval_failure(t, j, mode)
            if self.interrupted[0]:
                return Termination(
                    "interrupted", t, j, "interrupted by the user", location=mode.name
                )
            chosen, enabled, armed = self._enabled_at_entry(mode, t, x)
            if self._failed() is not None:
                return self._eval_failure(t, j, mode)
            if chosen is None:
                blocked = self._blocked(mode, t, x, j, "does not hold")
                if blocked is not None:
                    return blocked
                if t >= t_end:  # a jump landed exactly at t_end: nothing left to flow
                    return Termination("t_end", t, j, "reached t_end", location=mode.name)
                outcome = self._flow(mode, t, x, j, armed)
                if isinstance(outcome, Termination):
                    return outcome
                t_before = t
                t, x, chosen, enabled = outcome
                if chosen is None:
                    stalls = stalls + 1 if t == t_before else 0
                    if stalls > self.max_per_instant:
                        return Termination(
                            "solver_failure",
                            t,
                            j,
                            "events keep firing at the same instant without any transition "
                            "becoming enabled (a guard touching its boundary?)",
                            location=mode.name,
                        )
                    continue
            if j >= max_jumps:
                return Termination(
                    "max_jumps", t, j, f"reached max_jumps={max_jumps}", location=mode.name
                )
            same_instant = same_instant + 1 if t == last_jump_t else 1
            last_jump_t = t
            if same_instant > self.max_per_instant:
                return Termination(
                    "zeno",
                    t,
                    j,
                    f"{self.max_per_instant} jumps at the same instant: a cycle of transitions "
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
            estimate = zeno.update(t) if self.zeno_enabled else None
            if estimate is not None and estimate <= t_end:
                return Termination(
                    "zeno",
                    t,
                    j,
                    f"jumps accumulate (gaps shrink geometrically); estimated Zeno time {estimate:.12g}",
                    zeno_time=estimate,
                    location=mode.name,
                )

    def _failed(self) -> EvalFailure | None:
        """The evaluation failure at a point of the trajectory, if any."""
        for failure in (self.dyn.failure, self.dyn.flow_failure):
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
            f"{self.dyn.describe_failure(failure)} (at t={where:.9g})",
            location=mode.name,
        )

    # --- entry and event decisions ------------------------------------------------------

    def _band(self, x: np.ndarray) -> float:
        """Values of rho within this of 0 count as on the boundary."""
        return 1e-10 * (1.0 + max(map(abs, x.tolist()), default=0.0))

    def _slope(
        self, fn: Callable[[float, Any], float], mode: CompiledMode, t: float, x: np.ndarray
    ) -> float:
        """d/dt of ``fn`` along the flow, by a small forward difference."""
        h = 1e-7 * max(1.0, abs(t))
        ahead = [xi + h * di for xi, di in zip(x.tolist(), mode.rhs(t, x), strict=True)]
        return float((fn(t + h, np.array(ahead)) - fn(t, x)) / h)

    def _holds_now(
        self,
        cond: CompiledCondition,
        mode: CompiledMode,
        t: float,
        x: np.ndarray,
        armed: bool,
        band: float,
    ) -> tuple[bool, bool]:
        """(enabled now, armed) for a guard at a point where no event says so."""
        value = cond.rho(t, x)
        if value < -band:
            return True, True
        if value > band:
            return False, True
        if not armed:
            return False, False
        slope = self._slope(cond.rho, mode, t, x)
        if slope < -band:
            return True, True
        if slope > band:
            return False, False  # on the boundary, moving away: disarm until strictly false
        return bool(cond.holds(t, x)), False

    def _enabled_at_entry(
        self, mode: CompiledMode, t: float, x: np.ndarray
    ) -> tuple[CompiledTransition | None, list[CompiledTransition], list[bool]]:
        enabled: list[CompiledTransition] = []
        armed: list[bool] = []
        band = self._band(x)
        for tr in mode.transitions:
            now, is_armed = self._holds_now(tr, mode, t, x, True, band)
            armed.append(is_armed)
            if now:
                enabled.append(tr)
        return _choose(enabled), enabled, armed

    def _blocked(
        self, mode: CompiledMode, t: float, x: np.ndarray, j: int, how: str
    ) -> Termination | None:
        """End as ``blocked`` if an invariant is being left here (no transition is enabled)."""
        left = self._invariant_left_at(mode, t, x)
        if left is None:
            return None
        message = f"invariant of {left} {how} and no transition is enabled"
        return Termination("blocked", t, j, message, location=mode.name)

    def _invariant_left_at(self, mode: CompiledMode, t: float, x: np.ndarray) -> str | None:
        band = self._band(x)
        for inv in mode.invariants:
            value = inv.rho(t, x)
            if value > band:
                return inv.name
            if value >= -band:
                slope = self._slope(inv.rho, mode, t, x)
                if slope > band or (abs(slope) <= band and not inv.holds(t, x)):
                    return inv.name
        return None

    # --- flowing ------------------------------------------------------------------------

    def _flow(
        self, mode: CompiledMode, t0: float, x0: np.ndarray, j: int, armed: list[bool]
    ) -> (
        Termination | tuple[float, np.ndarray, CompiledTransition | None, list[CompiledTransition]]
    ):
        settings = self.settings
        t_end: float = settings["t_end"]
        band = self._band(x0)
        inv_armed = [inv.rho(t0, x0) < -band for inv in mode.invariants]
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
        dense = settings["dt"] is not None or settings["dense"]
        self.dyn.flow_failure.clear()
        max_step = settings["max_step"] if settings["max_step"] is not None else np.inf
        sol = solve_ivp(
            mode.rhs,
            (t0, t_end),
            x0,
            method=settings["method"],
            rtol=settings["rtol"],
            atol=settings["atol"],
            max_step=max_step,
            first_step=self._first_step(t0, t_end, max_step),
            events=events,
            dense_output=dense,
        )
        ts, xs = sol.t, sol.y.T
        if ts.size >= 3:  # the last full step (the final one is cut short by the event)
            self.last_step = float(ts[-2] - ts[-3])
        self._store_segment(mode, j, sol, ts, xs)
        if settings["dense"] and sol.sol is not None and ts.size > 1:
            self.segments.append((j, float(ts[0]), float(ts[-1]), sol.sol))
        t, x = float(ts[-1]), xs[-1].copy()
        if self.dyn.failure.error is not None:
            return self._eval_failure(t, j, mode)
        flow_failure = self.dyn.flow_failure
        # a state that becomes non-finite makes the solver fail, so the last row is enough
        # unless it did
        finite = _finite(x) if sol.status != -1 else bool(np.isfinite(xs).all())
        if flow_failure.error is not None and (sol.status == -1 or not finite):
            return Termination(
                "nonfinite",
                t,
                j,
                f"{self.dyn.describe_failure(flow_failure)} (at t={flow_failure.t:.9g}); "
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
        if stalled[0]:
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
        if interrupt.at is not None or self.interrupted[0]:
            return Termination("interrupted", t, j, "interrupted by the user", location=mode.name)
        band = self._band(x)
        enabled: list[CompiledTransition] = []
        for i, tr in enumerate(mode.transitions):
            # a crossing the solver found still has to pass the boundary rule: rho may
            # reach 0 and stay there while a strict guard never holds (e.g. `0 > 0 and ...`)
            armed_now = watch_armed[i] or tr.rho(t, x) <= band
            if self._holds_now(tr, mode, t, x, armed_now, band)[0]:
                enabled.append(tr)
        if self._failed() is not None:
            return self._eval_failure(t, j, mode)
        chosen = _choose(enabled)
        if chosen is None:
            blocked = self._blocked(mode, t, x, j, "is about to be left")
            if blocked is not None:
                return blocked
        return t, x, chosen, enabled

    def _first_step(self, t0: float, t_end: float, max_step: float) -> float | None:
        """Start a stay with the last full step of the previous one (None: let scipy choose).

        Warm-starting saves the solver's initial-step estimate (two evaluations of
        the right-hand side) at every jump; its error control still accepts or
        shrinks the step as the tolerances require.
        """
        h = self.last_step
        if h is None or not h > 0.0:
            return None
        return min(h, max_step, t_end - t0) if t_end > t0 else None

    def _store_segment(
        self, mode: CompiledMode, j: int, sol: Any, ts: np.ndarray, xs: np.ndarray
    ) -> None:
        dt = self.settings["dt"]
        if dt is None or sol.sol is None:
            self._store(mode, j, ts[1:], xs[1:])
            return
        t0, t1 = float(ts[0]), float(ts[-1])
        start = self.settings["t_start"]
        k0 = math.floor((t0 - start) / dt) + 1
        k1 = math.ceil((t1 - start) / dt) - 1
        grid = start + dt * np.arange(k0, k1 + 1) if k1 >= k0 else np.empty(0)
        grid = grid[(grid > t0) & (grid < t1)]
        inner = sol.sol(grid).T if grid.size else np.empty((0, xs.shape[1]))
        self._store(mode, j, np.append(grid, t1), np.vstack([inner, xs[-1:]]))

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
        after = chosen.reset(t, x)
        x_new = np.array(after, dtype=float)
        target = self.dyn.mode(chosen.view.target)
        names = self.dyn.state_names
        self.jumps.append(
            Jump(
                t,
                j,
                chosen.name,
                chosen.view.label,
                mode.name,
                target.name,
                dict(zip(names, x.tolist(), strict=True)),
                dict(zip(names, x_new.tolist(), strict=True)),
                tuple(tr.name for tr in enabled),
                _chosen_by(chosen, enabled),
            )
        )
        self._store(target, j + 1, np.array([t]), x_new.reshape(1, -1))
        return target, x_new


def _finite(x: np.ndarray) -> bool:
    return all(map(math.isfinite, x.tolist()))


def _choose(enabled: list[CompiledTransition]) -> CompiledTransition | None:
    """Highest priority first, then file order."""
    if not enabled:
        return None
    return min(enabled, key=lambda tr: (-tr.view.priority, tr.view.order))


def _chosen_by(chosen: CompiledTransition, enabled: list[CompiledTransition]) -> str:
    if len(enabled) == 1:
        return "only"
    top = [tr for tr in enabled if tr.view.priority == chosen.view.priority]
    return "priority" if len(top) == 1 else "file order"
