"""Which trajectory columns belong to which component, and the units of state and signals.

A :class:`~hybrid.simulation.result.Run` keeps these facts of its model so that
it can be drawn (one figure per component of a system, axis labels with the
``unit:`` of each state variable and signal) without the model at hand.

Examples
--------
>>> import hybrid
>>> layout = run_layout(hybrid.load("docs/examples/tank_system.yaml"))
>>> layout["components"]   # plant: state h and signal level; ctrl: signal command
(('plant', ('h', 'level')), ('ctrl', ('command',)))
>>> from hybrid.compose import as_system
>>> run_layout(as_system(hybrid.load("specs/bouncing_ball.yaml")))  # a system of one
{'units': {'h': 'm', 'v': 'm/s'}, 'components': ()}
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from hybrid.compose import System

__all__ = ["run_layout"]


def run_layout(system: System) -> dict[str, Any]:
    """``units`` (state variable or signal to its ``unit:``) and ``components`` (per component of a
    system: its name and its columns, state variables first, then signal columns;
    empty for a plain automaton): the keyword arguments a :class:`Run` takes."""
    units = {s.name: s.unit for s in system.states if s.unit}
    for component in system.components:
        units.update(component.automaton.signal_units)
    if system.single:
        return {"units": units, "components": ()}
    components = []
    for component in system.components:
        automaton = component.automaton
        columns = [s.name for s in automaton.states]
        for name in automaton.signal_names:
            size = automaton.vector_sizes.get(name)
            columns.extend([name] if size is None else [f"{name}[{k}]" for k in range(size)])
        components.append((component.name, tuple(columns)))
    return {"units": units, "components": tuple(components)}
