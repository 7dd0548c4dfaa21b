"""The recorder: the points, jumps and interpolants of a run, assembled into a :class:`Run`.

Points are collected per stay (:class:`StayRecord`: the end of every accepted
step, or the points of a ``dt`` grid, and the end of the stay) and stored as
arrays when the stay ends, signals computed then (a signal that fails must end
the run there); the columns are assembled once, at the end. At each step's end
the recorder keeps what the stepped flow left there
(:class:`~hybrid.expr.codegen.Stash`), so that the signals of that point reuse
what it computed.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.integrate import OdeSolution

from hybrid.simulation.compiled import CompiledMode, CompiledModel, CompiledTransition
from hybrid.simulation.dense import StepCurve
from hybrid.simulation.layout import run_layout
from hybrid.simulation.monitor import Monitor
from hybrid.simulation.result import Jump, Run, Termination
from hybrid.simulation.same_instant import signals_after
from hybrid.simulation.settings import Settings

__all__ = ["Recorder", "StayRecord"]


class StayRecord:
    """The points of one stay in a mode, step by step, stored by :meth:`close`."""

    def __init__(self, recorder: Recorder, mode: CompiledMode, j: int, t0: float) -> None:
        self.recorder = recorder
        self.mode = mode
        self.j = j
        self.ts: list[float] = []
        self.xs: list[np.ndarray] = []
        """The states of the points: one row per step end, or one block of rows per step
        of a ``dt`` grid (a million points as rows would cost a second to stack)."""
        self.dt = recorder.settings.dt
        self.dense = recorder.settings.dense
        self.step_ends = [t0]
        self.interpolants: list[Any] = []
        self.slot = recorder.compiled.stash_slot if mode.flow is not None else None
        self.stashes: list[Any] = []
        """What the stash held as each step end was recorded, read again by :meth:`close`."""

    def step(self, curve: StepCurve, stop: float | None) -> None:
        """Record an accepted step; ``stop`` is where the stay ends inside it (None: it goes on).

        Stored: the step end if the stay goes on; with a ``dt`` grid instead, the
        grid points after the step start and before ``stop`` (up to the step end
        if the stay goes on).
        """
        if self.dt is None:
            if stop is None:
                self.ts.append(curve.t1)
                self.xs.append(curve.x1)
                if self.slot is not None:
                    self.stashes.append(self.slot[0])
        else:
            grid = self._grid(curve.t0, curve.t1 if stop is None else stop, stop is None)
            if grid.size:
                self.ts.extend(grid.tolist())
                self.xs.append(curve.many(grid))
        if self.dense:
            self.step_ends.append(curve.t1)
            self.interpolants.append(curve.dense_output())
        monitor = self.recorder.monitor
        if monitor is not None:
            monitor.segment(self.mode, curve, stop)

    def _grid(self, after: float, until: float, inclusive: bool) -> np.ndarray:
        dt = self.dt
        assert dt is not None
        start = self.recorder.settings.t_start
        k0 = math.floor((after - start) / dt)
        k1 = math.floor((until - start) / dt) + 1
        grid = start + dt * np.arange(k0, k1 + 1)
        keep = (grid > after) & ((grid <= until) if inclusive else (grid < until))
        return grid[keep]

    def close(self, t: float | None, x: np.ndarray | None) -> None:
        """End the stay at ``(t, x)`` (None: no point beyond those recorded) and store its points."""
        if t is not None and x is not None:
            self.ts.append(t)
            self.xs.append(x)
        if self.ts:
            if self.dt is None:
                xs = np.array(self.xs)
            else:
                xs = np.concatenate([np.atleast_2d(x) for x in self.xs])
            self.recorder.points(self.mode, self.j, np.array(self.ts), xs, self.stashes)
        if self.dense and self.interpolants:
            end = self.ts[-1] if self.ts else self.step_ends[-1]
            solution = OdeSolution(self.step_ends, self.interpolants)
            self.recorder.segments.append((self.j, self.step_ends[0], end, solution))

    @property
    def count(self) -> int:
        """Points recorded so far in this stay."""
        return len(self.ts)


class Recorder:
    """Collects what a run computes, in hybrid-time order."""

    def __init__(self, compiled: CompiledModel, settings: Settings) -> None:
        self.compiled = compiled
        self.settings = settings
        self.chunks: list[tuple[CompiledMode, int, np.ndarray, np.ndarray, Any]] = []
        """Per stored stretch: mode, j, times, states, and the signals (a list of rows, or an
        array of them when there are several)."""
        self.jumps: list[Jump] = []
        self.segments: list[tuple[int, float, float, Any]] = []
        self.count = 0
        """Points stored so far."""
        self.monitor: Monitor | None = None
        """The requirement monitor, if the model has requirements: it sees every point and step."""
        self._states: tuple[bytes, dict[str, float]] = (b"", {})
        """The last jump's state after it, as bytes and as the mapping its record holds:
        a jump that leaves the state as it was, or starts where the last one ended, shares
        it (a system whose components switch at one instant would otherwise keep two
        copies of the whole state per jump)."""

    def start(self, mode: CompiledMode, t: float, x: np.ndarray) -> None:
        """Store the initial point of the run (hybrid time 0)."""
        self.points(mode, 0, np.array([t]), x.reshape(1, -1))
        if self.monitor is not None:
            self.monitor.point(mode, t, x)

    def points(
        self,
        mode: CompiledMode,
        j: int,
        ts: np.ndarray,
        xs: np.ndarray,
        stashes: list[Any] | None = None,
    ) -> None:
        """Store points ``ts`` (n,) with states ``xs`` (n, d) in ``mode`` at hybrid time ``j``.

        ``stashes[k]`` is what the stash held when point ``k`` was recorded (if given).
        """
        if ts.size:
            self.count += ts.size
            outputs = mode.outputs
            if stashes:
                slot = self.compiled.stash_slot
                signals = []
                for k, (t, x) in enumerate(zip(ts.tolist(), xs, strict=True)):
                    if k < len(stashes):
                        slot[0] = stashes[k]
                    signals.append(outputs(t, x))
            else:
                signals = [outputs(t, x) for t, x in zip(ts.tolist(), xs, strict=True)]
            if len(signals) > 1:  # as floats in an array: a Python float and its place take 32 bytes
                rows = np.array(signals, dtype=float).reshape(len(signals), len(self.compiled.columns))
                self.chunks.append((mode, j, ts, xs, rows))
            else:
                self.chunks.append((mode, j, ts, xs, signals))

    def stay(self, mode: CompiledMode, j: int, t0: float) -> StayRecord:
        """Start recording a stay in ``mode`` that begins at ``t0`` (its first point is stored)."""
        return StayRecord(self, mode, j, t0)

    def jump(
        self,
        mode: CompiledMode,
        target: CompiledMode,
        chosen: CompiledTransition,
        enabled: list[CompiledTransition],
        chosen_by: str,
        t: float,
        j: int,
        before: np.ndarray,
        after: np.ndarray,
    ) -> None:
        """Record a jump and store the post-jump point (at ``t``, hybrid time ``j + 1``)."""
        names = self.compiled.state_names
        point, end = before.tobytes(), after.tobytes()
        kept, states = self._states
        if point != kept:
            states = dict(zip(names, before.tolist(), strict=True))
        start = states
        if end != point:
            states = dict(zip(names, after.tolist(), strict=True))
        self._states = (end, states)
        self.jumps.append(
            Jump(
                t,
                j,
                chosen.name,
                chosen.view.label,
                mode.name,
                target.name,
                start,
                states,
                tuple(tr.name for tr in enabled),
                chosen_by,
            )
        )
        row = None if end != point else self._carried_signals(mode, chosen, target, t, after, point)
        if row is None:
            self.points(target, j + 1, np.array([t]), after.reshape(1, -1))
        else:
            self.count += 1
            self.chunks.append((target, j + 1, np.array([t]), after.reshape(1, -1), [row]))
        if self.monitor is not None:
            self.monitor.point(target, t, after)

    def _carried_signals(
        self,
        mode: CompiledMode,
        chosen: CompiledTransition,
        target: CompiledMode,
        t: float,
        x: np.ndarray,
        point: bytes,
    ) -> tuple[float, ...] | None:
        """The signals at ``(t, x)`` (``point``: its bytes) after a jump that left the state
        as it was, from the point stored before it (modes built from parts:
        :func:`~hybrid.simulation.same_instant.signals_after`)."""
        if self.compiled.parts is None or not self.chunks:
            return None
        last, _, ts, xs, rows = self.chunks[-1]
        if last is not mode or ts[-1] != t or xs[-1].tobytes() != point:
            return None
        return signals_after(self.compiled, mode, chosen, target, t, x, rows[-1])

    def run(self, name: str, termination: Termination) -> Run:
        """The :class:`Run` of everything recorded."""
        n_states, n_signals = len(self.compiled.state_names), len(self.compiled.columns)
        chunks = self.chunks
        sizes = [c[2].size for c in chunks]
        t = np.concatenate([c[2] for c in chunks]) if chunks else np.empty(0)
        states = np.vstack([c[3] for c in chunks]) if chunks else np.empty((0, n_states))
        j = np.repeat(np.array([c[1] for c in chunks], dtype=np.int64), sizes)
        location = np.repeat(np.array([c[0].name for c in chunks], dtype=object), sizes)
        signals = _signal_rows([c[4] for c in chunks], n_signals)
        return Run(
            model=name,
            state_names=tuple(self.compiled.state_names),
            signal_names=tuple(self.compiled.columns),
            t=t,
            j=j,
            location=location,
            states=states,
            signals=signals,
            jumps=self.jumps,
            termination=termination,
            settings=self.settings.as_dict(),
            segments=self.segments,
            **run_layout(self.compiled.system),
            requirements={} if self.monitor is None else self.monitor.results(termination.t),
        )


def _signal_rows(stretches: list[Any], n_signals: int) -> NDArray[np.float64]:
    """The signals of every stretch, in order, as one 2-D array, filled in place.

    A stretch of several points holds an array already; those of one point (the
    jumps' points, most of a system's) a list of rows, copied in a run of them at
    a time.
    """
    signals = np.empty((sum(len(s) for s in stretches), n_signals))
    k, rows = 0, list[Any]()
    for stretch in [*stretches, None]:
        if rows and not isinstance(stretch, list):
            signals[k : k + len(rows)] = np.array(rows, dtype=np.float64).reshape(len(rows), n_signals)
            k, rows = k + len(rows), []
        if isinstance(stretch, np.ndarray):
            signals[k : k + len(stretch)] = stretch
            k += len(stretch)
        elif stretch is not None:
            rows += stretch
    return signals
