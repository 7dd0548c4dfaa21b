"""A run cut along hybrid time for drawing: stays, jumps and the columns of each component.

No matplotlib here: :mod:`hybrid.export.plot` draws what this module cuts.

A *stay* is the maximal stretch of stored points with one value of ``j`` (one
location of every component, between two jumps); a *jump* is a pair of
consecutive points where ``j`` grows by one at the same ``t`` (the pre-jump and
the post-jump row of the trajectory).

Examples
--------
>>> import hybrid
>>> run = hybrid.simulate(hybrid.load("specs/bouncing_ball.yaml"), t_end=3.0)
>>> [(s.j, s.location) for s in stays(run)]
[(0, 'falling'), (1, 'falling')]
>>> [bool(run.t[i] == run.t[i + 1]) for i in jump_rows(run)]
[True]
>>> views(run)[0].states
('h', 'v')
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from hybrid.errors import UsageError, did_you_mean
from hybrid.simulation.result import Run

__all__ = ["Stay", "View", "jump_rows", "stays", "views"]


@dataclass(frozen=True)
class Stay:
    """Points ``start:stop`` of a run, all at hybrid time ``j``, in ``location``."""

    j: int
    start: int
    stop: int
    location: str
    t0: float
    t1: float


@dataclass(frozen=True)
class View:
    """What one figure (or one section of a system's figure) shows.

    ``name`` is the model (an automaton) or the component; ``index`` is the
    component's position in a system's location names ``comp.loc|comp.loc``
    (``None`` for an automaton, whose location names are plain).
    """

    name: str
    index: int | None
    states: tuple[str, ...]
    signals: tuple[str, ...]

    def location(self, mode: str) -> str:
        """This component's location in a run's location name."""
        if self.index is None:
            return mode
        return mode.split("|")[self.index].removeprefix(f"{self.name}.")


def stays(run: Run, view: View | None = None) -> list[Stay]:
    """The stays of ``run`` in hybrid-time order (locations as ``view`` names them)."""
    n = len(run)
    if n == 0:
        return []
    breaks = np.flatnonzero(np.diff(run.j)) + 1
    starts = [0, *breaks.tolist()]
    stops = [*breaks.tolist(), n]
    out = []
    for start, stop in zip(starts, stops, strict=True):
        mode = str(run.location[start])
        out.append(
            Stay(
                int(run.j[start]),
                start,
                stop,
                view.location(mode) if view else mode,
                float(run.t[start]),
                float(run.t[stop - 1]),
            )
        )
    return out


def jump_rows(run: Run) -> NDArray[np.int64]:
    """Indices ``i`` where row ``i`` is a pre-jump point and row ``i + 1`` its post-jump point."""
    if len(run) < 2:
        return np.empty(0, dtype=np.int64)
    return np.flatnonzero((np.diff(run.j) == 1) & (np.diff(run.t) == 0)).astype(np.int64)


def views(run: Run, names: Sequence[str] = (), component: str | None = None) -> list[View]:
    """One :class:`View` per component of a system (one for an automaton).

    ``names`` keeps only those state variables and signals (a vector signal by
    its name keeps all its columns); ``component`` keeps only that component.
    Unknown names are a :class:`~hybrid.UsageError` naming the closest one.
    """
    columns = run.columns
    wanted: set[str] = set()
    for name in names:
        matches = [c for c in columns if c == name or c.split("[")[0] == name]
        if not matches:
            raise UsageError(f"no state variable or signal '{name}'{did_you_mean(name, columns)}")
        wanted.update(matches)
    groups = run.components or ((run.model, columns),)
    known = [g[0] for g in groups]
    if component is not None and component not in known:
        if not run.components:
            raise UsageError(f"component= applies to a system; {run.model} is an automaton")
        raise UsageError(
            f"no component '{component}' in {run.model}{did_you_mean(component, known)}"
            f" (components: {', '.join(known)})"
        )
    out = []
    for index, (name, cols) in enumerate(groups):
        if component is not None and name != component:
            continue
        keep = [c for c in cols if not wanted or c in wanted]
        if wanted and not keep:
            continue
        out.append(
            View(
                name,
                index if run.components else None,
                tuple(c for c in keep if c in run.state_names),
                tuple(c for c in keep if c not in run.state_names),
            )
        )
    return out
