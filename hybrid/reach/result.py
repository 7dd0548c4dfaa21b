"""What :func:`hybrid.reach` returns: sets, verdicts per forbidden entry, hull, plot, files.

Examples
--------
>>> import hybrid
>>> m = hybrid.load_text('''
... automaton: decay
... state: {x: {initial: [1, 2]}}
... locations: {l: {flow: {x: -x}}}
... properties: {forbidden: [{when: x > 2.5}]}
... ''')
>>> r = hybrid.reach(m, t_end=1.0, step=0.01)
>>> r.verdict, r.variables, len(r.sets)
('proved', ('x',), 101)
>>> lo, hi = r.hull()
>>> bool(lo[0] <= 2.0 * 2.718281828 ** -1.0 <= 1.0 and 2.0 <= hi[0] < 2.01)
True
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, BinaryIO

import numpy as np
from numpy.typing import NDArray

from hybrid.compose import System
from hybrid.errors import Position, UsageError
from hybrid.model import Automaton, Forbidden
from hybrid.reach.affine import Condition
from hybrid.reach.engine import ReachSet
from hybrid.simulation.result import Run

__all__ = ["VERDICTS", "PropertyResult", "ReachResult", "ReachSet"]

Array = NDArray[np.float64]
VERDICTS = ("proved", "unknown", "refuted")
"""Verdicts from best to worst (the result's verdict is the worst of its entries')."""


@dataclass(frozen=True)
class PropertyResult:
    """The verdict on one ``properties.forbidden`` entry.

    ``first_contact`` is the earliest time a set meets the entry (``None``: none
    does, or no sets were computed); ``witness`` a simulated run that reaches it
    (refuted only), entering at ``witness_time``, from ``witness_initial`` with
    ``witness_inputs``. A refutation found by exact propagation
    (:mod:`hybrid.reach.falsify`) holds ``replay`` instead of the run: ``witness``
    simulates it on first access (its time was found without a simulation).
    """

    entry: Forbidden
    verdict: str
    message: str
    first_contact: float | None = None
    simulated: Run | None = field(default=None, repr=False)
    witness_time: float | None = None
    witness_initial: dict[str, float] = field(default_factory=dict, repr=False)
    witness_inputs: dict[str, Any] = field(default_factory=dict, repr=False)
    witness_location: str | dict[str, str] | None = None
    """Where the witness starts: its initial location (a name per component in a system)."""
    condition: Condition = field(default=(), repr=False)
    replay: Callable[[], Run | None] | None = field(default=None, repr=False, compare=False)

    @property
    def witness(self) -> Run | None:
        """The witness run (refuted only), simulated on first access if it was not yet."""
        if self.simulated is None and self.replay is not None:
            object.__setattr__(self, "simulated", self.replay())
            object.__setattr__(self, "replay", None)
        return self.simulated

    @property
    def position(self) -> Position:
        return self.entry.position

    def as_dict(self) -> dict[str, Any]:
        return {
            "entry": self.entry.text(),
            "position": str(self.entry.position),
            "verdict": self.verdict,
            "message": self.message,
            "first_contact": self.first_contact,
            "witness_time": self.witness_time,
            "witness_initial": self.witness_initial or None,
            "witness_location": self.witness_location,
        }


@dataclass(frozen=True)
class ReachResult:
    """Sets of the states reached, and a verdict per forbidden entry.

    ``complete`` is ``False`` when the search stopped before exhausting the
    horizon and jump bound (too many flowpipes): nothing is then proved.
    ``jump_bound_from`` is the earliest time a run may take a jump past
    ``max_jumps`` (``None``: none can before ``t_end``): the sets, and what is
    proved, leave out what such a run does after it.
    """

    model: str
    variables: tuple[str, ...]
    sets: tuple[ReachSet, ...] = field(repr=False)
    properties: tuple[PropertyResult, ...]
    t_end: float
    max_jumps: int
    step: float
    complete: bool = True
    jump_bound_from: float | None = None
    seconds: float = 0.0
    file: str = "<spec>"
    source: Automaton | System | None = field(default=None, repr=False, compare=False)
    """The model reached (the picture simulates its nominal run)."""

    @property
    def verdict(self) -> str:
        """The worst verdict over the entries (``proved`` with none)."""
        worst = 0
        for p in self.properties:
            worst = max(worst, VERDICTS.index(p.verdict))
        return VERDICTS[worst]

    @property
    def jump_past_bound(self) -> str:
        """``"jump 11 may come from t = 32.44 on"`` when a run may jump past ``max_jumps``
        before ``t_end`` (what the sets leave out), else ``""``: what the command line's
        summary and check's bounded ``ok`` say of it."""
        if self.jump_bound_from is None:
            return ""
        return f"jump {self.max_jumps + 1} may come from t = {self.jump_bound_from:.4g} on"

    def hull(self, location: str | None = None) -> tuple[Array, Array]:
        """``(lo, hi)`` over all sets (of ``location`` only, if given)."""
        chosen = [s for s in self.sets if location is None or s.location == location]
        if not chosen:
            raise UsageError(
                f"no set of location '{location}'" if location else "no set was reached"
            )
        return (
            np.min(np.stack([s.lo for s in chosen]), axis=0),
            np.max(np.stack([s.hi for s in chosen]), axis=0),
        )

    def as_dict(self) -> dict[str, Any]:
        """The result without its sets (see :meth:`write_sets`)."""
        return {
            "model": self.model,
            "verdict": self.verdict,
            "complete": self.complete,
            "t_end": self.t_end,
            "max_jumps": self.max_jumps,
            "jump_bound_from": self.jump_bound_from,
            "step": self.step,
            "sets": len(self.sets),
            "seconds": round(self.seconds, 6),
            "properties": [p.as_dict() for p in self.properties],
        }

    def write_sets(self, target: str | Path | BinaryIO, fmt: str | None = None) -> None:
        """Write every set (location, time interval, box hull) as ``json`` or ``npz``.

        ``target`` is a path (the format from its suffix unless given) or a binary file.
        """
        if fmt is None:
            fmt = (
                Path(str(target)).suffix.lower().lstrip(".")
                if isinstance(target, str | Path)
                else "json"
            )
        if fmt not in ("json", "npz"):
            raise UsageError(f"sets are written as .json or .npz, not '{fmt}'")
        if isinstance(target, str | Path):
            from hybrid.files import atomic_write  # whole or not at all

            with atomic_write(target) as handle:
                self.write_sets(handle, fmt)
            return
        if not hasattr(target, "write"):
            raise UsageError(f"sets are written to a path or a binary file, got {target!r}")
        n = len(self.variables)
        if fmt == "npz":
            np.savez_compressed(
                target,
                variables=np.array(self.variables, dtype=str),
                location=np.array([s.location for s in self.sets], dtype=str),
                t=np.array([s.t for s in self.sets], dtype=float).reshape(-1, 2),
                lo=np.array([s.lo for s in self.sets], dtype=float).reshape(-1, n),
                hi=np.array([s.hi for s in self.sets], dtype=float).reshape(-1, n),
            )
            return
        document = {
            "model": self.model,
            "variables": list(self.variables),
            "sets": [
                {"location": s.location, "t": list(s.t), "lo": s.lo.tolist(), "hi": s.hi.tolist()}
                for s in self.sets
            ],
        }
        target.write((json.dumps(document) + "\n").encode("utf-8"))

    def plot(self, x: str, y: str, *, ax: Any = None, runs: Sequence[Run] = ()) -> Any:
        """Draw the sets projected on ``(x, y)`` (``t`` allowed), runs over them, the forbidden sets.

        ``runs`` (default: the model's nominal run) are drawn in black, witnesses
        in red, forbidden cases that read only ``x`` and ``y`` shaded in red.
        Needs matplotlib (the ``plot`` extra). Returns the matplotlib Axes.
        """
        from hybrid.reach.picture import draw

        return draw(self, x, y, ax=ax, runs=runs)
