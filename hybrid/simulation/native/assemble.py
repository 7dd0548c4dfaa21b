"""A :class:`~hybrid.simulation.result.Run` from the arrays a compiled run filled.

The counterpart of :meth:`hybrid.simulation.recorder.Recorder.run` (columns, jumps,
segments), in four parts.

**Names by index** (:class:`Layout`). The compiled loop records modes, transitions and
invariants by number, and a jump by its transition and the flags of the transitions
enabled with it (packed into one key, ``J_KEY``); :class:`Layout` turns these back into
the names and words of the reference engine's :class:`~hybrid.simulation.result.Jump`.

**Jumps kept in arrays** (:class:`JumpRecords`). A
:class:`~hybrid.simulation.result.Jump` is a frozen dataclass with two dicts of states:
about a kilobyte each, ten times its numbers, and building the records of a short run
cost about half of its compiled loop. A compiled :class:`~hybrid.simulation.result.Run`
holds :class:`JumpRecords` instead: a read-only sequence over the arrays the loop filled
(copied out), equal to the list of records the reference engine builds, whose items are
built on access (``run.jumps[k]``, iterating); ``run.jump_times`` reads its array.

**How the run ended** (:func:`termination_of`), worded as the reference engine words it.
The counterpart of the messages :class:`hybrid.simulation.loop.EventLoop` writes into a
:class:`~hybrid.simulation.result.Termination`: the texts are the same, so a user reads
the same thing from either backend. An evaluation failure is described by running the
reference engine's compiled function at the failing point
(:func:`hybrid.simulation.failures.describe_failure`), so the message names the
expression and its arguments exactly as it does there.

**The run** (:func:`run_from`): the columns, the jumps, the segments and the settings
record.

Examples
--------
>>> import hybrid
>>> from pathlib import Path
>>> ball = hybrid.load(Path("specs/bouncing_ball.yaml"))
>>> run = hybrid.simulate(ball, t_end=5.0, backend="compiled", handle_sigint=False)
>>> jumps = run.jumps
>>> len(jumps), jumps[0].edge, round(jumps[0].t, 6), jumps[-1] == list(jumps)[-1]
(2, 'bounce', 1.427843, True)
"""

from __future__ import annotations

import math
from collections.abc import Callable, Hashable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, overload

import numpy as np
from numpy.typing import NDArray

from hybrid.compose import System
from hybrid.simulation.bounds import Extremes
from hybrid.simulation.native import buffers as b
from hybrid.simulation.native.structure import NativeModel
from hybrid.simulation.result import Jump, Run, Termination
from hybrid.simulation.settings import Settings

__all__ = [
    "PACKED_WIDTH",
    "DenseSegment",
    "Inputs",
    "JumpFields",
    "JumpRecords",
    "Layout",
    "RecordedRun",
    "describe_native_failure",
    "jump_records",
    "run_from",
    "settings_record",
    "termination_of",
]


JumpFields = dict[str, Any]
"""A :class:`Jump`'s fields in order, ``t``, ``j``, ``before`` and ``after`` to be filled in."""

PACKED_WIDTH = b.PACKED_WIDTH
"""Most transitions a mode may have for a jump's enabled flags to be packed into an int key."""


@dataclass(frozen=True)
class Layout:
    """Names by index: modes, transitions (global order of the tables), invariants."""

    mode_names: NDArray[np.object_]
    transitions: tuple[tuple[int, int, Any], ...]
    """Per global transition: (source mode, place in its mode, NativeTransition)."""
    invariant_first: tuple[int, ...]
    """Per mode, the global index of its first invariant (as ``MODE_INV``)."""
    describe: tuple[tuple[str, str | None, str, str], ...]
    """Per global transition: its name, label, source and target mode names."""
    choices: dict[Hashable, JumpFields]
    """The fields of a jump but its time and states, per :meth:`jump_keys` key seen so far."""
    modes: tuple[Any, ...]
    """The modes (:class:`~hybrid.simulation.native.structure.NativeMode`)."""
    state_names: tuple[str, ...]
    bits: NDArray[np.int64]
    """``1 << k`` for each flag column of a jump (as many as a mode has transitions, at most
    :data:`PACKED_WIDTH`)."""
    packed: bool
    """Whether the compiled loop's ``J_KEY`` holds each jump's key exactly (at most
    :data:`PACKED_WIDTH` flag columns, and every key below ``2**53``)."""

    @classmethod
    def of(cls, native: NativeModel) -> Layout:
        rows: list[tuple[int, int, Any]] = []
        first = [0]
        for m, mode in enumerate(native.modes):
            rows += [(m, k, tr) for k, tr in enumerate(mode.transitions)]
            first.append(first[-1] + len(mode.invariants))
        names = np.array([mode.name for mode in native.modes], dtype=object)
        describe = tuple(
            (tr.view.name, tr.view.label, native.modes[m].name,
             native.modes[native.index[tr.view.target]].name)
            for m, _, tr in rows
        )  # fmt: skip
        width = max(1, *(len(mode.transitions) for mode in native.modes))  # jps' flag columns
        bits = np.left_shift(1, np.arange(min(width, PACKED_WIDTH), dtype=np.int64))
        packed = width <= PACKED_WIDTH and len(rows) << width <= 1 << 53
        return cls(names, tuple(rows), tuple(first), describe, {}, tuple(native.modes),
                   tuple(native.state_names), bits, packed)  # fmt: skip

    def enabled(self, tr: int, flags: bytes) -> tuple[tuple[str, ...], str]:
        """The names of the transitions enabled with ``tr`` chosen, and how it was chosen."""
        m, _, chosen = self.transitions[tr]
        mode = self.modes[m]
        on = [t for k, t in enumerate(mode.transitions) if flags[k]]
        if len(on) <= 1:
            how = "only"
        else:
            top = [t for t in on if t.view.priority == chosen.view.priority]
            how = "priority" if len(top) == 1 else "file order"
        return tuple(t.view.name for t in on), how

    def jump_keys(self, transitions: NDArray[np.float64], flags: NDArray[np.float64]) -> list[Any]:
        """A key per jump for :attr:`choices` from its transition and enabled flags (a row each):
        up to :data:`PACKED_WIDTH` flags, ``tr << width`` plus bit ``k`` per enabled ``k``;
        beyond, ``(tr, flags as bytes)``."""
        on = flags != 0.0
        tr = transitions.astype(np.int64)
        width = on.shape[1]
        if width <= PACKED_WIDTH:
            bits = self.bits if self.bits.size == width else np.left_shift(1, np.arange(width))
            return ((tr << width) | (on.astype(np.int64) @ bits)).tolist()  # type: ignore[no-any-return]
        data = on.astype(np.uint8).tobytes()
        return [(t, data[k * width : (k + 1) * width]) for k, t in enumerate(tr.tolist())]

    def fields(self, key: Any, width: int) -> JumpFields:
        """The fields of a jump of a :meth:`jump_keys` key (or the loop's ``J_KEY``, a float)
        but its time and states (None)."""
        if isinstance(key, (int, float)):
            packed = int(key)
            tr, flags = packed >> width, bytes((packed >> k) & 1 for k in range(width))
        else:
            tr, flags = key
        edge, label, source, target = self.describe[tr]
        enabled, how = self.enabled(tr, flags)
        found = self.choices[key] = {
            "t": None, "j": None, "edge": edge, "label": label, "source": source, "target": target,
            "before": None, "after": None, "enabled": enabled, "chosen_by": how,
        }  # fmt: skip
        return found


class JumpRecords(Sequence[Jump]):
    """The jumps of one compiled run, as arrays; a :class:`Jump` per item on access.

    It keeps the rows the loop filled (one copy: time, hybrid time, transition,
    key, state before and after, enabled flags) and reads its columns when asked.
    Compares equal to a list of the same jumps (and to another such sequence);
    pickles as that list.
    """

    __slots__ = ("_d", "_layout", "_rows")

    def __init__(self, layout: Layout, rows: NDArray[np.float64], d: int) -> None:
        self._layout, self._rows, self._d = layout, rows, d

    @property
    def times(self) -> NDArray[np.float64]:
        """The jump times (a copy)."""
        return self._rows[:, b.J_T].copy()

    def __len__(self) -> int:
        return int(self._rows.shape[0])

    @overload
    def __getitem__(self, index: int) -> Jump: ...

    @overload
    def __getitem__(self, index: slice) -> list[Jump]: ...

    def __getitem__(self, index: int | slice) -> Jump | list[Jump]:
        if isinstance(index, slice):
            rows = range(len(self))[index]
            return self._build(rows) if rows.step == 1 else self._build(range(len(self)))[index]
        n = len(self)
        k = index + n if index < 0 else index
        if not 0 <= k < n:
            raise IndexError("jump index out of range")
        return self._build(range(k, k + 1))[0]

    def __iter__(self) -> Iterator[Jump]:
        return iter(self._build(range(len(self))))

    def __eq__(self, other: object) -> bool:
        if isinstance(other, JumpRecords) or type(other) is list:
            return list(self) == list(other)
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]

    def __add__(self, other: Sequence[Jump]) -> list[Jump]:
        return [*self, *other]

    def __radd__(self, other: Sequence[Jump]) -> list[Jump]:
        return [*other, *self]

    def __repr__(self) -> str:
        return repr(list(self))

    def __reduce__(self) -> tuple[Any, ...]:
        return (list, (list(self),))

    def _build(self, rows: range) -> list[Jump]:
        """The records of ``rows`` (consecutive): fields copied from each key's, set at once.

        Jump is a frozen dataclass without slots, and its generated ``__init__``
        costs an ``object.__setattr__`` per field; the states' dicts are built in bulk.
        """
        if not rows:
            return []
        lo, hi = rows.start, rows.stop
        layout, names, d = self._layout, self._layout.state_names, self._d
        block = self._rows[lo:hi]
        x, y, z = b.J_X, b.J_X + d, b.J_X + 2 * d
        width = block.shape[1] - z
        if layout.packed:
            keys: Any = block[:, b.J_KEY].tolist()
        else:
            keys = layout.jump_keys(block[:, b.J_TR], block[:, z:])
        befores = _state_dicts(names, block[:, x:y].T.tolist(), hi - lo)
        afters = _state_dicts(names, block[:, y:z].T.tolist(), hi - lo)
        seen, fields_of = layout.choices, layout.fields
        new, set_field = object.__new__, object.__setattr__
        jumps: list[Jump] = []
        append = jumps.append
        for t, j, key, before, after in zip(block[:, b.J_T].tolist(),
                                            block[:, b.J_J].astype(np.int64).tolist(),
                                            keys, befores, afters, strict=True):  # fmt: skip
            fields = (seen.get(key) or fields_of(key, width)).copy()
            fields["t"], fields["j"], fields["before"], fields["after"] = t, j, before, after
            jump = new(Jump)
            set_field(jump, "__dict__", fields)
            append(jump)
        return jumps


def jump_records(layout: Layout, buf: b.RunArrays) -> JumpRecords:
    """The jumps of the run in ``buf`` (one run's arrays), copied out of it (one copy)."""
    return JumpRecords(layout, buf.jps[: int(buf.oi[b.I_JUMPS])].copy(), len(layout.state_names))


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


Inputs = Mapping[str, Callable[[float], float]] | None
"""The reference engine's inputs of a model (to word a failure as the reference does)."""


def termination_of(
    native: NativeModel,
    layout: Layout,
    model: System,
    settings: Settings,
    buf: b.RunArrays,
    inputs: Inputs = None,
    read: tuple[list[int], list[float]] | None = None,
) -> Termination:
    """How the run in ``buf`` ended, worded as the reference engine words it.

    A plain end (``t_end``, ``max_jumps``, ``interrupted``) where the last run
    of the same model ended is that run's record again (it is frozen): a
    repeated run builds none. ``read``: ``buf.oi`` and ``buf.of`` as lists, if
    the caller has read them.
    """
    oi, of = (buf.oi.tolist(), buf.of.tolist()) if read is None else read  # read at once
    detail = oi[b.I_DETAIL]
    if detail == b.D_NONE:
        t = of[b.F_T]
        key = (oi[b.I_CAUSE], t, math.copysign(1.0, t), oi[b.I_J], oi[b.I_MODE],
               settings.max_jumps)  # fmt: skip
        last = _LAST_END[0]
        if last is not None and last[0] is native and last[1] == key:
            return last[2]
        plain = _termination(native, layout, model, settings, buf, inputs, oi, of)
        _LAST_END[0] = (native, key, plain)  # one tuple, replaced at once
        return plain
    return _termination(native, layout, model, settings, buf, inputs, oi, of)


_LAST_END: list[tuple[NativeModel, tuple[Any, ...], Termination] | None] = [None]
"""The last plain end: its model structure, key (cause, t and its sign, j, mode, max_jumps) and
record."""


def _termination(native: NativeModel, layout: Layout, model: System,
                 settings: Settings, buf: b.RunArrays, inputs: Inputs, oi: list[int],
                 of: list[float]) -> Termination:  # fmt: skip
    """:func:`termination_of` from ``buf``'s counts and numbers read as ``oi`` and ``of``."""
    cause = b.CAUSE_CODES[oi[b.I_CAUSE]]
    t, j, m = of[b.F_T], oi[b.I_J], oi[b.I_MODE]
    detail, index = oi[b.I_DETAIL], oi[b.I_DETAIL_INDEX]
    mode = native.modes[m]
    zeno_time = of[b.F_ZENO_TIME] if cause == "zeno" else None
    if detail == b.D_INITIAL:
        message = "initial state is not finite"
    elif detail in (b.D_BLOCKED_ENTRY, b.D_BLOCKED_FLOW):
        how = "does not hold" if detail == b.D_BLOCKED_ENTRY else "is about to be left"
        message = f"invariant of {mode.invariants[index][0]} {how} and no transition is enabled"
    elif detail == b.D_URGENT:
        message = (
            f"urgent location {', '.join(mode.urgent)}: no time may pass there and no "
            "transition is enabled"
        )
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
        described = describe_native_failure(native, layout, model, buf, inputs)
        if described is None:
            what = _reference_function(int(buf.oi[b.I_FAIL_KIND]), int(buf.oi[b.I_FAIL_INDEX]),
                                       int(buf.oi[b.I_FAIL_MODE]), None, layout, native)[0]  # fmt: skip
            described = f"{what} gave a non-finite value"
        message = f"{described} (at t={fail_t:.9g})"
        if detail == b.D_FLOW:
            message += f"; the solution leaves the domain of the flow after t={t:.9g}"
        if detail == b.D_EVAL:
            t = fail_t
    elif detail in (b.D_STEP_TOO_SMALL, b.D_STATE_NONFINITE, b.D_NOT_ADVANCING):
        message = _gave_up_message(detail, t, settings, float(buf.of[b.F_PEAK]))
    elif detail == b.D_CRAWL:
        message = _crawl_message(settings, t, buf)
    elif detail == b.D_FLOW_START:
        message = _flow_at_start(native, layout, model, buf, index, inputs)
    elif cause == "t_end":
        message = "reached t_end"
    elif cause == "max_jumps":
        message = f"reached max_jumps={settings.max_jumps}"
    else:
        message = "interrupted by the user"
    return Termination(cause, t, j, message, zeno_time=zeno_time, location=mode.name)


def _gave_up_message(detail: int, t: float, settings: Settings, peak: float) -> str:
    """The message of a stay whose integrator gave up (the reference's words)."""
    from hybrid.simulation.stay import solver_advice

    advice = solver_advice(t, settings, peak)
    if detail == b.D_NOT_ADVANCING:
        return (
            "solver stopped advancing: its step size fell below the spacing of floating-point "
            f"numbers at t={t:.9g} ({advice})"
        )
    why = (
        "solver stopped: Required step size is less than spacing between numbers."
        if detail == b.D_STEP_TOO_SMALL
        else "the state became non-finite"
    )
    return f"{why} ({advice})"


def _crawl_message(settings: Settings, t: float, buf: b.RunArrays) -> str:
    """``StayIntegrator._crawled``'s words."""
    from hybrid.simulation.stay import CRAWL_STEPS

    pace, longest = float(buf.of[b.F_AUX0]), float(buf.of[b.F_AUX1])
    remaining = (settings.t_end - t) / pace
    return (
        f"solver crawls: its last {CRAWL_STEPS} steps averaged {pace:.3g} (it took steps of "
        f"{longest:.3g} before), so t_end is still {remaining:.2g} steps away (largest "
        f"|state| {float(buf.of[b.F_PEAK]):.3g}); the solution may near a singularity here (a "
        "derivative without bound) and chatter across it"
    )


def _flow_at_start(native: NativeModel, layout: Layout, model: System,
                   buf: b.RunArrays, index: int, inputs: Inputs) -> str:  # fmt: skip
    """``StayIntegrator._start``'s words for a flow that fails or is not finite at the start."""
    t = float(buf.of[b.F_FAIL_T])
    described = describe_native_failure(native, layout, model, buf, inputs)
    if described is not None:
        return f"{described} (at t={t:.9g})"
    x = np.array(buf.of[b.N_OUT_F : b.N_OUT_F + len(native.state_names)], dtype=float)
    mode = native.modes[int(buf.oi[b.I_FAIL_MODE])]
    derivative = _reference_mode(native, model, int(buf.oi[b.I_FAIL_MODE]), inputs)[1].rhs(t, x)
    names = native.state_names
    bad = next((k for k, v in enumerate(derivative) if not math.isfinite(v)), index)
    return f"the flow of {mode.name} gives {names[bad]}' = {derivative[bad]} (at t={t:.9g})"


def _reference_mode(native: NativeModel, model: System, m: int,
                    inputs: Inputs) -> tuple[Any, Any]:  # fmt: skip
    """The reference engine's compiled model and its mode ``m`` (for the words of a failure)."""
    from hybrid.simulation.compiled import CompiledModel
    from hybrid.simulation.start import run_inputs

    compiled = CompiledModel(model, run_inputs(model, inputs))
    return compiled, compiled.mode(native.modes[m].key)


def describe_native_failure(native: NativeModel, layout: Layout, model: System,
                            buf: b.RunArrays, inputs: Inputs = None) -> str | None:  # fmt: skip
    """``<what> failed: <call(args)>: <error>``, found by the reference engine's functions.

    None if the reference's function does not fail at that point (a value that
    is not finite without an error).
    """
    from hybrid.simulation.failures import describe_failure

    kind, index = int(buf.oi[b.I_FAIL_KIND]), int(buf.oi[b.I_FAIL_INDEX])
    m = int(buf.oi[b.I_FAIL_MODE])
    t = float(buf.of[b.F_FAIL_T])
    x = np.array(buf.of[b.N_OUT_F : b.N_OUT_F + len(native.state_names)], dtype=float)
    compiled, mode = _reference_mode(native, model, m, inputs)
    _, call = _reference_function(kind, index, m, mode, layout)
    call(t, x)
    for failure in (compiled.failure, compiled.flow_failure):
        if failure.error is not None:
            return str(describe_failure(compiled, failure))
    return None


def _reference_function(kind: int, index: int, m: int, mode: Any, layout: Layout,
                        native: NativeModel | None = None) -> Sequence[Any]:  # fmt: skip
    """``(what, the reference's function)`` that failed (``mode`` None: the words only)."""
    names = native.modes[m] if native is not None else mode
    if kind in (b.F_GUARD, b.F_RESET):
        k = layout.transitions[index][1]
        name = names.transitions[k].view.name if native is not None else mode.transitions[k].name
        what = f"the {'guard' if kind == b.F_GUARD else 'reset'} of {name}"
        if mode is None:
            return what, None
        tr = mode.transitions[k]
        return what, tr.rho if kind == b.F_GUARD else tr.reset
    if kind == b.F_INVARIANT:
        inv = index - layout.invariant_first[m]
        name = names.invariants[inv][0] if native is not None else mode.invariants[inv].name
        return f"the invariant of {name}", None if mode is None else mode.invariants[inv].rho
    if kind == b.F_SIGNALS:
        return f"the signals of {names.name}", None if mode is None else mode.outputs
    return f"the flow of {names.name}", None if mode is None else mode.rhs


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


def _segments(buf: b.RunArrays, d: int, n: int) -> list[tuple[int, float, float, Any]]:
    """The interpolants of the ``n`` steps stored in ``buf``, one per stay."""
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
    model: System,
    settings: Settings,
    buf: b.RunArrays,
    inputs: Inputs = None,
) -> Run:
    """The :class:`Run` recorded in ``buf`` (one run's arrays) for ``model``.

    Its points are copied out of ``buf`` at once, as one block, and made into
    columns when first read (:class:`RecordedRun`); the rest is made here.
    """
    oi, of = buf.oi.tolist(), buf.of.tolist()  # the counts and numbers, read at once
    n, d = oi[b.I_POINTS], len(native.state_names)
    run: RecordedRun = RecordedRun.__new__(RecordedRun)
    run.__dict__.update(
        model=model.name,
        state_names=layout.state_names,
        signal_names=tuple(native.columns),
        jumps=JumpRecords(layout, buf.jps[: oi[b.I_JUMPS]].copy(), d),
        termination=termination_of(native, layout, model, settings, buf, inputs, (oi, of)),
        settings=settings_record(settings),
        segments=_segments(buf, d, oi[b.I_STORED_STEPS]) if oi[b.I_STORED_STEPS] else [],
        units={},
        requirements={},
        _rows=buf.pts[:n].copy(),
        _names=layout.mode_names,
        _extremes=_extremes(buf, d),
    )  # the fields a Run's __init__ sets, defaults included; not the columns yet
    return run


def _extremes(buf: b.RunArrays, d: int) -> Extremes | None:
    """The states' smallest and largest values the loop kept in the run's scratch, as
    lists (None where the scratch is not kept: an ensemble's rows)."""
    if buf.wi.shape[0] <= b.W_EXTREMES:
        return None
    at = int(buf.wi[b.W_EXTREMES])
    values = buf.wf[at : at + 2 * d].tolist()
    return values[:d], values[d:]


_COLUMNS = frozenset(("t", "j", "location", "states", "signals"))


class RecordedRun(Run):
    """A compiled run: a :class:`Run` whose columns are made from its points on first read.

    The compiled loop's points (time, hybrid time, mode, states, signals per
    row) are kept as the one block copied out of the loop's arrays; ``t``,
    ``j``, ``location``, ``states`` and ``signals`` are made from it, all five
    at once, the first time one is read, and are then what an eagerly built
    :class:`Run` holds (contiguous arrays of their own). A run nobody reads
    costs one copy. Copied or pickled, it is a plain :class:`Run`.

    Examples
    --------
    >>> import hybrid
    >>> ball = hybrid.load("specs/bouncing_ball.yaml")
    >>> run = hybrid.simulate(ball, t_end=2.0, backend="compiled", handle_sigint=False)
    >>> "t" in vars(run)  # not made yet
    False
    >>> run.location[0], len(run.t), "t" in vars(run)
    ('falling', 9, True)
    """

    def __getattr__(self, name: str) -> Any:
        """A column not made yet: made now (called only for attributes not set)."""
        if name in _COLUMNS and "_rows" in self.__dict__:
            self._unpack()
            return self.__dict__[name]
        return super().__getattr__(name)  # what to write instead

    def __len__(self) -> int:
        rows = self.__dict__.get("_rows")
        return int(self.t.shape[0] if rows is None else rows.shape[0])

    def __reduce__(self) -> tuple[Any, ...]:
        self._unpack()
        fields = {k: v for k, v in self.__dict__.items() if k != "_extremes"}
        return (_plain_run, (fields,))

    def stored_extremes(self) -> Extremes | None:
        extremes: Extremes | None = self.__dict__.get("_extremes")
        return extremes

    def checked_columns(self) -> tuple[NDArray[np.float64], Any, NDArray[np.float64]]:
        rows = self.__dict__.get("_rows")
        if rows is None:
            return super().checked_columns()
        return rows[:, b.P_T], rows[:, b.P_J], rows[:, b.P_X : b.P_X + len(self.state_names)]

    def _unpack(self) -> None:
        """Make the columns from the block (two threads may both: they make the same)."""
        found = self.__dict__
        rows, names = found.get("_rows"), found.get("_names")
        if rows is None or names is None:
            return
        d = len(self.state_names)
        columns = {
            "t": rows[:, b.P_T].copy(),
            "j": rows[:, b.P_J].astype(np.int64),
            "location": names.take(rows[:, b.P_M].astype(np.int64)),
            "states": rows[:, b.P_X : b.P_X + d].copy(),
            "signals": rows[:, b.P_X + d :].copy(),
        }
        for name, column in columns.items():
            found.setdefault(name, column)  # one set before it was made stays
        found.pop("_rows", None)
        found.pop("_names", None)


def _plain_run(fields: dict[str, Any]) -> Run:
    """A :class:`Run` holding ``fields`` (how a :class:`RecordedRun` is copied and pickled)."""
    run = Run.__new__(Run)
    run.__dict__.update(fields)
    return run
