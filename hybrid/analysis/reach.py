"""Reachability in a system, one group of interacting components at a time.

Components interact in the analysis only through shared labels: their inputs
are unknowns there (whatever another component's signal does), so two
components that share no label move independently. :func:`groups` splits a
system into groups of components linked by shared labels, and
:func:`explore_system` explores each group's product on its own (the other
components stay in their initial locations). The reachable modes of the
system are the combinations of the reachable modes of its groups, so they are
never multiplied out: 200 independent components are 200 explorations of 2
modes, not one of ``2**200``.

:class:`Reachability` answers what the checks ask: which locations may be
reached, which synchronising edges may fire, where a deadlock or a conflict
may happen, and a shortest witness path to each (a path inside one group).

Examples
--------
>>> import hybrid
>>> a = hybrid.load_text("automaton: a\\nlocations: {l: {}, m: {}}\\nedges: [{from: l, to: m}]\\n")
>>> b = hybrid.load_text("automaton: b\\nlocations: {p: {}, q: {}}\\nedges: [{from: p, to: q}]\\n")
>>> system = hybrid.compose(a, b)
>>> groups(system)
[(0,), (1,)]
>>> r = explore_system(ProductTables(system))
>>> r.states, r.complete, r.witness(r.first_reach[(1, 1)])
(4, True, ((None, 'a.l|b.p'), ('b.p->q#0', 'a.l|b.q')))
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hybrid.analysis.explore import (
    DEFAULT_MAX_BYTES,
    DEFAULT_MAX_STATES,
    Exploration,
    Progress,
    explore,
)
from hybrid.analysis.findings import WitnessStep
from hybrid.analysis.product import ProductTables
from hybrid.compose import System

__all__ = ["Reachability", "Ref", "explore_system", "groups"]

Ref = tuple[int, int]
"""A mode of one group's product: ``(group, code)``."""


def groups(system: System) -> list[tuple[int, ...]]:
    """Components linked by shared labels, as sorted tuples of indices, in order."""
    parent = list(range(len(system.components)))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for owners in system.shared_labels.values():
        root = find(owners[0])
        for o in owners[1:]:
            other = find(o)
            if other != root:
                parent[max(other, root)] = min(other, root)
                root = min(other, root)
    members: dict[int, list[int]] = {}
    for i in range(len(parent)):
        members.setdefault(find(i), []).append(i)
    return sorted(tuple(m) for m in members.values())


@dataclass
class Reachability:
    """What the explorations of all groups found, in the system's component indices."""

    tables: ProductTables
    parts: list[tuple[tuple[int, ...], ProductTables, Exploration]] = field(default_factory=list)
    reached: list[np.ndarray] = field(default_factory=list)
    first_reach: dict[tuple[int, int], Ref] = field(default_factory=dict)
    fired: set[tuple[int, int]] = field(default_factory=set)
    stuck_at: set[tuple[int, int]] = field(default_factory=set)
    conflicted_at: set[tuple[int, int]] = field(default_factory=set)
    first_deadlock: Ref | None = None
    first_conflict: Ref | None = None

    @property
    def complete(self) -> bool:
        return all(e.complete for _, _, e in self.parts)

    @property
    def states(self) -> int:
        """Reachable modes of the system (explored ones, if incomplete): a product over groups."""
        return math.prod(e.states for _, _, e in self.parts)

    @property
    def seconds(self) -> float:
        return sum(e.seconds for _, _, e in self.parts)

    @property
    def bound(self) -> int:
        """The most modes one group's exploration could keep."""
        return max((e.bound for _, _, e in self.parts), default=0)

    @property
    def largest_group(self) -> int:
        return max((len(m) for m, _, _ in self.parts), default=0)

    @property
    def deadlocks(self) -> int:
        """Reachable modes of the system where some component may be stuck."""
        return self._modes_with([e.deadlocks for _, _, e in self.parts])

    @property
    def conflicts(self) -> int:
        """Reachable modes of the system where two edges may be enabled at once."""
        return self._modes_with([e.conflicts for _, _, e in self.parts])

    def _modes_with(self, counts: list[int]) -> int:
        """Modes of the system with a mode counted in some group (all minus those with none)."""
        states = [e.states for _, _, e in self.parts]
        return math.prod(states) - math.prod(n - c for n, c in zip(states, counts, strict=True))

    def witness(self, ref: Ref) -> tuple[WitnessStep, ...]:
        """A shortest path (inside one group) from an initial mode to ``ref``."""
        _, tables, exploration = self.parts[ref[0]]
        steps: list[WitnessStep] = [(None, tables.name(exploration.origin(ref[1])))]
        for transition, mode in exploration.path_to(ref[1]):
            steps.append((tables.transition_name(transition), tables.name(mode)))
        return tuple(steps)


def explore_system(
    tables: ProductTables,
    max_states: int = DEFAULT_MAX_STATES,
    *,
    max_bytes: int = DEFAULT_MAX_BYTES,
    progress: Progress | None = None,
) -> Reachability:
    """Explore every group of ``tables``' system on its own (see the module's docstring)."""
    result = Reachability(tables)
    result.reached = [np.zeros(n, dtype=bool) for n in tables.radices]
    for g, members in enumerate(groups(tables.system)):
        view = tables if len(members) == len(tables.components) else tables.subset(members)
        exploration = explore(view, max_states, max_bytes=max_bytes, progress=progress)
        result.parts.append((members, view, exploration))
        for local, i in enumerate(members):
            result.reached[i] |= exploration.reached[local]
        for (local, loc), code in exploration.first_reach.items():
            result.first_reach[(members[local], loc)] = (g, code)
        result.fired.update((members[c], e) for c, e in exploration.fired)
        result.stuck_at.update((members[c], k) for c, k in exploration.stuck_at)
        result.conflicted_at.update((members[c], k) for c, k in exploration.conflicted_at)
        if result.first_deadlock is None and exploration.first_deadlock is not None:
            result.first_deadlock = (g, exploration.first_deadlock)
        if result.first_conflict is None and exploration.first_conflict is not None:
            result.first_conflict = (g, exploration.first_conflict)
    return result
