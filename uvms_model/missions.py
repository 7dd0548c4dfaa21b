"""Run the paper's two missions (and their ablations) from the specs, and measure them.

Every number the demo prints, the docs tabulate and the tests assert comes from
:func:`run_mission`: locations visited with entry times, minimum gamma, maximum
end-effector tracking error, and the largest jump of any joint or vehicle rate
at a switch (the paper's smoothness claim).

Examples
--------
>>> result = run_mission("uvms_mission_1")
>>> result.run.termination.cause, result.visited[0][0]
('t_end', 'q0')
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import hybrid

__all__ = [
    "ABLATIONS",
    "MISSIONS",
    "RATE_SIGNALS",
    "MissionResult",
    "run_mission",
    "specs_dir",
]

MISSIONS = ("uvms_mission_1", "uvms_mission_2")
RATE_SIGNALS = ("q1_rate", "q2_rate", "q3_rate_out", "x_rate", "y_rate", "phid")
"""Joint and vehicle rates whose continuity at switches is measured."""

ABLATIONS: Mapping[str, Mapping[str, float]] = {
    "both (the paper's strategy)": {},
    "FM only": {"uvms.switching": 0.0},
    "automaton only": {"uvms.fm_on": 0.0},
    "no strategy": {"uvms.fm_on": 0.0, "uvms.switching": 0.0},
}
"""Ablations: parameter overrides of the same specs."""


def specs_dir() -> Path:
    """The repository's ``specs/`` folder."""
    return Path(__file__).resolve().parent.parent / "specs"


@dataclass
class MissionResult:
    """A simulated mission and its measures."""

    name: str
    model: hybrid.Automaton | hybrid.System
    """The simulated model, parameters as overridden."""
    run: hybrid.Run
    wall_time: float
    visited: list[tuple[str, float]]
    """``(location of the uvms automaton, first entry time)``, in order."""
    min_gamma: float
    max_tracking_error: float
    max_rate_jump: float
    """Largest change of any rate in :data:`RATE_SIGNALS` across a jump."""

    @property
    def real_time_factor(self) -> float:
        return float(self.run.t[-1] - self.run.t[0]) / self.wall_time

    def summary(self) -> str:
        """The one-screen summary the demo prints."""
        term = self.run.termination
        lines = [
            f"{self.name}: {term.cause} at t={term.t:.2f} s, {len(self.run.jumps)} jumps, "
            f"wall {self.wall_time:.2f} s ({self.real_time_factor:.0f}x real time)",
            "  uvms locations entered: "
            + ", ".join(f"{loc} at {t:.2f} s" for loc, t in self.visited),
            f"  min gamma {self.min_gamma:.3f}   max end-effector error "
            f"{self.max_tracking_error * 1e3:.2e} mm   largest rate jump at a switch "
            f"{self.max_rate_jump:.1e}",
        ]
        return "\n".join(lines)


def run_mission(
    name: str,
    parameters: Mapping[str, float] | None = None,
    *,
    rtol: float = 1e-8,
    atol: float = 1e-10,
    dense: bool = False,
) -> MissionResult:
    """Load ``specs/<name>.yaml``, simulate 60 s and measure the result."""
    model = hybrid.load(specs_dir() / f"{name}.yaml", parameters=parameters)
    start = time.perf_counter()
    run = hybrid.simulate(model, t_end=60.0, rtol=rtol, atol=atol, dense=dense)
    wall = time.perf_counter() - start
    uvms_loc = np.array([loc.split("|")[0].split(".")[-1] for loc in run.location])
    visited: list[tuple[str, float]] = []
    for i, loc in enumerate(uvms_loc):
        if i == 0 or loc != uvms_loc[i - 1]:
            visited.append((str(loc), float(run.t[i])))
    same_t = (run.t[1:] == run.t[:-1]) & (run.j[1:] == run.j[:-1] + 1)
    jumps = [
        float(np.max(np.abs(run[c][1:][same_t] - run[c][:-1][same_t]), initial=0.0))
        for c in RATE_SIGNALS
    ]
    return MissionResult(
        name=name,
        model=model,
        run=run,
        wall_time=wall,
        visited=visited,
        min_gamma=float(np.min(run["gamma"])),
        max_tracking_error=float(np.max(run["tracking_error"])),
        max_rate_jump=max(jumps),
    )
