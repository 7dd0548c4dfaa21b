"""Requirements on compiled runs: the scipy backend's monitor, shown the compiled run's steps.

The compiled loop does not evaluate requirements itself. A run of a model with
requirements keeps every step's interpolant (as with ``dense=True``), and the
monitor of :mod:`hybrid.simulation.monitor` is then shown what the scipy
backend's recorder shows it, in the same order: the start point, each accepted
step of each stay (DOPRI5's continuous extension, up to the event that ends the
stay), the point after each jump. So the results follow the same rules
(samples, refined extremes, violation times located by Brent's method); they
differ from the scipy backend's only as far as the two backends' steps differ.

Examples
--------
>>> import hybrid, math
>>> heater = hybrid.load_text('''
... automaton: heater
... state: {x: {initial: 20.0}}
... locations: {cooling: {flow: {x: -0.1*x}}}
... requirements: [{name: warm, always: "x >= 15"}]
... ''')
>>> warm = hybrid.simulate(heater, t_end=5.0, rtol=1e-10, atol=1e-12,
...                        backend="compiled").requirements["warm"]
>>> warm.holds, abs(warm.robustness - (20 * math.exp(-0.5) - 15)) < 1e-9
(False, True)
>>> abs(warm.violated_at - 10 * math.log(20 / 15)) < 1e-7
True
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from hybrid.frames import in_frame_room
from hybrid.modes import Mode
from hybrid.simulation.compiled import CompiledModel
from hybrid.simulation.dense import StepCurve, polynomial_curve
from hybrid.simulation.monitor import Monitor
from hybrid.simulation.native.assemble import DenseSegment, Layout
from hybrid.simulation.result import RequirementResult, Run

__all__ = ["replay"]


@in_frame_room
def replay(
    monitor: Monitor, model: CompiledModel, layout: Layout, run: Run
) -> dict[str, RequirementResult]:
    """Each requirement's result on ``run``, a compiled run kept with its steps' interpolants.

    ``model`` is the scipy backend's compiled form of the same model (the
    monitor compiles the requirements' margins with it; the modes' own functions
    are not needed, so they are not compiled), ``layout`` the compiled
    backend's names of modes.
    """
    visited = {mode.name: _Visited(mode.key) for mode in layout.modes}
    names = model.state_names

    def mode(name: Any) -> _Visited:
        return visited[str(name)]

    current = mode(run.location[0])
    monitor.point(current, float(run.t[0]), np.array([run[n][0] for n in names], dtype=float))
    stays = iter(run.segments)
    pending = next(stays, None)
    for j in range(len(run.jumps) + 1):
        while pending is not None and pending[0] == j:
            for curve, stop in _steps(pending[3], pending[2]):
                monitor.segment(current, curve, stop)
            pending = next(stays, None)
        if j < len(run.jumps):
            jump = run.jumps[j]
            current = mode(jump.target)
            monitor.point(current, jump.t, np.array([jump.after[n] for n in names], dtype=float))
    return monitor.results(run.termination.t)


@dataclass(frozen=True)
class _Visited:
    """A mode the run visited, as the monitor reads it (:class:`~hybrid.simulation.monitor.Keyed`)."""

    key: Mode


def _steps(stay: DenseSegment, end: float) -> Iterator[tuple[StepCurve, float | None]]:
    """The stay's accepted steps as curves; the last one cut at ``end`` (the stay's end)."""
    t_old, h = stay.t_old.tolist(), stay.h.tolist()
    last = len(t_old) - 1
    for k in range(last + 1):
        t0 = t_old[k]  # a step ends where the next begins (``t + h`` may differ by an ulp)
        t1 = t_old[k + 1] if k < last else t0 + h[k]
        curve = polynomial_curve(t0, t1, stay.y_old[k], stay.q[k])
        yield curve, (end if k == last and end != curve.t1 else None)
