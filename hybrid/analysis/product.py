"""The discrete structure of a system's product, per component, for exploration.

A *mode* is one location per component. :class:`ProductTables` precomputes,
per component and location, the live edges (guard can hold within bounds)
split into local ones and ones carrying a label shared with other components
(those fire together, one edge from each owner of the label, as in
:func:`hybrid.modes.transitions_of`), and answers per-mode questions
(successors, deadlock, nondeterminism) from them. Modes are tuples of
location indices, encoded as integers in mixed radix.
:mod:`hybrid.analysis.explore` walks the product from the initial mode.

Examples
--------
>>> import hybrid
>>> a = hybrid.load_text("automaton: a\\nlocations: {idle: {}, busy: {}}\\nedges: [{from: idle, to: busy}]\\n")
>>> tables = ProductTables(hybrid.compose(a))
>>> [tables.name(tr.target) for tr in tables.successors(tables.initial)]
['a.busy']
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass, field

from hybrid.analysis.components import component_facts
from hybrid.analysis.static import AutomatonFacts
from hybrid.compose import System

__all__ = ["MAX_INITIAL_MODES", "Mode", "ProductTables", "Transition"]

Mode = tuple[int, ...]

MAX_INITIAL_MODES = 100_000
"""Most initial modes explored from (each component in one of its initial locations)."""


@dataclass(frozen=True)
class Transition:
    """One product transition: the (component, edge index) parts firing together."""

    parts: tuple[tuple[int, int], ...]
    label: str | None
    target: Mode


@dataclass
class _Component:
    name: str
    facts: AutomatonFacts
    locations: tuple[str, ...]
    local: list[tuple[int, ...]]  # per location: live local edges
    sync: list[dict[str, tuple[int, ...]]]  # per location: shared label -> live edges
    labels: tuple[str, ...]  # shared labels of this component, in bit order
    targets: list[int]  # per edge index: target location index
    conflicts: list[list[tuple[int, int]]]  # per location: overlapping same-priority pairs
    index: dict[str, int] = field(default_factory=dict)  # location name -> position

    def __post_init__(self) -> None:
        self.index = {name: i for i, name in enumerate(self.locations)}


class ProductTables:
    """Discrete structure of a system, per component, for fast exploration.

    Parameters
    ----------
    system
        The system (a plain automaton is a system of one, see :func:`hybrid.compose.as_system`).
    facts
        Optional precomputed :class:`AutomatonFacts`, one per component.
    """

    def __init__(self, system: System, facts: Sequence[AutomatonFacts] | None = None) -> None:
        self.system = system
        facts = (
            list(facts)
            if facts is not None
            else [component_facts(system, i) for i in range(len(system.components))]
        )
        self.owners = system.shared_labels
        self.components: list[_Component] = []
        for comp, fa in zip(system.components, facts, strict=True):
            automaton = comp.automaton
            locs = tuple(automaton.locations)
            index = {name: k for k, name in enumerate(locs)}
            shared = tuple(a for a in automaton.labels if a in self.owners)
            local: list[tuple[int, ...]] = []
            sync: list[dict[str, tuple[int, ...]]] = []
            conflicts: list[list[tuple[int, int]]] = []
            for name in locs:
                live = [f.edge for f in fa.outgoing(name) if f.live]
                local.append(tuple(e.index for e in live if e.label not in self.owners))
                per: dict[str, list[int]] = {}
                for e in live:
                    if e.label is not None and e.label in self.owners:
                        per.setdefault(e.label, []).append(e.index)
                sync.append({a: tuple(v) for a, v in per.items()})
                conflicts.append(fa.conflicts(name))
            targets = [index[e.target] for e in automaton.edges]
            self.components.append(
                _Component(comp.name, fa, locs, local, sync, shared, targets, conflicts)
            )
        self.members: tuple[int, ...] = tuple(range(len(self.components)))
        self.base: tuple[str, ...] = tuple(system.initial_mode)
        self._layout()

    def _layout(self) -> None:
        self.radices = [len(c.locations) for c in self.components]
        self.size = 1
        self.weights: list[int] = []
        for n in self.radices:
            self.weights.append(self.size)
            self.size *= n
        self.initial: Mode = tuple(
            comp.index[self.base[g]] for comp, g in zip(self.components, self.members, strict=True)
        )
        choices = [
            [comp.index[n] for n in self.system.components[g].automaton.initial_locations]
            for comp, g in zip(self.components, self.members, strict=True)
        ]
        starts = itertools.islice(itertools.product(*choices), MAX_INITIAL_MODES + 1)
        self.initials: list[Mode] = list(dict.fromkeys([self.initial, *starts]))
        """The initial modes (each component in one of its initial locations), ``initial``
        first; at most :data:`MAX_INITIAL_MODES` (``initials_complete`` says if all)."""
        self.initials_complete = len(self.initials) <= MAX_INITIAL_MODES
        del self.initials[MAX_INITIAL_MODES:]
        self._stuck: dict[tuple[int, int, int], bool] = {}
        self._conflict: dict[tuple[int, int, int], bool] = {}

    def subset(self, members: Sequence[int]) -> ProductTables:
        """The same tables restricted to some components (the others stay in their initial
        locations); labels shared with a component left out must not be among them."""
        view = object.__new__(ProductTables)
        view.system = self.system
        local = {g: k for k, g in enumerate(members)}
        view.components = [self.components[self.members.index(g)] for g in members]
        view.owners = {
            a: tuple(local[o] for o in owners)
            for a, owners in self.system.shared_labels.items()
            if all(o in local for o in owners)
        }
        view.members = tuple(members)
        view.base = self.base
        view._layout()
        return view

    # --- modes ---------------------------------------------------------------------------

    def encode(self, mode: Mode) -> int:
        return sum(loc * w for loc, w in zip(mode, self.weights, strict=True))

    def decode(self, code: int) -> Mode:
        return tuple((code // w) % n for w, n in zip(self.weights, self.radices, strict=True))

    def name(self, mode: Mode) -> str:
        """``loc`` for a plain automaton, ``comp.loc|comp.loc`` for a system."""
        full = list(self.base)
        for c, g, k in zip(self.components, self.members, mode, strict=True):
            full[g] = c.locations[k]
        return self.system.mode_name(tuple(full))

    def location_name(self, component: int, location: int) -> str:
        """A component location as the user writes it (qualified in a system)."""
        return self.system.qualified(
            self.members[component], self.components[component].locations[location]
        )

    def edge_name(self, component: int, edge: int) -> str:
        name = self.components[component].facts.automaton.edges[edge].name
        return self.system.qualified(self.members[component], name)

    def transition_name(self, transition: Transition) -> str:
        return "+".join(self.edge_name(i, e) for i, e in transition.parts)

    # --- transitions ---------------------------------------------------------------------

    def offered(self, mode: Mode) -> frozenset[str]:
        """Shared labels every owner can take (by a live edge) in ``mode``."""
        return frozenset(
            a
            for a, owners in self.owners.items()
            if all(self.components[o].sync[mode[o]].get(a) for o in owners)
        )

    def successors(self, mode: Mode) -> list[Transition]:
        """The live transitions leaving ``mode``, local ones first, in component order."""
        result: list[Transition] = []
        for i, c in enumerate(self.components):
            for e in c.local[mode[i]]:
                target = list(mode)
                target[i] = c.targets[e]
                label = c.facts.automaton.edges[e].label
                result.append(Transition(((i, e),), label, tuple(target)))
        for a in sorted(self.offered(mode)):
            owners = self.owners[a]
            choices = [self.components[o].sync[mode[o]][a] for o in owners]
            for combo in itertools.product(*choices):
                target = list(mode)
                for o, e in zip(owners, combo, strict=True):
                    target[o] = self.components[o].targets[e]
                result.append(Transition(tuple(zip(owners, combo, strict=True)), a, tuple(target)))
        return result

    # --- per-mode verdicts ---------------------------------------------------------------

    def bits(self, component: int, offered: frozenset[str]) -> int:
        """The offered shared labels of ``component`` as a bit mask (its label order)."""
        return sum(1 << j for j, a in enumerate(self.components[component].labels) if a in offered)

    def _available(self, component: int, location: int, bits: int) -> list[int]:
        c = self.components[component]
        edges = list(c.local[location])
        for j, a in enumerate(c.labels):
            if bits >> j & 1:
                edges.extend(c.sync[location].get(a, ()))
        return edges

    def stuck(self, component: int, location: int, bits: int) -> bool:
        """Whether the component may reach an exit of its location with no transition enabled."""
        key = (component, location, bits)
        found = self._stuck.get(key)
        if found is None:
            c = self.components[component]
            name = c.locations[location]
            found = not c.facts.covered(name, self._available(component, location, bits))
            self._stuck[key] = found
        return found

    def conflicted(self, component: int, location: int, bits: int) -> bool:
        """Whether two same-priority transitions moving the component may be enabled at once."""
        key = (component, location, bits)
        found = self._conflict.get(key)
        if found is None:
            available = set(self._available(component, location, bits))
            found = any(
                a in available and b in available
                for a, b in self.components[component].conflicts[location]
            )
            self._conflict[key] = found
        return found

    def may_stick(self, component: int, location: int) -> bool:
        """Cheap pre-test: can :meth:`stuck` be true for some offered labels?"""
        return self.stuck(component, location, 0)  # fewest edges available: most stuck

    def may_conflict(self, component: int, location: int) -> bool:
        return bool(self.components[component].conflicts[location])
