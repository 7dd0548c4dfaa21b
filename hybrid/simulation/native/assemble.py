"""A :class:`~hybrid.simulation.result.Run` from the arrays a compiled run filled.

The counterpart of :meth:`hybrid.simulation.recorder.Recorder.run` (columns,
jumps, segments); the names come from the model's
:class:`~hybrid.simulation.native.layout.Layout`, the termination and its words
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
from hybrid.simulation.native.layout import Layout
from hybrid.simulation.native.structure import NativeModel
from hybrid.simulation.result import Jump, Run
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


def _jumps(layout: Layout, buf: b.RunArrays) -> list[Jump]:
    """The :class:`Jump` records of the run in ``buf``, equal to the reference engine's.

    Costs about as much as the compiled run of a short model, so it is kept
    lean: the columns become lists at once (one ``tolist``), the states' dicts
    are built in bulk (:func:`_state_dicts`), each jump's fields are a copy of
    its key's (:attr:`Layout.choices`: edge, label, modes, enabled transitions,
    ``chosen_by``, in field order; the key the loop packed in ``J_KEY``) with
    its time and states set, and are set at once (Jump is a frozen dataclass
    without slots, and its generated ``__init__`` costs an
    ``object.__setattr__`` per field).
    """
    n = int(buf.oi[b.I_JUMPS])
    if n == 0:
        return []
    names = layout.state_names
    x, y, z = b.J_X, b.J_X + len(names), b.J_X + 2 * len(names)
    rows = buf.jps[:n]
    width = rows.shape[1] - z
    columns = rows[:, :z].T.tolist()
    keys = columns[b.J_KEY] if layout.packed else layout.jump_keys(rows[:, b.J_TR], rows[:, z:])
    befores = _state_dicts(names, columns[x:y], n)
    afters = _state_dicts(names, columns[y:z], n)
    seen, fields_of = layout.choices, layout.fields
    new, set_field = object.__new__, object.__setattr__
    jumps: list[Jump] = []
    append = jumps.append
    for t, j, key, before, after in zip(columns[b.J_T], map(int, columns[b.J_J]), keys,
                                        befores, afters, strict=True):  # fmt: skip
        fields = (seen.get(key) or fields_of(key, width)).copy()
        fields["t"], fields["j"], fields["before"], fields["after"] = t, j, before, after
        jump = new(Jump)
        set_field(jump, "__dict__", fields)
        append(jump)
    return jumps


def _state_dicts(names: tuple[str, ...], columns: list[list[float]],
                 n: int) -> list[dict[str, float]]:  # fmt: skip
    """``dict(zip(names, row))`` per row of the ``n`` rows of ``columns`` (one list per name);
    for one or two names a dict display (a third of the cost)."""
    if len(names) == 1:
        (a,) = names
        return [{a: v} for v in columns[0]]
    if len(names) == 2:
        a, c = names
        return [{a: u, c: v} for u, v in zip(*columns, strict=True)]
    if not names:
        return [{} for _ in range(n)]
    return [dict(zip(names, row)) for row in zip(*columns, strict=True)]  # noqa: B905 (each row holds len(names) values)


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
        jumps=_jumps(layout, buf),
        termination=termination_of(native, layout, model, settings, buf, inputs),
        settings=settings_record(settings),
        segments=_segments(buf, d),
    )
