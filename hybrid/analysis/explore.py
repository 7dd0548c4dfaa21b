"""The reachable product of a system, explored on the fly from the initial mode.

A *mode* is one location per component. The product is never built whole:
the explorer starts at the initial mode and follows transitions breadth-first,
so only reachable modes are ever visited. It works on discrete structure
precomputed per component (:class:`ProductTables`): per location, the live
edges (guard can hold within bounds) split into local ones and ones carrying
a label shared with other components (those fire together, one edge from
each owner of the label, as in :func:`hybrid.modes.transitions_of`).

Modes are tuples of location indices, encoded as integers in mixed radix, and
each BFS level is processed with numpy: successors, the visited set (a bitmap
when the product is small enough, else a set of ints), and the per-mode
verdicts (deadlock, nondeterminism), which are decided once per distinct
(location, available shared labels) and looked up for every mode.
:func:`explore_reference` is a plain-Python BFS with the same results, kept
as a cross-check and for products too large for 62-bit codes.

Examples
--------
>>> import hybrid
>>> a = hybrid.load_text('''
... automaton: a
... labels: [go]
... locations: {idle: {}, busy: {}}
... edges: [{from: idle, to: busy, label: go}, {from: busy, to: idle}]
... ''')
>>> b = hybrid.load_text('''
... automaton: b
... labels: [go]
... locations: {wait: {}, run: {}}
... edges: [{from: wait, to: run, label: go}]
... ''')
>>> result = explore(ProductTables(hybrid.compose(a, b)))
>>> result.states, result.complete
(3, True)
"""

from __future__ import annotations

import itertools
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from hybrid.analysis.product import Mode, ProductTables, Transition

__all__ = ["DEFAULT_MAX_STATES", "Exploration", "explore", "explore_reference"]

DEFAULT_MAX_STATES = 5_000_000
DENSE_LIMIT = 1 << 25  # products up to this size keep the visited set as a bitmap
_CODE_LIMIT = 1 << 62


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
    modes: list[int] = field(default_factory=list)
    """Codes of the modes visited, in breadth-first order (level by level)."""
    _parent: Callable[[int], int | None] | None = None

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


def explore(tables: ProductTables, max_states: int = DEFAULT_MAX_STATES) -> Exploration:
    """Breadth-first exploration of the reachable product (numpy, level by level).

    Stops after ``max_states`` modes (``complete`` is then ``False``).
    """
    if tables.size >= _CODE_LIMIT:
        return explore_reference(tables, max_states)
    start = time.perf_counter()
    result = Exploration(tables)
    result.reached = [np.zeros(n, dtype=bool) for n in tables.radices]
    weights = np.array(tables.weights, dtype=np.int64)
    radices = np.array(tables.radices, dtype=np.int64)
    local_tabs = [_delta_table(tables, i, None) for i in range(len(tables.components))]
    sync_tabs = {
        a: [(o, *_delta_table(tables, o, a)) for o in owners] for a, owners in tables.owners.items()
    }
    stick_loc = [
        np.array([tables.may_stick(i, loc) for loc in range(n)])
        for i, n in enumerate(tables.radices)
    ]
    conflict_loc = [
        np.array([tables.may_conflict(i, loc) for loc in range(n)])
        for i, n in enumerate(tables.radices)
    ]

    dense = tables.size <= DENSE_LIMIT
    bitmap = np.zeros(tables.size if dense else 0, dtype=bool)
    seen: set[int] = set()
    levels: list[tuple[np.ndarray, np.ndarray]] = []
    init = tables.encode(tables.initial)
    frontier = np.array([init], dtype=np.int64)
    if dense:
        bitmap[init] = True
    else:
        seen.add(init)
    levels.append((frontier, np.array([-1], dtype=np.int64)))
    count = 1

    while frontier.size:
        digits = (frontier[:, None] // weights) % radices
        offered = {}
        for a, parts in sync_tabs.items():
            ok = np.ones(frontier.size, dtype=bool)
            for o, _, mask in parts:
                ok &= mask[digits[:, o]].any(axis=1)
            offered[a] = ok
        _record_reach(result, digits, frontier)
        _record_fired(tables, result, digits, offered)
        _record_verdicts(tables, result, digits, frontier, offered, stick_loc, conflict_loc)

        stepped = _successors(frontier, digits, local_tabs, sync_tabs, offered)
        if stepped is None:
            break
        candidates, parents = stepped
        unique, first = np.unique(candidates, return_index=True)
        parents = parents[first]
        if dense:
            fresh = ~bitmap[unique]
        else:
            fresh = np.fromiter(
                (c not in seen for c in unique.tolist()), dtype=bool, count=unique.size
            )
        unique, parents = unique[fresh], parents[fresh]
        if count + unique.size > max_states:
            keep = max_states - count
            unique, parents = unique[:keep], parents[:keep]
            result.complete = False
        if dense:
            bitmap[unique] = True
        else:
            seen.update(unique.tolist())
        count += unique.size
        levels.append((unique, parents))
        frontier = unique
        if not result.complete:
            digits = (frontier[:, None] // weights) % radices
            _record_reach(result, digits, frontier)
            break

    result.states = count
    result.seconds = time.perf_counter() - start

    def parent(code: int) -> int | None:
        for codes, pars in levels:
            pos = int(np.searchsorted(codes, code))
            if pos < codes.size and int(codes[pos]) == code:
                value = int(pars[pos])
                return None if value < 0 else value
        return None

    result._parent = parent
    result.modes = [int(c) for codes, _ in levels for c in codes.tolist()]
    return result


_Table = tuple[np.ndarray, np.ndarray]


def _successors(
    frontier: np.ndarray,
    digits: np.ndarray,
    local_tabs: list[_Table],
    sync_tabs: dict[str, list[tuple[int, np.ndarray, np.ndarray]]],
    offered: dict[str, np.ndarray],
) -> tuple[np.ndarray, np.ndarray] | None:
    """Codes of all successors of the frontier and, aligned, the code of their parent."""
    succ: list[np.ndarray] = []
    pars: list[np.ndarray] = []
    for i, (delta, mask) in enumerate(local_tabs):
        if not mask.any():
            continue
        d = delta[digits[:, i]]
        m = mask[digits[:, i]]
        succ.append((frontier[:, None] + d)[m])
        pars.append(np.broadcast_to(frontier[:, None], d.shape)[m])
    for a, parts in sync_tabs.items():
        ok = offered[a]
        if not ok.any():
            continue
        base = frontier[ok]
        # one axis per owner of the label: every combination of their edges
        total = base.reshape((-1,) + (1,) * len(parts))
        valid = np.ones(total.shape, dtype=bool)
        for n, (o, delta, mask) in enumerate(parts):
            shape = [base.size] + [1] * len(parts)
            shape[n + 1] = delta.shape[1]
            sel = digits[ok, o]
            total = total + delta[sel].reshape(shape)
            valid = valid & mask[sel].reshape(shape)
        succ.append(total[valid])
        pars.append(np.broadcast_to(base.reshape((-1,) + (1,) * len(parts)), total.shape)[valid])
    if not succ:
        return None
    return np.concatenate(succ), np.concatenate(pars)


def _delta_table(
    tables: ProductTables, component: int, label: str | None
) -> tuple[np.ndarray, np.ndarray]:
    """Per location: code deltas of the live edges (local ones, or those with ``label``)."""
    c = tables.components[component]
    rows: list[list[int]] = []
    for loc in range(len(c.locations)):
        edges = c.local[loc] if label is None else c.sync[loc].get(label, ())
        rows.append([(c.targets[e] - loc) * tables.weights[component] for e in edges])
    width = max((len(r) for r in rows), default=0)
    delta = np.zeros((len(rows), max(width, 1)), dtype=np.int64)
    mask = np.zeros((len(rows), max(width, 1)), dtype=bool)
    for loc, r in enumerate(rows):
        delta[loc, : len(r)] = r
        mask[loc, : len(r)] = True
    if width == 0:
        mask[:] = False
    return delta, mask


def _record_reach(result: Exploration, digits: np.ndarray, frontier: np.ndarray) -> None:
    for i, reached in enumerate(result.reached):
        if reached.all():
            continue
        column = digits[:, i]
        present = np.bincount(column, minlength=reached.size) > 0
        for loc in np.flatnonzero(present & ~reached):
            result.first_reach[(i, int(loc))] = int(frontier[np.argmax(column == loc)])
        reached |= present


def _record_fired(
    tables: ProductTables, result: Exploration, digits: np.ndarray, offered: dict[str, np.ndarray]
) -> None:
    for a, ok in offered.items():
        if not ok.any():
            continue
        for o in tables.owners[a]:
            c = tables.components[o]
            for loc in np.unique(digits[ok, o]).tolist():
                for e in c.sync[loc].get(a, ()):
                    result.fired.add((o, e))


def _record_verdicts(
    tables: ProductTables,
    result: Exploration,
    digits: np.ndarray,
    frontier: np.ndarray,
    offered: dict[str, np.ndarray],
    stick_loc: list[np.ndarray],
    conflict_loc: list[np.ndarray],
) -> None:
    size = frontier.size
    dead = np.zeros(size, dtype=bool)
    clash = np.zeros(size, dtype=bool)
    for i, c in enumerate(tables.components):
        column = digits[:, i]
        want_stick = stick_loc[i][column]
        want_clash = conflict_loc[i][column]
        if not (want_stick.any() or want_clash.any()):
            continue
        bits = np.zeros(size, dtype=np.int64)
        for j, a in enumerate(c.labels):
            bits |= offered[a].astype(np.int64) << j
        keys = column * (1 << len(c.labels)) + bits
        uniq, inverse = np.unique(keys, return_inverse=True)
        width = 1 << len(c.labels)
        stuck = np.array(
            [
                bool(stick_loc[i][k // width]) and tables.stuck(i, int(k // width), int(k % width))
                for k in uniq.tolist()
            ]
        )
        clashing = np.array(
            [
                bool(conflict_loc[i][k // width])
                and tables.conflicted(i, int(k // width), int(k % width))
                for k in uniq.tolist()
            ]
        )
        s, x = stuck[inverse], clashing[inverse]
        if s.any():
            for loc in np.unique(column[s]).tolist():
                result.stuck_at.add((i, loc))
        if x.any():
            for loc in np.unique(column[x]).tolist():
                result.conflicted_at.add((i, loc))
        dead |= s
        clash |= x
    if dead.any():
        result.deadlocks += int(dead.sum())
        if result.first_deadlock is None:
            result.first_deadlock = int(frontier[np.argmax(dead)])
    if clash.any():
        result.conflicts += int(clash.sum())
        if result.first_conflict is None:
            result.first_conflict = int(frontier[np.argmax(clash)])


def explore_reference(tables: ProductTables, max_states: int = DEFAULT_MAX_STATES) -> Exploration:
    """The same exploration in plain Python over tuples (slow; a cross-check)."""
    start = time.perf_counter()
    result = Exploration(tables)
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
    result.states = len(parents)
    result.seconds = time.perf_counter() - start
    by_code = {
        tables.encode(m): (None if p is None else tables.encode(p)) for m, p in parents.items()
    }
    result._parent = by_code.get
    result.modes = list(by_code)
    return result
