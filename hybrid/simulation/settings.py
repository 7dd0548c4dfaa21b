"""The settings of one simulation run, validated once, frozen.

Examples
--------
>>> s = Settings(t_end=10.0)
>>> s.method, s.rtol, s.max_step
('RK45', 1e-06, inf)
>>> Settings(t_end=-1.0)
Traceback (most recent call last):
...
hybrid.errors.UsageError: t_end must be a finite time after t_start=0.0, got -1.0
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

from hybrid.errors import UsageError

__all__ = ["BACKENDS", "MAX_JUMPS_PER_INSTANT", "METHODS", "Settings"]

METHODS = ("RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA")
"""The integration methods of :func:`scipy.integrate.solve_ivp` a run may use."""

BACKENDS = ("scipy", "compiled")
"""``scipy``: the solve_ivp engine (the reference); ``compiled``: hybrid.simulation.native."""

MAX_JUMPS_PER_INSTANT = 1000
"""Jumps allowed at one instant before a run ends as ``zeno`` (a zero-time cycle)."""


@dataclass(frozen=True)
class Settings:
    """How to integrate and when to stop; ``max_step`` is ``inf`` when not limited."""

    t_end: float
    t_start: float = 0.0
    max_jumps: int = 10_000
    rtol: float = 1e-6
    atol: float = 1e-9
    max_step: float = math.inf
    method: str = "RK45"
    dt: float | None = None
    dense: bool = False
    zeno: bool = True
    max_jumps_per_instant: int = MAX_JUMPS_PER_INSTANT
    backend: str = "scipy"

    def __post_init__(self) -> None:
        t0, t1 = self.t_start, self.t_end
        if not (math.isfinite(t0) and math.isfinite(t1)) or t1 <= t0:
            raise UsageError(f"t_end must be a finite time after t_start={t0}, got {t1}")
        if self.max_jumps < 0:
            raise UsageError(f"max_jumps must be >= 0, got {self.max_jumps}")
        for name in ("rtol", "atol"):
            if not getattr(self, name) > 0:
                raise UsageError(f"{name} must be > 0, got {getattr(self, name)}")
        if not self.max_step > 0:
            raise UsageError(f"max_step must be > 0, got {self.max_step}")
        if self.dt is not None and not self.dt > 0:
            raise UsageError(f"dt must be > 0, got {self.dt}")
        if self.method not in METHODS:
            raise UsageError(f"unknown method '{self.method}'; choose one of {', '.join(METHODS)}")
        if self.backend not in BACKENDS:
            raise UsageError(f"unknown backend '{self.backend}'; choose one of {', '.join(BACKENDS)}")

    @property
    def keeps_interpolants(self) -> bool:
        """Whether each stay's dense output is needed (a ``dt`` grid or ``dense=True``)."""
        return self.dt is not None or self.dense

    def as_dict(self) -> dict[str, Any]:
        """The settings as the events JSON records them (``max_step`` null when not limited)."""
        record = asdict(self)
        if math.isinf(self.max_step):
            record["max_step"] = None
        return record
