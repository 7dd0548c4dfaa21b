"""A :class:`~hybrid.simulation.result.Run` from the arrays a compiled run filled.

The counterpart of :meth:`hybrid.simulation.recorder.Recorder.run` (columns,
jumps, segments) and of the messages :class:`hybrid.simulation.loop.EventLoop`
writes into a :class:`~hybrid.simulation.result.Termination`: the texts are
the same, so a user reads the same thing from either backend. An evaluation
failure is described by running the reference engine's compiled function at
the failing point (:func:`hybrid.simulation.failures.describe_failure`), so
the message names the expression and its arguments exactly as it does there.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hybrid.compose import System
from hybrid.model import Automaton
from hybrid.simulation.native import buffers as b
from hybrid.simulation.native.structure import NativeModel
from hybrid.simulation.result import Jump, Run, Termination
from hybrid.simulation.settings import Settings

__all__ = ["DenseSegment", "Layout", "run_from", "settings_record"]


@dataclass(frozen=True)
class Layout:
    """Names by index: modes, transitions (global order of the tables), invariants."""

    mode_names: NDArray[np.str_]
    transitions: tuple[tuple[int, int, Any], ...]
    """Per global transition: (source mode, place in its mode, NativeTransition)."""
    invariant_first: tuple[int, ...]
    """Per mode, the global index of its first invariant (as ``MODE_INV``)."""
    describe: tuple[tuple[str, str | None, str, str], ...]
    """Per global transition: its name, label, source and target mode names."""
    choices: dict[tuple[int, tuple[float, ...]], tuple[tuple[str, ...], str]]
    """Enabled names and ``chosen_by`` per (transition, enabled flags) seen so far."""
    modes: tuple[Any, ...]
    """The modes (:class:`~hybrid.simulation.native.structure.NativeMode`)."""

    @classmethod
    def of(cls, native: NativeModel) -> Layout:
        rows: list[tuple[int, int, Any]] = []
        first = [0]
        for m, mode in enumerate(native.modes):
            rows += [(m, k, tr) for k, tr in enumerate(mode.transitions)]
            first.append(first[-1] + len(mode.invariants))
        names = np.array([mode.name for mode in native.modes], dtype=np.str_)
        describe = tuple(
            (tr.view.name, tr.view.label, native.modes[m].name,
             native.modes[native.index[tr.view.target]].name)
            for m, _, tr in rows
        )  # fmt: skip
        return cls(names, tuple(rows), tuple(first), describe, {}, tuple(native.modes))

    def enabled(self, tr: int, flags: tuple[float, ...]) -> tuple[tuple[str, ...], str]:
        """The names of the transitions enabled with ``tr`` chosen, and how it was chosen."""
        key = (tr, flags)
        hit = self.choices.get(key)
        if hit is None:
            m, _, chosen = self.transitions[tr]
            mode = self.modes[m]
            on = [t for k, t in enumerate(mode.transitions) if flags[k]]
            if len(on) <= 1:
                how = "only"
            else:
                top = [t for t in on if t.view.priority == chosen.view.priority]
                how = "priority" if len(top) == 1 else "file order"
            hit = self.choices[key] = (tuple(t.view.name for t in on), how)
        return hit


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


def _jumps(native: NativeModel, layout: Layout, buf: b.RunArrays) -> list[Jump]:
    names = native.state_names
    d = len(names)
    n = int(buf.oi[b.I_JUMPS])
    rows = buf.jps[:n]
    times = rows[:, b.J_T].tolist()
    hybrid_times = rows[:, b.J_J].astype(np.int64).tolist()
    transitions = rows[:, b.J_TR].astype(np.int64).tolist()
    befores = rows[:, b.J_X : b.J_X + d].tolist()
    afters = rows[:, b.J_X + d : b.J_X + 2 * d].tolist()
    flags = rows[:, b.J_X + 2 * d :].tolist()
    jumps = []
    new, enabled_of, describe, seen = object.__new__, layout.enabled, layout.describe, layout.choices
    for t, j, tr, before, after, on in zip(
        times, hybrid_times, transitions, befores, afters, flags, strict=True
    ):
        key = (tr, tuple(on))
        enabled, how = seen.get(key) or enabled_of(*key)
        name, label, source, target = describe[tr]
        jump = new(Jump)
        # the fields set directly: Jump is a frozen dataclass without slots, and its
        # generated __init__ (one object.__setattr__ per field) costs as much as the run
        jump.__dict__.update(
            t=t, j=j, edge=name, label=label, source=source, target=target,
            before=dict(zip(names, before, strict=True)),
            after=dict(zip(names, after, strict=True)),
            enabled=enabled, chosen_by=how,
        )  # fmt: skip
        jumps.append(jump)
    return jumps


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
) -> Run:
    """The :class:`Run` recorded in ``buf`` (one run's arrays) for ``model``."""
    n = int(buf.oi[b.I_POINTS])
    d = len(native.state_names)
    pts = buf.pts[:n]
    return Run(
        model=model.name,
        state_names=tuple(native.state_names),
        signal_names=tuple(native.columns),
        t=pts[:, b.P_T].copy(),
        j=pts[:, b.P_J].astype(np.int64),
        location=layout.mode_names[pts[:, b.P_M].astype(np.int64)],
        states=pts[:, b.P_X : b.P_X + d].copy(),
        signals=pts[:, b.P_X + d :].copy(),
        jumps=_jumps(native, layout, buf),
        termination=termination_of(native, layout, model, settings, buf),
        settings=settings_record(settings),
        segments=_segments(buf, d),
    )


def termination_of(
    native: NativeModel,
    layout: Layout,
    model: Automaton | System,
    settings: Settings,
    buf: b.RunArrays,
) -> Termination:
    """How the run in ``buf`` ended, worded as the reference engine words it."""
    code = int(buf.oi[b.I_CAUSE])
    cause = b.CAUSE_CODES[code]
    t, j, m = float(buf.of[b.F_T]), int(buf.oi[b.I_J]), int(buf.oi[b.I_MODE])
    detail, index = int(buf.oi[b.I_DETAIL]), int(buf.oi[b.I_DETAIL_INDEX])
    mode = native.modes[m]
    zeno_time = float(buf.of[b.F_ZENO_TIME]) if cause == "zeno" else None
    if detail == b.D_INITIAL:
        message = "initial state is not finite"
    elif detail in (b.D_BLOCKED_ENTRY, b.D_BLOCKED_FLOW):
        how = "does not hold" if detail == b.D_BLOCKED_ENTRY else "is about to be left"
        message = f"invariant of {mode.invariants[index][0]} {how} and no transition is enabled"
    elif detail == b.D_STALL:
        message = (
            "events keep firing at the same instant without any transition "
            "becoming enabled (a guard touching its boundary?)"
        )
    elif detail == b.D_ZENO_INSTANT:
        name = layout.transitions[index][2].view.name
        message = (
            f"{settings.max_jumps_per_instant} jumps at the same instant: a cycle of "
            f"transitions takes no time (last: {name})"
        )
    elif detail == b.D_ZENO_GEOMETRIC:
        message = (
            "jumps accumulate (gaps shrink geometrically); estimated Zeno time "
            f"{zeno_time:.12g}"
        )
    elif detail == b.D_RESET_NONFINITE:
        message = f"reset of {layout.transitions[index][2].view.name} gave a non-finite state"
    elif detail in (b.D_EVAL, b.D_FLOW):
        fail_t = float(buf.of[b.F_FAIL_T])
        described = describe_native_failure(native, layout, model, buf)
        message = f"{described} (at t={fail_t:.9g})"
        if detail == b.D_FLOW:
            message += f"; the solution leaves the domain of the flow after t={t:.9g}"
        if detail == b.D_EVAL:
            t = fail_t
    elif detail in (b.D_STEP_TOO_SMALL, b.D_STATE_NONFINITE):
        n, d = int(buf.oi[b.I_POINTS]), len(native.state_names)
        peak = float(np.max(np.abs(buf.pts[n - 1, b.P_X : b.P_X + d]))) if n else math.nan
        what = (
            "Required step size is less than spacing between numbers."
            if detail == b.D_STEP_TOO_SMALL
            else "the solution is no longer finite."
        )
        message = (
            f"solver stopped: {what} (largest |state| {peak:.3g}; the solution may blow up "
            "here, or try tighter tolerances, or the scipy backend with another --method)"
        )
    elif cause == "t_end":
        message = "reached t_end"
    elif cause == "max_jumps":
        message = f"reached max_jumps={settings.max_jumps}"
    else:
        message = "interrupted by the user"
    return Termination(cause, t, j, message, zeno_time=zeno_time, location=mode.name)


def describe_native_failure(
    native: NativeModel, layout: Layout, model: Automaton | System, buf: b.RunArrays
) -> str:
    """``<what> failed: <call(args)>: <error>``, found by the reference engine's functions."""
    from hybrid.simulation.compiled import CompiledModel
    from hybrid.simulation.failures import describe_failure

    kind, index = int(buf.oi[b.I_FAIL_KIND]), int(buf.oi[b.I_FAIL_INDEX])
    m = int(buf.oi[b.I_FAIL_MODE])
    t = float(buf.of[b.F_FAIL_T])
    x = np.array(buf.of[b.N_OUT_F : b.N_OUT_F + len(native.state_names)], dtype=float)
    compiled = CompiledModel(model)
    mode = compiled.mode(native.modes[m].key)
    what, call = _reference_function(kind, index, m, mode, layout)
    call(t, x)
    for failure in (compiled.failure, compiled.flow_failure):
        if failure.error is not None:
            return describe_failure(compiled, failure)
    return f"{what} gave a non-finite value"


def _reference_function(kind: int, index: int, m: int, mode: Any, layout: Layout) -> Sequence[Any]:
    if kind == b.F_GUARD:
        k = layout.transitions[index][1]
        return f"the guard of {mode.transitions[k].name}", mode.transitions[k].rho
    if kind == b.F_INVARIANT:
        inv = mode.invariants[index - layout.invariant_first[m]]
        return f"the invariant of {inv.name}", inv.rho
    if kind == b.F_RESET:
        k = layout.transitions[index][1]
        return f"the reset of {mode.transitions[k].name}", mode.transitions[k].reset
    if kind == b.F_SIGNALS:
        return f"the signals of {mode.name}", mode.outputs
    return f"the flow of {mode.name}", mode.rhs
