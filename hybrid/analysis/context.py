"""Everything the checks read, computed once per model: :func:`analyse`.

The static facts of every component (:mod:`hybrid.analysis.static`), the
location graphs (:mod:`hybrid.analysis.graph`), and the exploration of the
reachable product (:mod:`hybrid.analysis.explore`).

Examples
--------
>>> import hybrid
>>> analysis = analyse(hybrid.load("specs/thermostat.yaml"))
>>> analysis.exploration.states, path_text(analysis.witness_to("on"))
(2, 'off -[turn_on]-> on')
"""

from __future__ import annotations

from dataclasses import dataclass

import networkx as nx

from hybrid.analysis.components import component_facts
from hybrid.analysis.explore import DEFAULT_MAX_BYTES, DEFAULT_MAX_STATES, Progress
from hybrid.analysis.findings import WitnessStep
from hybrid.analysis.graph import location_graph
from hybrid.analysis.product import ProductTables
from hybrid.analysis.reach import Reachability, Ref, explore_system
from hybrid.analysis.static import AutomatonFacts
from hybrid.analysis.zerotime import ZeroTimeGraph
from hybrid.compose import System, as_system
from hybrid.model import Automaton

__all__ = ["Analysis", "analyse", "path_text"]


@dataclass
class Analysis:
    """Everything the checks read, computed once per model."""

    model: Automaton | System
    system: System
    facts: list[AutomatonFacts]
    graphs: list[nx.MultiDiGraph]
    tables: ProductTables
    exploration: Reachability
    _zero_time: list[ZeroTimeGraph] | None = None

    @property
    def zero_time(self) -> list[ZeroTimeGraph]:
        """The zero-time graph of every component (built on first use)."""
        if self._zero_time is None:
            self._zero_time = [ZeroTimeGraph(f) for f in self.facts]
        return self._zero_time

    def reached(self, component: int, location: str) -> bool:
        """Whether the location may be reached (always true if exploration stopped early)."""
        if not self.exploration.complete:
            return True
        loc = self.tables.components[component].index[location]
        return bool(self.exploration.reached[component][loc])

    def qualified(self, component: int, name: str) -> str:
        """A location or edge name as the user writes it (``comp.name`` in a system)."""
        return self.system.qualified(component, name)

    def witness_to(self, location: str) -> tuple[WitnessStep, ...] | None:
        """A shortest path to a location (``comp.loc`` in a system), or ``None`` if unreachable.

        The path follows edges that can fire (and, in a system, that can
        synchronise); guards are judged one edge at a time, so the path is a
        candidate run, not a proven one.
        """
        tables = self.tables
        for i, comp in enumerate(tables.components):
            for k in range(len(comp.locations)):
                if tables.location_name(i, k) == location:
                    ref = self.exploration.first_reach.get((i, k))
                    return None if ref is None else self.witness(ref)
        raise KeyError(location)

    def witness(self, ref: Ref) -> tuple[WitnessStep, ...]:
        """The path to a mode: ``(None, initial)`` then ``(transition, mode)`` steps."""
        return self.exploration.witness(ref)


def analyse(
    model: Automaton | System,
    *,
    max_states: int = DEFAULT_MAX_STATES,
    max_bytes: int = DEFAULT_MAX_BYTES,
    progress: Progress | None = None,
) -> Analysis:
    """Static facts, location graphs and the reachable product of ``model``.

    Parameters
    ----------
    model
        An automaton or a system.
    max_states
        Stop exploring a group's product after this many modes.
    max_bytes
        Stop exploring a group's product before its modes take more memory than this.
    progress
        Called as ``progress(modes, frontier)`` while exploring (for a progress display).
    """
    system = as_system(model)
    facts = [component_facts(system, i) for i in range(len(system.components))]
    graphs = [location_graph(c.automaton, f) for c, f in zip(system.components, facts, strict=True)]
    tables = ProductTables(system, facts)
    exploration = explore_system(tables, max_states, max_bytes=max_bytes, progress=progress)
    return Analysis(model, system, facts, graphs, tables, exploration)


def path_text(witness: tuple[WitnessStep, ...]) -> str:
    """``a -[e1]-> b -[e2]-> c``."""
    parts = []
    for transition, mode in witness:
        parts.append(mode if transition is None else f"-[{transition}]-> {mode}")
    return " ".join(parts)
