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

from hybrid.analysis.explore import DEFAULT_MAX_STATES, Exploration, explore
from hybrid.analysis.findings import WitnessStep
from hybrid.analysis.graph import location_graph
from hybrid.analysis.product import ProductTables
from hybrid.analysis.static import AutomatonFacts
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
    exploration: Exploration

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

        The path follows edges whose guards can hold within the declared bounds
        (and, in a system, that can synchronise); guards are judged one at a
        time, so the path is a candidate run, not a proven one.
        """
        tables = self.tables
        for i, comp in enumerate(tables.components):
            for k in range(len(comp.locations)):
                if tables.location_name(i, k) == location:
                    code = self.exploration.first_reach.get((i, k))
                    return None if code is None else self.witness(code)
        raise KeyError(location)

    def witness(self, code: int) -> tuple[WitnessStep, ...]:
        """The path to mode ``code``: ``(None, initial)`` then ``(transition, mode)`` steps."""
        tables = self.tables
        steps: list[WitnessStep] = [(None, tables.name(tables.initial))]
        for transition, mode in self.exploration.path_to(code):
            steps.append((tables.transition_name(transition), tables.name(mode)))
        return tuple(steps)


def analyse(model: Automaton | System, *, max_states: int = DEFAULT_MAX_STATES) -> Analysis:
    """Static facts, location graphs and the product exploration of ``model``.

    Parameters
    ----------
    model
        An automaton or a system.
    max_states
        Stop exploring the product after this many modes.
    """
    system = as_system(model)
    facts = [AutomatonFacts(c.automaton) for c in system.components]
    graphs = [location_graph(c.automaton, f) for c, f in zip(system.components, facts, strict=True)]
    tables = ProductTables(system, facts)
    exploration = explore(tables, max_states)
    return Analysis(model, system, facts, graphs, tables, exploration)


def path_text(witness: tuple[WitnessStep, ...]) -> str:
    """``a -[e1]-> b -[e2]-> c``."""
    parts = []
    for transition, mode in witness:
        parts.append(mode if transition is None else f"-[{transition}]-> {mode}")
    return " ".join(parts)
