"""The recorder: the points, jumps and interpolants of a run, assembled into a :class:`Run`.

Points are stored per stay as arrays, signals computed when stored (a signal
that fails must end the run there), and the columns are assembled once, at
the end.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from hybrid.simulation.compiled import CompiledMode, CompiledModel, CompiledTransition
from hybrid.simulation.layout import run_layout
from hybrid.simulation.result import Jump, Run, Termination
from hybrid.simulation.settings import Settings

__all__ = ["Recorder"]


class Recorder:
    """Collects what a run computes, in hybrid-time order."""

    def __init__(self, compiled: CompiledModel, settings: Settings) -> None:
        self.compiled = compiled
        self.settings = settings
        self.chunks: list[tuple[CompiledMode, int, np.ndarray, np.ndarray, list[Any]]] = []
        self.jumps: list[Jump] = []
        self.segments: list[tuple[int, float, float, Any]] = []

    def points(self, mode: CompiledMode, j: int, ts: np.ndarray, xs: np.ndarray) -> None:
        """Store points ``ts`` (n,) with states ``xs`` (n, d) in ``mode`` at hybrid time ``j``."""
        if ts.size:
            outputs = mode.outputs
            signals = [outputs(t, x) for t, x in zip(ts.tolist(), xs, strict=True)]
            self.chunks.append((mode, j, ts, xs, signals))

    def stay(self, mode: CompiledMode, j: int, ts: np.ndarray, xs: np.ndarray, sol: Any) -> None:
        """Store a stay's points (after its first): the solver's, or a ``dt`` grid, and its end.

        With ``dense`` settings the stay's interpolant is kept in ``run.segments``.
        """
        dt = self.settings.dt
        if dt is None or sol is None:
            self.points(mode, j, ts[1:], xs[1:])
        else:
            t0, t1 = float(ts[0]), float(ts[-1])
            start = self.settings.t_start
            k0 = math.floor((t0 - start) / dt) + 1
            k1 = math.ceil((t1 - start) / dt) - 1
            grid = start + dt * np.arange(k0, k1 + 1) if k1 >= k0 else np.empty(0)
            grid = grid[(grid > t0) & (grid < t1)]
            inner = sol(grid).T if grid.size else np.empty((0, xs.shape[1]))
            self.points(mode, j, np.append(grid, t1), np.vstack([inner, xs[-1:]]))
        if self.settings.dense and sol is not None and ts.size > 1:
            self.segments.append((j, float(ts[0]), float(ts[-1]), sol))

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
        self.jumps.append(
            Jump(
                t,
                j,
                chosen.name,
                chosen.view.label,
                mode.name,
                target.name,
                dict(zip(names, before.tolist(), strict=True)),
                dict(zip(names, after.tolist(), strict=True)),
                tuple(tr.name for tr in enabled),
                chosen_by,
            )
        )
        self.points(target, j + 1, np.array([t]), after.reshape(1, -1))

    def run(self, name: str, termination: Termination) -> Run:
        """The :class:`Run` of everything recorded."""
        n_states, n_signals = len(self.compiled.state_names), len(self.compiled.columns)
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
        )
