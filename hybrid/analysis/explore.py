"""The reachable product of a system, explored on the fly from the initial mode.

A *mode* is one location per component. The product is never built whole:
the explorer starts at the initial mode and follows transitions breadth-first,
so only reachable modes are ever visited. It works on discrete structure
precomputed per component (:class:`ProductTables`): per location, the live
edges (guard can hold within bounds) split into local ones and ones carrying
a label shared with other components (those fire together, one edge from
each owner of the label, as in :func:`hybrid.modes.transitions_of`).

Modes are tuples of location indices, encoded in mixed radix as one int64
word, or several for products beyond 62 bits (:func:`words`), and each BFS
level is processed with numpy, in slices: successors, the visited set (a
bitmap when the product is small enough, else sorted arrays merged as they
grow), and the per-mode verdicts (deadlock, nondeterminism), which are
decided once per distinct (location, available shared labels) and looked up
for every mode. A mode is named by its index in breadth-first order.
:class:`Exploration` holds what it found; :func:`explore_reference` is a plain-Python
BFS with the same results, kept as a cross-check and the explorer of products too
large for 62-bit codes.

Exploration starts from every initial mode at once (level 0), so each mode
is reached by a shortest path from one of them.

The explorer is bounded: it stops (``complete`` false) after ``max_states``
modes, or earlier when the modes it keeps would take more than ``max_bytes``
of memory (:func:`state_bound`), so a product too large to explore ends
with a note instead of exhausting memory. ``progress(modes, frontier)`` is
called after every slice, for a progress display.

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
    "explore",
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


DENSE_LIMIT = 1 << 25  # products up to this size keep the visited set as a bitmap


def explore(
    tables: ProductTables,
    max_states: int = DEFAULT_MAX_STATES,
    *,
    max_bytes: int = DEFAULT_MAX_BYTES,
    progress: Progress | None = None,
) -> Exploration:
    """Breadth-first exploration of the reachable product (numpy, level by level).

    Stops after ``max_states`` modes, or when the modes kept would exceed
    ``max_bytes`` (``complete`` is then ``False``; ``bound`` says where).
    """
    start = time.perf_counter()
    bound = state_bound(tables, max_states, max_bytes)
    result = Exploration(tables, bound=bound)
    result.reached = [np.zeros(n, dtype=bool) for n in tables.radices]
    layout = words(tables)
    width = 1 + max((w for w, _ in layout), default=0)
    col = np.array([w for w, _ in layout], dtype=np.int64)
    weight = np.array([g for _, g in layout], dtype=np.int64)
    radices = np.array(tables.radices, dtype=np.int64)
    local_tabs = [_delta_table(tables, i, None, int(weight[i])) for i in range(len(radices))]
    sync_tabs = {
        a: [(o, *_delta_table(tables, o, a, int(weight[o]))) for o in owners]
        for a, owners in tables.owners.items()
    }
    stick_loc = [
        np.array([tables.may_stick(i, loc) for loc in range(n)])
        for i, n in enumerate(tables.radices)
    ]
    conflict_loc = [
        np.array([tables.may_conflict(i, loc) for loc in range(n)])
        for i, n in enumerate(tables.radices)
    ]
    # a slice's successors take about (modes x components x words) int64s: keep that bounded
    step = max(64, SLICE_CELLS // (max(1, len(radices)) * width))

    def digits_of(rows: np.ndarray) -> np.ndarray:
        return (rows[:, col] // weight) % radices

    visited = _Visited(width, tables.size)
    init = np.zeros((len(tables.initials), width), dtype=np.int64)
    for k, start_mode in enumerate(tables.initials):
        for i, loc in enumerate(start_mode):
            init[k, col[i]] += loc * weight[i]
    levels: list[tuple[np.ndarray, np.ndarray]] = [
        (init, np.full(init.shape[0], -1, dtype=np.int64))
    ]
    offsets = [0]
    visited.add(init)
    frontier = init
    count = init.shape[0]

    while frontier.size and result.complete:
        base = offsets[-1]
        fresh: list[tuple[np.ndarray, np.ndarray]] = []
        for lo in range(0, frontier.shape[0], step):
            part = frontier[lo : lo + step]
            ids = base + lo + np.arange(part.shape[0], dtype=np.int64)
            digits = digits_of(part)
            offered = {}
            for a, parts in sync_tabs.items():
                ok = np.ones(part.shape[0], dtype=bool)
                for o, _, mask in parts:
                    ok &= mask[digits[:, o]].any(axis=1)
                offered[a] = ok
            _record_reach(result, digits, ids)
            _record_fired(tables, result, digits, offered)
            _record_verdicts(tables, result, digits, ids, offered, stick_loc, conflict_loc)
            if not result.complete:
                continue  # the bound was met: only record the rest of this level
            stepped = _successors(part, ids, digits, col, local_tabs, sync_tabs, offered)
            if stepped is not None:
                rows, parents = stepped
                keys = _keys(rows)
                _, first = np.unique(keys, return_index=True)
                rows, parents = rows[first], parents[first]
                new = ~visited.contains(rows)
                rows, parents = rows[new], parents[new]
                if rows.shape[0]:
                    visited.add(rows)
                    fresh.append((rows, parents))
                    count += rows.shape[0]
                    if count > bound:
                        result.complete = False
            if progress is not None:
                progress(count, frontier.shape[0])
        if not fresh:
            break
        rows = np.concatenate([r for r, _ in fresh])
        parents = np.concatenate([p for _, p in fresh])
        if not result.complete:
            keep = bound - (count - rows.shape[0])
            rows, parents = rows[:keep], parents[:keep]
            count = bound
        offsets.append(offsets[-1] + levels[-1][0].shape[0])
        levels.append((rows, parents))
        frontier = rows
        if not result.complete:  # the last level kept is reached too; record it in slices
            for lo in range(0, frontier.shape[0], step):
                part = frontier[lo : lo + step]
                ids = offsets[-1] + lo + np.arange(part.shape[0], dtype=np.int64)
                _record_reach(result, digits_of(part), ids)

    if not tables.initials_complete:  # more initial modes than explored from
        result.complete = False
    result.states = count

    def locate(index: int) -> tuple[int, int]:
        level = int(np.searchsorted(np.array(offsets), index, side="right")) - 1
        return level, index - offsets[level]

    def parent(index: int) -> int | None:
        level, pos = locate(index)
        value = int(levels[level][1][pos])
        return None if value < 0 else value

    def mode(index: int) -> Mode:
        level, pos = locate(index)
        row = levels[level][0][pos : pos + 1]
        return tuple(int(d) for d in digits_of(row)[0].tolist())

    result._parent = parent
    result._mode = mode
    result._matching = lambda wanted: first_in_levels(levels, offsets, digits_of, wanted)
    result.seconds = time.perf_counter() - start
    return result


def _keys(rows: np.ndarray) -> np.ndarray:
    """One sortable key per row of a code array (the int itself for one word)."""
    if rows.shape[1] == 1:
        return rows[:, 0]
    rows = np.ascontiguousarray(rows)
    return rows.view(np.dtype((np.void, 8 * rows.shape[1]))).ravel()


class _Visited:
    """The set of mode codes seen: a bitmap for small products, else sorted key arrays.

    Sorted arrays are merged when a newer one grows to half the size of the
    one before (as in a log-structured merge tree), so a lookup searches a
    logarithmic number of arrays and every key is copied a logarithmic
    number of times.
    """

    def __init__(self, width: int, size: int) -> None:
        self.bitmap = np.zeros(size, dtype=bool) if width == 1 and size <= DENSE_LIMIT else None
        self.chunks: list[np.ndarray] = []

    def contains(self, rows: np.ndarray) -> np.ndarray:
        keys = _keys(rows)
        if self.bitmap is not None:
            seen: np.ndarray = self.bitmap[keys]
            return seen
        found = np.zeros(keys.shape[0], dtype=bool)
        for chunk in self.chunks:
            pos = np.minimum(np.searchsorted(chunk, keys), chunk.shape[0] - 1)
            found |= chunk[pos] == keys
        return found

    def add(self, rows: np.ndarray) -> None:
        keys = _keys(rows)
        if self.bitmap is not None:
            self.bitmap[keys] = True
            return
        self.chunks.append(np.sort(keys))
        while len(self.chunks) > 1 and self.chunks[-2].shape[0] <= 2 * self.chunks[-1].shape[0]:
            last = self.chunks.pop()
            self.chunks[-1] = np.sort(np.concatenate([self.chunks[-1], last]))


_Table = tuple[np.ndarray, np.ndarray]


def _successors(
    part: np.ndarray,
    ids: np.ndarray,
    digits: np.ndarray,
    col: np.ndarray,
    local_tabs: list[_Table],
    sync_tabs: dict[str, list[tuple[int, np.ndarray, np.ndarray]]],
    offered: dict[str, np.ndarray],
) -> tuple[np.ndarray, np.ndarray] | None:
    """Codes of all successors of ``part`` and, aligned, the index of their parent."""
    succ: list[np.ndarray] = []
    pars: list[np.ndarray] = []
    for i, (delta, mask) in enumerate(local_tabs):
        if not mask.any():
            continue
        m = mask[digits[:, i]]
        row, edge = np.nonzero(m)
        if not row.size:
            continue
        rows = part[row].copy()
        rows[:, col[i]] += delta[digits[row, i], edge]
        succ.append(rows)
        pars.append(ids[row])
    for a, parts in sync_tabs.items():
        ok = offered[a]
        if not ok.any():
            continue
        # every combination of the owners' edges, one owner at a time
        rows, parent, picked = part[ok], ids[ok], digits[ok]
        for o, delta, mask in parts:
            row, edge = np.nonzero(mask[picked[:, o]])
            rows = rows[row].copy()
            rows[:, col[o]] += delta[picked[row, o], edge]
            parent, picked = parent[row], picked[row]
        succ.append(rows)
        pars.append(parent)
    if not succ:
        return None
    return np.concatenate(succ), np.concatenate(pars)


def _delta_table(
    tables: ProductTables, component: int, label: str | None, weight: int
) -> tuple[np.ndarray, np.ndarray]:
    """Per location: code deltas of the live edges (local ones, or those with ``label``)."""
    c = tables.components[component]
    rows: list[list[int]] = []
    for loc in range(len(c.locations)):
        edges = c.local[loc] if label is None else c.sync[loc].get(label, ())
        rows.append([(c.targets[e] - loc) * weight for e in edges])
    width = max((len(r) for r in rows), default=0)
    delta = np.zeros((len(rows), max(width, 1)), dtype=np.int64)
    mask = np.zeros((len(rows), max(width, 1)), dtype=bool)
    for loc, r in enumerate(rows):
        delta[loc, : len(r)] = r
        mask[loc, : len(r)] = True
    if width == 0:
        mask[:] = False
    return delta, mask


def _record_reach(result: Exploration, digits: np.ndarray, ids: np.ndarray) -> None:
    for i, reached in enumerate(result.reached):
        if reached.all():
            continue
        column = digits[:, i]
        present = np.bincount(column, minlength=reached.size) > 0
        for loc in np.flatnonzero(present & ~reached):
            result.first_reach[(i, int(loc))] = int(ids[np.argmax(column == loc)])
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
    ids: np.ndarray,
    offered: dict[str, np.ndarray],
    stick_loc: list[np.ndarray],
    conflict_loc: list[np.ndarray],
) -> None:
    size = ids.size
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
            result.first_deadlock = int(ids[np.argmax(dead)])
    if clash.any():
        result.conflicts += int(clash.sum())
        if result.first_conflict is None:
            result.first_conflict = int(ids[np.argmax(clash)])
