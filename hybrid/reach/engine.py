"""The hybrid loop: flowpipes per mode, guards met, resets applied, up to a jump bound.

A waiting list holds boxes to start from: ``(mode, lo, hi, jumps)``. Each is
kept as a set of its own (a run may enter outside the invariant: the simulator
then stops there, blocked, or jumps on at once), then clipped to its mode's
invariant and flowed with :func:`hybrid.reach.flowpipe.flowpipe`
until the horizon or until a segment's box leaves the invariant (a run that
stays in a mode satisfies its invariant throughout, so once no state of a
segment does, no run is still there later), and every segment is kept as a
set. Where a segment meets an edge's guard, the contracted boxes of
consecutive segments are joined (clustering: one box per stretch of contact,
at most :data:`MAX_CLUSTERS` per edge and flowpipe, the closest in time joined
first), mapped by the reset and queued in the target mode.

This is the *may* semantics of a hybrid automaton (an edge may fire whenever
its guard holds, time may pass while the invariant holds); the simulator's
runs (an edge fires as soon as it can) are among its runs, so the sets hold
every simulated state. A system's edges are taken per component, and edges
with a shared label together, one from each component that declares it.

Examples
--------
>>> import hybrid
>>> m = hybrid.load_text('''
... automaton: decay
... state: {x: {initial: [1, 2]}}
... locations: {l: {flow: {x: -x}}}
... ''')
>>> from hybrid.compose import as_system
>>> sets, complete, cut = explore(as_system(m), t_end=1.0, max_jumps=0, step=0.01)
>>> complete, len(sets), sets[-1].t[1] >= 1.0, cut
(True, 101, True, None)
"""

from __future__ import annotations

import itertools
import math
import weakref
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from hybrid.compose import System
from hybrid.errors import Position, UsageError
from hybrid.model import Edge
from hybrid.reach.affine import TIME, Condition, Forms, Rows
from hybrid.reach.boxes import affine_image, band, meets, meets_many
from hybrid.reach.flowpipe import Overflow, flowpipe

__all__ = [
    "MAX_CLUSTERS",
    "MAX_FLOWPIPES",
    "MAX_STEPS",
    "Mode",
    "ReachSet",
    "Transition",
    "explore",
    "forms_of",
    "initial_boxes",
    "mode_of",
]

Array = NDArray[np.float64]
MAX_CLUSTERS = 4
"""Boxes queued per edge and flowpipe after clustering."""
CLUSTER_CHUNK = 4096
"""Segments met against a guard at once (arrays of rows x columns per segment)."""
MAX_STEPS = 1_000_000
"""Most steps of one flowpipe (``t_end / step``): each keeps four boxes a step, and the
default step gives 4,000."""

MAX_FLOWPIPES = 20_000
"""Flowpipes computed at most; beyond, the result is incomplete (nothing is proved)."""


@dataclass(frozen=True)
class ReachSet:
    """The box hull ``[lo, hi]`` of the reachable states of ``location`` over the times ``t``."""

    location: str
    t: tuple[float, float]
    lo: Array = field(repr=False)
    hi: Array = field(repr=False)
    mode: tuple[str, ...] = field(default=(), repr=False)
    jumps: int = 0


@dataclass(frozen=True)
class Transition:
    """Edges that fire together: a guard (disjunction of cases) and an affine reset."""

    name: str
    target: tuple[str, ...]
    guard: Condition
    rmat: Array
    smat: Array
    rvec: Array


@dataclass(frozen=True)
class Mode:
    """One mode's dynamics, invariant and transitions, read once."""

    key: tuple[str, ...]
    name: str
    a: Array
    b: Array
    c: Array
    invariant: Condition
    transitions: tuple[Transition, ...]
    urgent: bool
    invariant_all: Condition = ()
    """The invariant where it holds for every input value (a witness's check)."""


class _Modes:
    def __init__(self, forms: Forms) -> None:
        self.forms = forms
        self.cache: dict[tuple[str, ...], Mode] = {}

    def get(self, key: tuple[str, ...]) -> Mode:
        found = self.cache.get(key)
        if found is None:
            found = self._read(key)
            self.cache[key] = found
        return found

    def _read(self, key: tuple[str, ...]) -> Mode:
        forms, system = self.forms, self.forms.system
        a, b, c = forms.flow(key)
        invariant: Condition = (Rows(np.zeros((0, a.shape[0])), np.zeros(0)),)
        invariant_all = invariant
        for i, comp in enumerate(system.components):
            loc = comp.automaton.locations[key[i]]
            what = f"the invariant of location '{system.qualified(i, loc.name)}'"
            where = loc.invariant_position
            part = forms.condition(loc.invariant, i, key, where, what)
            invariant = _and(invariant, part)
            every = forms.condition(loc.invariant, i, key, where, what, for_all=True)
            invariant_all = _and(invariant_all, every)
        urgent = any(
            comp.automaton.locations[key[i]].urgent for i, comp in enumerate(system.components)
        )
        name, transitions = system.mode_name(key), tuple(self._transitions(key))
        return Mode(key, name, a, b, c, invariant, transitions, urgent, invariant_all)

    def _transitions(self, key: tuple[str, ...]) -> Iterator[Transition]:
        system = self.forms.system
        shared = system.shared_labels
        for i, comp in enumerate(system.components):
            for edge in comp.automaton.outgoing(key[i]):
                if edge.label is None or edge.label not in shared:
                    yield self._joint(key, [(i, edge)])
        for label, owners in shared.items():
            choices = [
                [
                    (i, e)
                    for e in system.components[i].automaton.outgoing(key[i])
                    if e.label == label
                ]
                for i in owners
            ]
            for combo in itertools.product(*choices):
                yield self._joint(key, list(combo))

    def _joint(self, key: tuple[str, ...], edges: list[tuple[int, Edge]]) -> Transition:
        forms, system = self.forms, self.forms.system
        n = len(forms.variables)
        guard: Condition = (Rows(np.zeros((0, n)), np.zeros(0)),)
        rmat, smat, rvec = np.eye(n), np.zeros((n, len(forms.inputs))), np.zeros(n)
        target = list(key)
        names = []
        for i, edge in edges:
            label = system.qualified(i, edge.name)
            names.append(label)
            what = f"the guard of edge '{label}'"
            guard = _and(guard, forms.condition(edge.guard, i, key, edge.guard_position, what))
            r, s, v = forms.reset(i, key, edge.reset, edge.reset_positions, edge.position, label)
            for var in edge.reset:
                row = forms.index[var]
                rmat[row], smat[row], rvec[row] = r[row], s[row], v[row]
            target[i] = edge.target
        return Transition(" + ".join(names), tuple(target), guard, rmat, smat, rvec)


_READ: weakref.WeakKeyDictionary[Forms, _Modes] = weakref.WeakKeyDictionary()
_FORMS: dict[int, tuple[weakref.ref[System], Forms]] = {}
""":func:`forms_of`'s cache: a model's id -> (the model, weakly; its forms)."""


def forms_of(model: System) -> Forms:
    """The forms of ``model``, read once per model object (a model is immutable).

    :func:`~hybrid.compose.as_system` gives the same system for the same
    automaton, so the runs of :func:`hybrid.reach` on one automaton share them.

    Examples
    --------
    >>> import hybrid
    >>> m = hybrid.load_text('''
    ... automaton: a
    ... state: {x: {initial: 1}}
    ... locations: {l: {flow: {x: -x}}}
    ... ''')
    >>> from hybrid.compose import as_system
    >>> forms_of(as_system(m)) is forms_of(as_system(m))
    True
    """
    key = id(model)
    found = _FORMS.get(key)
    if found is not None and found[0]() is model:
        return found[1]
    forms = Forms(model)
    cache = _FORMS  # bound here: at exit the module's globals may be gone first

    def forget(_: object) -> None:
        cache.pop(key, None)

    _FORMS[key] = (weakref.ref(model, forget), forms)
    return forms


def _modes(forms: Forms) -> _Modes:
    found = _READ.get(forms)
    if found is None:
        found = _READ[forms] = _Modes(forms)
    return found


def mode_of(forms: Forms, key: tuple[str, ...]) -> Mode:
    """The mode ``key`` (a location per component) as read from ``forms``, once per ``forms``."""
    return _modes(forms).get(key)


def _and(left: Condition, right: Condition) -> Condition:
    return tuple(p.conjoin(q) for p in left for q in right)


def initial_boxes(forms: Forms) -> list[tuple[tuple[str, ...], Array, Array]]:
    """Every initial mode with the initial box (``t = 0``)."""
    system = forms.system
    ranges = system.initial_set()
    lo = np.array([ranges[v].lo for v in system.state_names] + [0.0])
    hi = np.array([ranges[v].hi for v in system.state_names] + [0.0])
    modes = itertools.product(*(c.automaton.initial_locations for c in system.components))
    return [(tuple(m), lo, hi) for m in modes]


def explore(
    model: System,
    *,
    t_end: float,
    max_jumps: int,
    step: float,
    forms: Forms | None = None,
    progress: Callable[[int, int, int], None] | None = None,
) -> tuple[list[ReachSet], bool, float | None]:
    """Every set reached within ``[0, t_end]`` and ``max_jumps`` jumps, whether the search
    finished, and the earliest time a run may take a jump past ``max_jumps`` (``None``:
    none can within the horizon): what such a run does after it is in no set.

    ``progress(flowpipes, sets, waiting)`` is called as each flowpipe begins: the
    flowpipes begun, the sets computed, and the entry boxes still waiting.

    Raises
    ------
    SpecError
        A flow, guard, invariant or reset that is not affine, at ``file:line:column``.
    UsageError
        A horizon or step that is not a positive finite number.
    """
    if not (math.isfinite(t_end) and t_end >= 0.0):
        raise UsageError(f"t_end must be a finite number >= 0, got {t_end}")
    if not (math.isfinite(step) and step > 0.0):
        raise UsageError(f"the step must be a finite number > 0, got {step}")
    if t_end / step > MAX_STEPS:
        raise UsageError(
            f"step={step:g} gives {t_end / step:.3g} steps to t_end={t_end:g} (the limit is "
            f"{MAX_STEPS:.0e} a flowpipe): raise it"
        )
    if max_jumps < 0:
        raise UsageError(f"max_jumps must be >= 0, got {max_jumps}")
    forms = forms or forms_of(model)
    modes = _modes(forms)
    t_index = forms.index[TIME]
    waiting = [(modes.get(m), lo, hi, 0) for m, lo, hi in initial_boxes(forms)]
    sets: list[ReachSet] = []
    pipes = 0
    cut: float | None = None  # the earliest jump past the bound
    while waiting:
        mode, lo, hi, jumps = waiting.pop(0)
        pipes += 1
        if progress is not None:
            progress(pipes, len(sets), len(waiting))
        if pipes > MAX_FLOWPIPES:
            return sets, False, cut
        if lo[t_index] > t_end:
            continue
        # the entry box itself, unclipped: a run may enter outside the invariant (it
        # then ends blocked there, or jumps on at once: jumps take precedence)
        segments = [(lo, hi)]
        entry = float(band(lo, hi, t_index))  # the band an invariant is disarmed with there
        start = meets(lo, hi, mode.invariant, widen=entry)
        if start is not None:
            segments += _segments(mode, forms, start, t_end, step, t_index, entry)
        for seg_lo, seg_hi in segments:
            sets.append(
                ReachSet(
                    mode.name,
                    (float(seg_lo[t_index]), float(seg_hi[t_index])),
                    seg_lo[:t_index],
                    seg_hi[:t_index],
                    mode.key,
                    jumps,
                )
            )
        for tr in mode.transitions:
            for box in _clusters(segments, tr.guard, t_index, entry):
                if jumps >= max_jumps:  # a jump the bound leaves out: when it may come
                    at = max(0.0, float(box[0][t_index]))
                    cut = at if cut is None else min(cut, at)
                    continue
                image = affine_image(*box, tr.rmat, tr.smat, tr.rvec, forms.u_lo, forms.u_hi)
                waiting.append((modes.get(tr.target), image[0], image[1], jumps + 1))
    return sets, True, cut


def _segments(
    mode: Mode,
    forms: Forms,
    start: tuple[Array, Array],
    t_end: float,
    step: float,
    t_index: int,
    entry: float,
) -> list[tuple[Array, Array]]:
    """The mode's segment boxes, clipped to its invariant, until it is left or ``t_end``.

    The invariant is widened by the simulator's band over each segment's box, and at
    least by ``entry``, the band at the stay's entry: an invariant met on its boundary
    there is watched from that band on.
    """
    if mode.urgent:
        return [start]
    steps = max(1, math.ceil((t_end - float(start[0][t_index])) / step - 1e-9))
    kept: list[tuple[Array, Array]] = []

    def keep(k: int, lo: Array, hi: Array) -> int:
        c_lo, c_hi, ok = meets_many(
            lo, hi, mode.invariant, widen=np.maximum(band(lo, hi, t_index), entry)
        )
        count = len(ok) if bool(ok.all()) else int(np.argmin(ok))
        kept.extend(zip(c_lo[:count], c_hi[:count], strict=True))
        return count

    if not (np.all(np.isfinite(start[0])) and np.all(np.isfinite(start[1]))):
        raise UsageError(f"the sets entering location '{mode.name}' are not bounded")
    try:
        flowpipe(
            mode.a, mode.b, mode.c, forms.u_lo, forms.u_hi, start[0], start[1], step, steps, keep
        )
    except Overflow:
        rows = np.abs(mode.a).sum(axis=1)
        norm = float(rows.max()) * step
        raise UsageError(
            f"the bounds of location '{mode.name}' overflow at step {step:g} "
            f"(|A| h = {norm:.3g} in the infinity norm): give a smaller step (--step of "
            "hybrid reach; for check, checks: {reach: {step: ...}} in the spec)",
            at=_fastest_flow(forms, mode, int(np.argmax(rows))),
        ) from None
    return kept


def _fastest_flow(forms: Forms, mode: Mode, row: int) -> Position | None:
    """Where the flow of ``row``'s variable in ``mode`` is written (the row of the largest
    ``|A|`` sum: the one that overflows first), or None (time's row, a flow not written)."""
    variable = forms.variables[row]
    for component, location in zip(forms.system.components, mode.key, strict=True):
        if variable in component.automaton.state_names:
            place = component.automaton.locations[location]
            return place.flow_positions.get(variable, place.position)
    return None


def _clusters(
    segments: list[tuple[Array, Array]], guard: Condition, t_index: int, entry: float
) -> list[tuple[Array, Array]]:
    """Boxes of the segments' states in the guard (widened by the simulator's band over
    each, at least ``entry``'s): one per stretch of consecutive contact."""
    stretches: list[tuple[Array, Array]] = []
    previous = -2
    for first in range(0, len(segments), CLUSTER_CHUNK):  # all at once, a chunk at a time
        chunk = segments[first : first + CLUSTER_CHUNK]
        lo, hi = np.stack([seg[0] for seg in chunk]), np.stack([seg[1] for seg in chunk])
        c_lo, c_hi, ok = meets_many(
            lo, hi, guard, widen=np.maximum(band(lo, hi, t_index), entry)
        )
        for i in np.flatnonzero(ok).tolist():
            k, box = first + i, (c_lo[i], c_hi[i])
            if k == previous + 1 and stretches:
                last = stretches[-1]
                stretches[-1] = (np.minimum(last[0], box[0]), np.maximum(last[1], box[1]))
            else:
                stretches.append(box)
            previous = k
    while len(stretches) > MAX_CLUSTERS:
        gaps = [stretches[i + 1][0][-1] - stretches[i][1][-1] for i in range(len(stretches) - 1)]
        i = int(np.argmin(gaps))
        a, b = stretches[i], stretches[i + 1]
        stretches[i : i + 2] = [(np.minimum(a[0], b[0]), np.maximum(a[1], b[1]))]
    return stretches
