"""The reachable product of a system, explored on the fly from the initial mode.

A *mode* is one location per component. The product is never built whole:
the explorer starts at the initial mode and follows transitions breadth-first,
so only reachable modes are ever visited. It works on discrete structure
precomputed per component (:class:`ProductTables`): per location, the live
edges (guard can hold within bounds) split into local ones and ones carrying
a label shared with other components (those fire together, one edge from
each owner of the label, as in :func:`hybrid.modes.transitions_of`).

Modes are tuples of location indices, encoded as integers in mixed radix, and
each BFS level is processed with numpy, in slices of :data:`SLICE` modes:
successors, the visited set (a bitmap when the product is small enough, else
sorted arrays merged as they grow), and the per-mode verdicts (deadlock,
nondeterminism), which are decided once per distinct (location, available
shared labels) and looked up for every mode. :func:`explore_reference` is a
plain-Python BFS with the same results, kept as a cross-check and for
products too large for 62-bit codes.

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

import time
from collections.abc import Iterator

import numpy as np

from hybrid.analysis.exploration import (
    CODE_LIMIT,
    DEFAULT_MAX_BYTES,
    DEFAULT_MAX_STATES,
    SLICE,
    Exploration,
    Progress,
    explore_reference,
    state_bound,
)
from hybrid.analysis.product import ProductTables

__all__ = [
    "DEFAULT_MAX_BYTES",
    "DEFAULT_MAX_STATES",
    "Exploration",
    "Progress",
    "explore",
    "explore_reference",
    "state_bound",
]

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
    bound = state_bound(tables, max_states, max_bytes)
    if tables.size >= CODE_LIMIT:
        return explore_reference(tables, bound, progress=progress)
    start = time.perf_counter()
    result = Exploration(tables, bound=bound)
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

    visited = _Visited(tables.size)
    levels: list[tuple[np.ndarray, np.ndarray]] = []
    init = tables.encode(tables.initial)
    frontier = np.array([init], dtype=np.int64)
    visited.add(frontier)
    levels.append((frontier, np.array([-1], dtype=np.int64)))
    count = 1

    while frontier.size and result.complete:
        fresh_parts: list[tuple[np.ndarray, np.ndarray]] = []
        for lo in range(0, frontier.size, SLICE):
            part = frontier[lo : lo + SLICE]
            digits = (part[:, None] // weights) % radices
            offered = {}
            for a, parts in sync_tabs.items():
                ok = np.ones(part.size, dtype=bool)
                for o, _, mask in parts:
                    ok &= mask[digits[:, o]].any(axis=1)
                offered[a] = ok
            _record_reach(result, digits, part)
            _record_fired(tables, result, digits, offered)
            _record_verdicts(tables, result, digits, part, offered, stick_loc, conflict_loc)
            if not result.complete:
                continue  # the bound was met: finish recording the last level only
            stepped = _successors(part, digits, local_tabs, sync_tabs, offered)
            if stepped is not None:
                candidates, parents = stepped
                unique, first = np.unique(candidates, return_index=True)
                parents = parents[first]
                fresh = ~visited.contains(unique)
                unique, parents = unique[fresh], parents[fresh]
                if unique.size:
                    visited.add(unique)
                    fresh_parts.append((unique, parents))
                    count += unique.size
                    if count > bound:
                        result.complete = False
            if progress is not None:
                progress(count, frontier.size)
        if not fresh_parts:
            break
        unique = np.concatenate([u for u, _ in fresh_parts])
        parents = np.concatenate([p for _, p in fresh_parts])
        order = np.argsort(unique, kind="stable")
        unique, parents = unique[order], parents[order]
        if not result.complete:
            keep = max(0, bound - (count - unique.size))
            unique, parents = unique[:keep], parents[:keep]
            count -= count - bound
        levels.append((unique, parents))
        frontier = unique
        if not result.complete and frontier.size:
            digits = (frontier[:, None] // weights) % radices
            _record_reach(result, digits, frontier)

    result.states = count
    result.seconds = time.perf_counter() - start

    def parent(code: int) -> int | None:
        for codes, pars in levels:
            pos = int(np.searchsorted(codes, code))
            if pos < codes.size and int(codes[pos]) == code:
                value = int(pars[pos])
                return None if value < 0 else value
        return None

    def codes() -> Iterator[int]:
        for level, _ in levels:
            yield from (int(c) for c in level.tolist())

    result._parent = parent
    result._codes = codes
    return result


class _Visited:
    """The set of mode codes seen: a bitmap for small products, else sorted arrays.

    Sorted arrays are merged when a newer one grows to half the size of the
    one before (as in a log-structured merge tree), so a lookup searches a
    logarithmic number of arrays and every code is copied a logarithmic
    number of times.
    """

    def __init__(self, size: int) -> None:
        self.bitmap = np.zeros(size, dtype=bool) if size <= DENSE_LIMIT else None
        self.chunks: list[np.ndarray] = []

    def contains(self, codes: np.ndarray) -> np.ndarray:
        if self.bitmap is not None:
            seen: np.ndarray = self.bitmap[codes]
            return seen
        found = np.zeros(codes.size, dtype=bool)
        for chunk in self.chunks:
            pos = np.minimum(np.searchsorted(chunk, codes), chunk.size - 1)
            found |= chunk[pos] == codes
        return found

    def add(self, codes: np.ndarray) -> None:
        if self.bitmap is not None:
            self.bitmap[codes] = True
            return
        self.chunks.append(np.sort(codes))
        while len(self.chunks) > 1 and self.chunks[-2].size <= 2 * self.chunks[-1].size:
            last = self.chunks.pop()
            self.chunks[-1] = np.sort(np.concatenate([self.chunks[-1], last]), kind="stable")


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
