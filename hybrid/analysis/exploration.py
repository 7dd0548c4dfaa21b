"""What an exploration of a product found, and the plain-Python reference explorer.

:class:`Exploration` holds the results of :func:`hybrid.analysis.explore.explore`
(and of :func:`explore_reference`, the same breadth-first search over tuples:
a cross-check, and the explorer of products too large for 62-bit codes).
"""

from __future__ import annotations

import itertools
import time
from collections import deque
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import numpy as np

from hybrid.analysis.product import Mode, ProductTables, Transition

__all__ = [
    "DEFAULT_MAX_BYTES",
    "DEFAULT_MAX_STATES",
    "SLICE",
    "Exploration",
    "Progress",
    "explore_reference",
    "state_bound",
]

DEFAULT_MAX_STATES = 5_000_000
DEFAULT_MAX_BYTES = 256 * 1024 * 1024
"""Memory the explorer lets the modes it keeps take (256 MiB), whatever ``max_states``."""
SLICE = 1 << 16  # modes of a level processed at once
CODE_LIMIT = 1 << 62
_BYTES_PER_CODE = 32  # level code and parent, visited copy, merge headroom
_BYTES_PER_TUPLE = 120  # reference explorer: dict entry, tuple header, parent reference

Progress = Callable[[int, int], None]
"""``progress(modes visited so far, modes in the frontier)``."""


def state_bound(tables: ProductTables, max_states: int, max_bytes: int) -> int:
    """How many modes an exploration of ``tables`` may keep within ``max_bytes``."""
    if tables.size < CODE_LIMIT:
        per_state = _BYTES_PER_CODE
    else:
        per_state = _BYTES_PER_TUPLE + 8 * len(tables.components)
    return max(1, min(max_states, max_bytes // per_state))


@dataclass
class Exploration:
    """What the exploration found; modes are given as integer codes."""

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
    _codes: Callable[[], Iterator[int]] | None = None

    def codes(self) -> Iterator[int]:
        """Codes of the modes visited, in breadth-first order (level by level)."""
        return iter(()) if self._codes is None else self._codes()

    def path_to(self, code: int) -> list[tuple[Transition, Mode]]:
        """A shortest path of transitions from the initial mode to mode ``code``."""
        if self._parent is None:
            return []
        chain = [code]
        while True:
            parent = self._parent(chain[-1])
            if parent is None:
                break
            chain.append(parent)
        chain.reverse()
        steps: list[tuple[Transition, Mode]] = []
        for src, dst in itertools.pairwise(chain):
            mode, target = self.tables.decode(src), self.tables.decode(dst)
            for tr in self.tables.successors(mode):
                if tr.target == target:
                    steps.append((tr, target))
                    break
        return steps


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
    parents: dict[Mode, Mode | None] = {tables.initial: None}
    queue: deque[Mode] = deque([tables.initial])
    while queue:
        mode = queue.popleft()
        code = tables.encode(mode)
        for i, loc in enumerate(mode):
            if not result.reached[i][loc]:
                result.reached[i][loc] = True
                result.first_reach[(i, loc)] = code
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
                result.first_deadlock = code
        if clash:
            result.conflicts += 1
            if result.first_conflict is None:
                result.first_conflict = code
        for tr in tables.successors(mode):
            if tr.label is not None and tr.label in tables.owners:
                result.fired.update(tr.parts)
            if tr.target not in parents:
                if len(parents) >= max_states:
                    result.complete = False
                    continue
                parents[tr.target] = mode
                queue.append(tr.target)
        if progress is not None and len(parents) % SLICE == 0:
            progress(len(parents), len(queue))
    result.states = len(parents)
    result.seconds = time.perf_counter() - start
    by_code = {
        tables.encode(m): (None if p is None else tables.encode(p)) for m, p in parents.items()
    }
    result._parent = by_code.get
    result._codes = lambda: iter(list(by_code))
    return result
