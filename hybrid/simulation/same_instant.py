"""Decisions carried across the jumps of one instant, in modes built from parts.

Components that reach their guards together jump one after another at one
instant, each jump moving one component, and each entry into a mode decides
every transition of the mode (:func:`~hybrid.simulation.boundary.enabled_at_entry`)
and stores the point with every signal: K jumps of N components cost K * N,
N² for a system whose components all switch. In a mode built from parts
(:mod:`~hybrid.simulation.parts`) a jump that leaves the state as it was
changes only the parts of the component that moved and of those that read its
signals (:attr:`~hybrid.simulation.parts.Parts.dependents`); every other
part is the same compiled object evaluated at the same ``(t, x)``, so its
decisions and its signals are what they were. Only the changed ones are
computed again:

- a transition's decision (:func:`~hybrid.simulation.boundary.decide_at_entry`)
  reads its own part's functions at ``(t, x)``, the point the slope test steps
  to (its entries for the component and those it reads, given by their parts'
  flows), and the levels used at the instant. It is decided again when its
  part or the part of a component it reads changes, or a level it reads is used.
- the slope test's point ``x + h x'`` is patched in the entries of the changed
  parts' flows; the signals of the point after a jump are the row before it
  with the changed parts' columns computed.

The numbers are the same as deciding and evaluating everything: the same
functions at the same arguments, in the same order. So are the failures: a
part evaluated without failure at these arguments cannot fail at them later,
and the changed parts are evaluated in component order wherever the whole
mode's function would have been, so the first failure is recorded under the
same name. A jump that changes the state, a new instant, a new stay: all
start over.

Examples
--------
>>> import hybrid, numpy as np
>>> from hybrid.simulation.compiled import CompiledModel
>>> text = '''
... automaton: c{i}
... state: {{x{i}: {{initial: 0}}}}
... locations:
...   a: {{flow: {{x{i}: 1}}}}
...   b: {{flow: {{x{i}: 0}}}}
... edges: [{{from: a, to: b, guard: x{i} >= 1}}]
... '''
>>> system = hybrid.compose(*[hybrid.load_text(text.format(i=i)) for i in range(8)])
>>> compiled = CompiledModel(system)
>>> memo = InstantMemo(compiled)
>>> mode, x = compiled.mode(compiled.initial_key), np.ones(8)
>>> chosen, enabled, _ = memo.enabled_at_entry(mode, 1.0, x, None, set())
>>> chosen.name, len(enabled)
('c0.a->b#0', 8)
>>> mode = compiled.target(mode, chosen)
>>> memo.enabled_at_entry(mode, 1.0, x, None, set())[0].name   # one part decided again
'c1.a->b#0'
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Set
from typing import NamedTuple

import numpy as np

from hybrid.expr.codegen import EVALUATION_ERRORS
from hybrid.simulation import boundary
from hybrid.simulation.compiled import CompiledModel
from hybrid.simulation.forms import CompiledMode, CompiledTransition, Part
from hybrid.simulation.parts import Parts

__all__ = ["InstantMemo", "signals_after"]

_ERRORS = EVALUATION_ERRORS  # an expression's failures, as the generated code catches them
_NONE: frozenset[str] = frozenset()


class _Decided(NamedTuple):
    """One part's transitions decided at the instant."""

    enabled: list[CompiledTransition]
    armed: list[bool]
    levels: frozenset[str]
    """The levels read by the decisions that read ``used``."""


class InstantMemo:
    """:func:`~hybrid.simulation.boundary.enabled_at_entry` of a run, carried from one
    entry to the next at the same instant (modes built from parts; any other mode is
    decided whole)."""

    def __init__(self, compiled: CompiledModel) -> None:
        assert compiled.parts is not None
        self._compiled = compiled
        self._parts: Parts = compiled.parts
        self._left: tuple[CompiledMode, CompiledTransition] | None = None  # the last answer
        self._failure = compiled.flow_failure
        self._t = math.nan
        self._x = b""
        self._reached: np.ndarray | None = None
        self._used: Set[str] = frozenset()
        self._used_count = 0
        self._assembly: tuple[Part, ...] = ()
        self._decided: list[_Decided | None] = []
        self._undecided: set[int] = set()
        self._enabling: set[int] = set()  # parts with an enabled transition
        self._looking: set[int] = set()  # parts whose decisions asked for the point
        self._reading_levels: set[int] = set()
        self._point: tuple[float, float, np.ndarray] | None = None
        self._stale: set[int] = set()  # parts whose flow changed since the point was made
        self._width = self._width_then = 0.0

    def enabled_at_entry(
        self,
        mode: CompiledMode,
        t: float,
        x: np.ndarray,
        reached: np.ndarray | None,
        used: Set[str],
    ) -> tuple[CompiledTransition | None, list[CompiledTransition], list[bool]]:
        """As :func:`~hybrid.simulation.boundary.enabled_at_entry`; the arming is
        listed only when no transition fires (it is what the stay's watch needs)."""
        assembly = mode.assembly
        if assembly is None:
            return boundary.enabled_at_entry(mode, t, x, reached, used)
        parts = assembly.parts
        xb = x.tobytes()
        if t != self._t or xb != self._x or reached is not self._reached or used is not self._used:
            self._start(t, xb, x, reached, used, parts)
        else:
            self._carry(mode, parts, used)
        if self._undecided:
            self._decide(mode, t, x, reached, used, parts)
        if self._looking and self._stale:
            self._look(mode, t, x)  # as the whole mode's slope test would evaluate the flows
        decided = self._decided
        enabled = [tr for i in sorted(self._enabling) for tr in decided[i].enabled]  # type: ignore[union-attr]
        chosen = boundary.choose(enabled)
        if chosen is not None:
            self._left = (mode, chosen)
            return chosen, enabled, []
        self._left = None
        armed = list(itertools.chain.from_iterable(d.armed for d in decided))  # type: ignore[union-attr]
        return None, enabled, armed

    # --- what is carried ----------------------------------------------------------------

    def _start(
        self,
        t: float,
        xb: bytes,
        x: np.ndarray,
        reached: np.ndarray | None,
        used: Set[str],
        parts: tuple[Part, ...],
    ) -> None:
        """A new instant, state or stay: nothing is known."""
        self._t, self._x, self._reached, self._used = t, xb, reached, used
        self._used_count = len(used)
        self._assembly = parts
        self._decided = [None] * len(parts)
        self._undecided = set(range(len(parts)))
        self._enabling.clear()
        self._looking.clear()
        self._reading_levels.clear()
        self._point = None
        self._stale.clear()
        self._width = boundary.band(x)
        self._width_then = 0.0 if reached is None else boundary.band(reached)

    def _carry(self, mode: CompiledMode, parts: tuple[Part, ...], used: Set[str]) -> None:
        """Forget what the parts changed since the last entry, or the levels used, can change."""
        dependents = self._parts.dependents
        moved = None
        if self._left is not None:  # the jump the last answer chose, if it led here
            source, tr = self._left
            if tr.move is not None and self._compiled.target(source, tr) is mode:
                moved = tr.move[0]
        changed = _changed(self._parts, moved, parts, self._assembly)
        self._assembly = parts
        for c in changed:
            self._stale.add(c)
            for i in dependents[c]:
                self._forget(i)
        if len(used) != self._used_count:
            # levels are a component's own (level_key), so the part of the component that
            # used one was forgotten above; this keeps the rule if that ever changes
            self._used_count = len(used)
            for i in list(self._reading_levels):
                d = self._decided[i]
                if d is not None and not d.levels.isdisjoint(used):
                    self._forget(i)

    def _forget(self, i: int) -> None:
        if self._decided[i] is not None:
            self._decided[i] = None
            self._undecided.add(i)
            self._enabling.discard(i)
            self._looking.discard(i)
            self._reading_levels.discard(i)

    def _decide(
        self,
        mode: CompiledMode,
        t: float,
        x: np.ndarray,
        reached: np.ndarray | None,
        used: Set[str],
        parts: tuple[Part, ...],
    ) -> None:
        """Decide the parts not decided, in component order."""
        asked: list[bool] = []

        def look() -> tuple[float, float, np.ndarray]:
            asked.append(True)
            return self._look(mode, t, x)

        width, width_then = self._width, self._width_then
        for i in sorted(self._undecided):
            part = parts[i]
            asked.clear()
            enabled: list[CompiledTransition] = []
            armed: list[bool] = []
            levels: set[str] = set()
            for tr in part.transitions:
                now, is_armed = boundary.decide_at_entry(
                    tr, mode, t, x, width, reached, width_then, used, look
                )
                armed.append(is_armed)
                if now:
                    enabled.append(tr)
                if tr.levels and reached is not None:
                    levels.update(tr.level_keys)
            self._decided[i] = _Decided(enabled, armed, frozenset(levels) if levels else _NONE)
            if enabled:
                self._enabling.add(i)
            if asked:
                self._looking.add(i)
            if levels:
                self._reading_levels.add(i)
        self._undecided.clear()

    def _look(self, mode: CompiledMode, t: float, x: np.ndarray) -> tuple[float, float, np.ndarray]:
        """The slope test's point in ``mode``: made whole once at the instant, then the
        entries of the parts whose flow changed computed again."""
        if self._point is None:
            self._point = boundary.ahead(mode, t, x)
            self._stale.clear()
        elif self._stale:
            assert mode.assembly is not None
            h, _, x1 = self._point
            xs = x.tolist()
            slices = self._parts.state_slices
            for c in sorted(self._stale):
                try:
                    rates = self._assembly[c].flow(t, xs)
                except _ERRORS as e:  # the whole function's failure: its name, and NaNs
                    self._failure.record(e, t, mode.assembly.flow_where)
                    x1[:] = math.nan
                    break
                where = slices[c]
                x1[where] = [xi + h * di for xi, di in zip(xs[where], rates, strict=True)]
            self._stale.clear()
        return self._point


def _changed(
    parts: Parts, moved: int | None, now: tuple[Part, ...], before: tuple[Part, ...]
) -> list[int]:
    """The components whose parts differ in ``now`` from ``before``: when the one mode is
    reached from the other by moving component ``moved``, its dependents
    (:meth:`~hybrid.simulation.parts.Parts.mode` builds one part per component and its
    readers' locations); else found by comparing them all."""
    if moved is not None:
        return list(parts.dependents[moved])
    return [c for c, (a, b) in enumerate(zip(now, before, strict=True)) if a is not b]


def signals_after(
    compiled: CompiledModel,
    source: CompiledMode,
    tr: CompiledTransition,
    target: CompiledMode,
    t: float,
    x: np.ndarray,
    row: tuple[float, ...],
) -> tuple[float, ...] | None:
    """The signals of ``(t, x)`` in ``target``, where ``tr`` leads from ``source``
    (:meth:`~hybrid.simulation.compiled.CompiledModel.target`), from ``row``, those of
    ``(t, x)`` in ``source``: the columns of the parts that differ computed again.
    ``None`` if either mode is not built from parts."""
    parts = compiled.parts
    if parts is None or source.assembly is None or target.assembly is None:
        return None
    values = list(row)
    xs = x.tolist()
    slices = parts.column_slices
    before = source.assembly.parts
    moved = None if tr.move is None else tr.move[0]
    for c in _changed(parts, moved, target.assembly.parts, before):
        try:
            values[slices[c]] = target.assembly.parts[c].signals(t, xs)
        except _ERRORS as e:  # the whole function's failure: its name, and NaNs
            compiled.failure.record(e, t, target.assembly.signals_where)
            return (math.nan,) * len(values)
    return tuple(values)
