"""What an exploration of a product found, and the plain-Python reference explorer.

:class:`Exploration` holds the results of :func:`hybrid.analysis.explore.explore`
(and of :func:`explore_reference`, the same breadth-first search over tuples:
a cross-check, and the explorer of products too large for 62-bit codes).
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import numpy as np

from hybrid.analysis.product import Mode, ProductTables, Transition

__all__ = [
    "DEFAULT_MAX_BYTES",
    "DEFAULT_MAX_STATES",
    "SLICE_CELLS",
    "Exploration",
    "Progress",
    "explore_reference",
    "first_in_levels",
    "state_bound",
    "words",
]

DEFAULT_MAX_STATES = 5_000_000
DEFAULT_MAX_BYTES = 256 * 1024 * 1024
"""Memory the explorer lets the modes it keeps take (256 MiB), whatever ``max_states``."""
SLICE_CELLS = 1 << 20  # (modes x components x words) of a level processed at once
WORD_BITS = 62  # mixed-radix digits packed per int64 word of a mode's code

Progress = Callable[[int, int], None]
"""``progress(modes visited so far, modes in the frontier)``."""


def words(tables: ProductTables) -> list[tuple[int, int]]:
    """Per component, the (word, weight) of its digit in a mode's code of int64 words."""
    layout: list[tuple[int, int]] = []
    word, weight = 0, 1
    for n in tables.radices:
        if weight * n >= 1 << WORD_BITS:
            word, weight = word + 1, 1
        layout.append((word, weight))
        weight *= n
    return layout


def state_bound(tables: ProductTables, max_states: int, max_bytes: int) -> int:
    """How many modes an exploration of ``tables`` may keep within ``max_bytes``.

    Each mode kept costs its code (one int64 per word) in its level and in the
    visited set, its parent index, and as much again for the copies made while
    a level is sorted and merged (measured: bench/product_exploration.py).
    """
    k = 1 + max((w for w, _ in words(tables)), default=0)
    per_state = 16 * (3 * k + 1)
    return max(1, min(max_states, max_bytes // per_state))


@dataclass
class Exploration:
    """What the exploration found; modes are named by their index in breadth-first order."""

    tables: ProductTables
    states: int = 0
    complete: bool = True
    seconds: float = 0.0
    reached: list[np.ndarray] = field(default_factory=list)
    first_reach: dict[tuple[int, int], int] = field(default_factory=dict)
    deadlocks: int = 0
    first_deadlock: int | None = None
    stuck_at: set[tuple[int, int]] = field(default_factory=set)
    conflicts: int = 0
    first_conflict: int | None = None
    conflicted_at: set[tuple[int, int]] = field(default_factory=set)
    fired: set[tuple[int, int]] = field(default_factory=set)
    bound: int = 0
    """The most modes this exploration could keep (``max_states`` or the memory bound)."""
    _parent: Callable[[int], int | None] | None = None
    _mode: Callable[[int], Mode] | None = None
    _matching: Callable[[dict[int, int]], int | None] | None = None

    def mode(self, index: int) -> Mode:
        """The mode visited ``index``-th (the initial modes come first)."""
        assert self._mode is not None
        return self._mode(index)

    def origin(self, index: int) -> Mode:
        """The initial mode a shortest path to the ``index``-th mode starts from."""
        while self._parent is not None and (parent := self._parent(index)) is not None:
            index = parent
        return self.mode(index)

    def first_matching(self, wanted: dict[int, int]) -> int | None:
        """The first mode visited (breadth-first: nearest) with component ``i`` in
        location ``wanted[i]`` for each ``i``; ``None`` if none was."""
        if self._matching is not None:
            return self._matching(wanted)
        for k, mode in enumerate(self.modes()):
            if all(mode[i] == loc for i, loc in wanted.items()):
                return k
        return None

    def modes(self) -> Iterator[Mode]:
        """The modes visited, in breadth-first order."""
        return (self.mode(k) for k in range(self.states))

    def path_to(self, index: int) -> list[tuple[Transition, Mode]]:
        """A shortest path of transitions from an initial mode (:meth:`origin`) to the
        ``index``-th mode."""
        if self._parent is None:
            return []
        chain = [index]
        while True:
            parent = self._parent(chain[-1])
            if parent is None:
                break
            chain.append(parent)
        chain.reverse()
        steps: list[tuple[Transition, Mode]] = []
        for src, dst in itertools.pairwise(chain):
            mode, target = self.mode(src), self.mode(dst)
            for tr in self.tables.successors(mode):
                if tr.target == target:
                    steps.append((tr, target))
                    break
        return steps


def first_in_levels(
    levels: list[tuple[np.ndarray, np.ndarray]],
    offsets: list[int],
    digits_of: Callable[[np.ndarray], np.ndarray],
    wanted: dict[int, int],
) -> int | None:
    """The index of the first mode of ``levels`` (code rows) with ``wanted`` locations."""
    for level, (rows, _) in enumerate(levels):
        digits = digits_of(rows)
        hit = np.ones(rows.shape[0], dtype=bool)
        for i, loc in wanted.items():
            hit &= digits[:, i] == loc
        if hit.any():
            return offsets[level] + int(np.argmax(hit))
    return None


def explore_reference(
    tables: ProductTables,
    max_states: int = DEFAULT_MAX_STATES,
    *,
    progress: Progress | None = None,
) -> Exploration:
    """The same exploration in plain Python over tuples (slow; a cross-check)."""
    start = time.perf_counter()
    result = Exploration(tables, bound=max_states)
    result.reached = [np.zeros(n, dtype=bool) for n in tables.radices]
    index: dict[Mode, int] = {m: k for k, m in enumerate(tables.initials)}
    order: list[Mode] = list(tables.initials)
    parents: list[int | None] = [None] * len(order)
    head = 0
    while head < len(order):
        mode = order[head]
        for i, loc in enumerate(mode):
            if not result.reached[i][loc]:
                result.reached[i][loc] = True
                result.first_reach[(i, loc)] = head
        offered = tables.offered(mode)
        dead = clash = False
        for i, loc in enumerate(mode):
            bits = tables.bits(i, offered)
            if tables.stuck(i, loc, bits):
                result.stuck_at.add((i, loc))
                dead = True
            if tables.conflicted(i, loc, bits):
                result.conflicted_at.add((i, loc))
                clash = True
        if dead:
            result.deadlocks += 1
            if result.first_deadlock is None:
                result.first_deadlock = head
        if clash:
            result.conflicts += 1
            if result.first_conflict is None:
                result.first_conflict = head
        for tr in tables.successors(mode):
            if tr.label is not None and tr.label in tables.owners:
                result.fired.update(tr.parts)
            if tr.target not in index:
                if len(order) >= max_states:
                    result.complete = False
                    continue
                index[tr.target] = len(order)
                order.append(tr.target)
                parents.append(head)
        head += 1
        if progress is not None and head % 4096 == 0:
            progress(len(order), len(order) - head)
    if not tables.initials_complete:  # more initial modes than explored from
        result.complete = False
    result.states = len(order)
    result.seconds = time.perf_counter() - start
    result._parent = parents.__getitem__
    result._mode = order.__getitem__
    return result
