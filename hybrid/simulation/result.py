"""What a simulation returns: the hybrid trajectory, its jumps and how it ended.

Examples
--------
>>> import hybrid
>>> run = hybrid.simulate(hybrid.load("specs/bouncing_ball.yaml"), t_end=2.0)
>>> run.termination.cause, len(run.jumps)
('t_end', 1)
>>> bool(run.j[-1] == 1), run["h"].shape == run.t.shape
(True, True)
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["CAUSES", "Jump", "Run", "Termination"]

CAUSES = ("t_end", "max_jumps", "zeno", "blocked", "nonfinite", "solver_failure", "interrupted")
"""Every way a run can end; only ``t_end`` is a normal end."""


@dataclass(frozen=True)
class Jump:
    """One discrete transition: at time ``t``, from hybrid time ``j`` to ``j + 1``.

    ``enabled`` lists every transition enabled at that instant and ``chosen_by``
    says how this one was picked (``only``, ``priority`` or ``file order``).
    """

    t: float
    j: int
    edge: str
    label: str | None
    source: str
    target: str
    before: Mapping[str, float]
    after: Mapping[str, float]
    enabled: tuple[str, ...] = ()
    chosen_by: str = "only"

    def as_dict(self) -> dict[str, Any]:
        return {
            "t": self.t,
            "j": self.j,
            "edge": self.edge,
            "label": self.label,
            "source": self.source,
            "target": self.target,
            "before": dict(self.before),
            "after": dict(self.after),
            "enabled": list(self.enabled),
            "chosen_by": self.chosen_by,
        }


@dataclass(frozen=True)
class Termination:
    """How and where (``t``, ``j``) a run ended."""

    cause: str
    t: float
    j: int
    message: str
    zeno_time: float | None = None
    location: str | None = None

    @property
    def ok(self) -> bool:
        return self.cause == "t_end"

    def as_dict(self) -> dict[str, Any]:
        return {
            "cause": self.cause,
            "t": self.t,
            "j": self.j,
            "message": self.message,
            "zeno_time": self.zeno_time,
            "location": self.location,
        }


@dataclass
class Run:
    """A hybrid trajectory: one entry per stored point, two points per jump.

    ``run.t``, ``run.j`` and ``run.location`` are arrays; ``run["name"]`` is the
    column of a state variable or signal.
    """

    model: str
    state_names: tuple[str, ...]
    signal_names: tuple[str, ...]
    t: NDArray[np.float64]
    j: NDArray[np.int64]
    location: NDArray[np.str_]
    states: NDArray[np.float64]
    signals: NDArray[np.float64]
    jumps: list[Jump]
    termination: Termination
    settings: dict[str, Any] = field(default_factory=dict)
    segments: list[tuple[int, float, float, Any]] = field(default_factory=list, repr=False)
    """With ``dense=True``: ``(j, t0, t1, interpolant)`` per stay in a mode."""

    def __getitem__(self, name: str) -> NDArray[np.float64]:
        if name in self.state_names:
            return self.states[:, self.state_names.index(name)]
        if name in self.signal_names:
            return self.signals[:, self.signal_names.index(name)]
        from difflib import get_close_matches

        close = get_close_matches(name, [*self.state_names, *self.signal_names], n=1)
        hint = f"; did you mean '{close[0]}'?" if close else ""
        raise KeyError(f"no state variable or signal '{name}'{hint}")

    def __len__(self) -> int:
        return int(self.t.shape[0])

    @property
    def columns(self) -> tuple[str, ...]:
        return (*self.state_names, *self.signal_names)

    @property
    def jump_times(self) -> NDArray[np.float64]:
        return np.array([jump.t for jump in self.jumps], dtype=float)
