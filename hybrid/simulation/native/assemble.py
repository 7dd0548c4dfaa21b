"""A :class:`~hybrid.simulation.result.Run` from the arrays a compiled run filled.

The counterpart of :meth:`hybrid.simulation.recorder.Recorder.run` (columns,
jumps, segments); the names come from the model's
:class:`~hybrid.simulation.native.names.Layout`, the termination and its words
from :mod:`~hybrid.simulation.native.ending`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hybrid.compose import System
from hybrid.model import Automaton
from hybrid.simulation.native import buffers as b
from hybrid.simulation.native.ending import Inputs, termination_of
from hybrid.simulation.native.jumps import jump_records
from hybrid.simulation.native.names import Layout
from hybrid.simulation.native.structure import NativeModel
from hybrid.simulation.result import Run
from hybrid.simulation.settings import Settings

__all__ = ["DenseSegment", "run_from", "settings_record"]


class DenseSegment:
    """The interpolant of one stay: ``segment(t)`` is the state, shape ``(d,)`` or ``(d, n)``.

    Like scipy's ``OdeSolution`` over the stay's DOPRI5 steps.
    """

    def __init__(self, t_old: NDArray[np.float64], h: NDArray[np.float64],
                 y_old: NDArray[np.float64], q: NDArray[np.float64]) -> None:  # fmt: skip
        self.t_old, self.h, self.y_old, self.q = t_old, h, y_old, q

    def __call__(self, t: Any) -> NDArray[np.float64]:
        times = np.asarray(t, dtype=float)
        flat = np.atleast_1d(times)
        k = np.clip(np.searchsorted(self.t_old, flat, side="right") - 1, 0, self.t_old.size - 1)
        s = (flat - self.t_old[k]) / self.h[k]
        powers = np.stack([s, s * s, s**3, s**4])  # (4, n)
        y: NDArray[np.float64] = self.h[k] * np.einsum("nic,cn->in", self.q[k], powers) + self.y_old[k].T
        return y[:, 0] if times.ndim == 0 else y


def settings_record(settings: Settings) -> dict[str, Any]:
    """``settings.as_dict()`` without ``dataclasses.asdict``'s deep copy (flat fields only)."""
    record = dict(settings.__dict__)
    if math.isinf(settings.max_step):
        record["max_step"] = None
    return record


def _segments(buf: b.RunArrays, d: int) -> list[tuple[int, float, float, Any]]:
    n = int(buf.oi[b.I_STORED_STEPS])
    if n == 0:
        return []
    sts = buf.sts[:n]
    stays = sts[:, b.Q_STAY]
    starts = np.flatnonzero(np.r_[True, stays[1:] != stays[:-1]])
    ends = np.r_[starts[1:], n]
    segments = []
    for lo, hi in zip(starts.tolist(), ends.tolist(), strict=True):
        rows = sts[lo:hi]
        interpolant = DenseSegment(
            rows[:, b.Q_T0].copy(), rows[:, b.Q_H].copy(), rows[:, b.Q_Y : b.Q_Y + d].copy(),
            rows[:, b.Q_Y + d :].reshape(hi - lo, d, 4).copy(),
        )  # fmt: skip
        t0, t1 = float(rows[0, b.Q_T0]), float(rows[-1, b.Q_TV])
        segments.append((int(rows[0, b.Q_J]), t0, t1, interpolant))
    return segments


def run_from(
    native: NativeModel,
    layout: Layout,
    model: Automaton | System,
    settings: Settings,
    buf: b.RunArrays,
    inputs: Inputs = None,
) -> Run:
    """The :class:`Run` recorded in ``buf`` (one run's arrays) for ``model``."""
    n = int(buf.oi[b.I_POINTS])
    d = len(native.state_names)
    pts = buf.pts[:n]
    return Run(
        model=model.name,
        state_names=layout.state_names,
        signal_names=tuple(native.columns),
        t=pts[:, b.P_T].copy(),
        j=pts[:, b.P_J].astype(np.int64),
        location=layout.mode_names[pts[:, b.P_M].astype(np.int64)],
        states=pts[:, b.P_X : b.P_X + d].copy(),
        signals=pts[:, b.P_X + d :].copy(),
        jumps=jump_records(layout, buf),
        termination=termination_of(native, layout, model, settings, buf, inputs),
        settings=settings_record(settings),
        segments=_segments(buf, d),
    )
