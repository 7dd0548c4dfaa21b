"""Which requirements a system watches, and under which names (no monitor needed).

The monitor (:mod:`hybrid.simulation.monitor`) evaluates them; campaigns and the
compiled backend only ask which there are, so this module imports neither scipy
nor the expression compiler.

Examples
--------
>>> import hybrid
>>> from hybrid.compose import as_system
>>> heater = hybrid.load_text('''
... automaton: heater
... state: {x: {initial: 20.0}}
... locations: {cooling: {flow: {x: -0.1*x}}}
... requirements: [{name: warm, always: "x >= 15"}]
... ''')
>>> [w.name for w in watched_requirements(as_system(heater))]
['warm']
"""

from __future__ import annotations

from dataclasses import dataclass

from hybrid.compose import System
from hybrid.model import Requirement

__all__ = ["Watched", "watched_requirements"]


@dataclass(frozen=True)
class Watched:
    """A requirement as the monitor of a system sees it.

    ``name`` is what results are reported under: the plain name in an automaton
    and for a system file's own requirements, ``comp.name`` for a component's
    requirement inside a system. ``component`` is the component whose
    parameters the condition reads (None for a system file's requirement);
    ``location`` is the ``in:`` location as ``(component index, location)``.
    """

    name: str
    requirement: Requirement
    component: int | None
    location: tuple[int, str] | None


def watched_requirements(system: System) -> list[Watched]:
    """Every requirement of ``system``: each component's (in order), then the system file's."""
    found: list[Watched] = []
    for i, c in enumerate(system.components):
        for r in c.automaton.requirements:
            where = (i, r.location) if r.location is not None else None
            found.append(Watched(system.qualified(i, r.name), r, i, where))
    names = [c.name for c in system.components]
    for r in system.requirements:
        where = None
        if r.location is not None:
            comp, _, loc = r.location.partition(".")
            where = (names.index(comp), loc)
        found.append(Watched(r.name, r, None, where))
    return found
