"""Requirements of a system whose independent components are simulated apart.

:mod:`~hybrid.simulation.apart` runs each group of components that share no
label and read no signal of each other on its own, and merges the runs. A
requirement is monitored inside the run of the group it belongs to, exactly as
in a run of the whole system:

- a component's requirement, or a system file's requirement that reads (and is
  scoped to) one group only, is monitored in that group's run;
- a system file's requirement that reads state variables or signals of several
  groups (or is scoped to a location of another group) joins those groups:
  they are simulated together (:func:`join_groups`), never approximated.

The merged run can end before a group's own run does (another group ended
early, or the system's ``max_jumps`` was reached): the group's requirements
are then monitored again over its own run cut at the system's end, on the
interpolants the group kept (:func:`cut_results`), with the same samples and
the same rules as while it ran.

Examples
--------
>>> import hybrid
>>> ball = hybrid.load("specs/bouncing_ball.yaml")
>>> heater = hybrid.load_text('''
... automaton: heater
... state: {x: {initial: 20.0}}
... locations: {cooling: {flow: {x: -0.1*x}}}
... requirements: [{name: warm, always: "x >= 15"}]
... ''')
>>> run = hybrid.simulate(hybrid.compose(ball, heater), t_end=2.0)
>>> sorted(run.requirements), run.requirements["heater.warm"].holds
(['heater.warm'], True)
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from hybrid.compose import System
from hybrid.simulation.compiled import CompiledModel
from hybrid.simulation.dense import StepCurve
from hybrid.simulation.margins import margin_table, owners, watched_requirements
from hybrid.simulation.monitor import Monitor
from hybrid.simulation.result import RequirementResult, Run
from hybrid.simulation.settings import Settings

__all__ = ["cut_results", "join_groups", "with_group_requirements"]


def join_groups(system: System, groups: Sequence[tuple[int, ...]]) -> list[tuple[int, ...]]:
    """``groups`` with those a system requirement spans merged into one (sorted tuples)."""
    merged = [set(g) for g in groups]
    for w in watched_requirements(system):
        if w.component is not None:
            continue
        needed = owners(system, w)
        touched = [g for g in merged if g & needed]
        if len(touched) > 1:
            union = set().union(*touched)
            merged = [g for g in merged if not g & needed] + [union]
    return sorted(tuple(sorted(g)) for g in merged)


def with_group_requirements(system: System, sub: System) -> System:
    """``sub`` (a group of ``system``'s components) with the system requirements it owns."""
    members = {i for i, c in enumerate(system.components) if any(c is s for s in sub.components)}
    own = tuple(
        w.requirement
        for w in watched_requirements(system)
        if w.component is None and owners(system, w) <= members
    )
    return replace(sub, requirements=own) if own else sub


def cut_results(
    parts: Sequence[tuple[Run, CompiledModel]], merged: Run, settings: Settings
) -> dict[str, RequirementResult]:
    """The requirements of every group, each over its run cut at the end of ``merged``."""
    found: dict[str, RequirementResult] = {}
    t_stop = merged.termination.t
    taken = {(jump.t, jump.edge) for jump in merged.jumps}
    for run, compiled in parts:
        if not run.requirements:
            continue
        j_stop = sum(1 for jump in run.jumps if (jump.t, jump.edge) in taken)
        end = run.termination
        if (end.t, end.j) == (t_stop, j_stop):
            found.update(run.requirements)
        else:
            found.update(_replay(run, compiled, settings, t_stop, j_stop))
    return found


def _replay(
    run: Run, compiled: CompiledModel, settings: Settings, t_stop: float, j_stop: int
) -> dict[str, RequirementResult]:
    """Monitor ``run`` again up to hybrid time ``(t_stop, j_stop)``, on its kept interpolants."""
    table = margin_table(compiled)
    assert table is not None
    monitor = Monitor(table, settings)
    modes = {m.name: m for m in compiled._modes.values()}
    first: dict[int, int] = {}
    for k, j in enumerate(run.j.tolist()):
        first.setdefault(j, k)
    stays: dict[int, list[tuple[float, float, Any]]] = {}
    for j, t0, t1, solution in run.segments:
        stays.setdefault(j, []).append((t0, t1, solution))
    for j in range(j_stop + 1):
        k = first[j]
        mode = modes[str(run.location[k])]
        monitor.point(mode, float(run.t[k]), run.states[k])
        for t0, t1, solution in sorted(stays.get(j, []), key=lambda s: s[0]):
            end = min(t1, t_stop) if j == j_stop else t1
            ends = solution.ts
            for i, piece in enumerate(solution.interpolants):
                a, b = float(ends[i]), float(ends[i + 1])
                if b <= t0 or a >= end:
                    continue
                curve = _Curve(a, b, piece)
                monitor.segment(mode, curve, None if b <= end else end)
    return monitor.results(t_stop)


class _Curve(StepCurve):
    """A step of a kept interpolant (a scipy ``DenseOutput``) as the monitor reads a step."""

    __slots__ = ("dense",)

    def __init__(self, t0: float, t1: float, dense: Any) -> None:
        super().__init__(
            t0, t1, np.asarray(dense(t0), dtype=float), np.asarray(dense(t1), dtype=float)
        )
        self.dense = dense

    def at(self, t: float) -> np.ndarray:
        if t == self.t0:
            return self.x0
        if t == self.t1:
            return self.x1
        return np.asarray(self.dense(t), dtype=float)

    def many(self, ts: np.ndarray) -> np.ndarray:
        return np.asarray(self.dense(ts), dtype=float).reshape(len(self.x0), -1).T
