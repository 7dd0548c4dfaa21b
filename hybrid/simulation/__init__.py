"""Event-detected simulation of hybrid automata and systems.

Modules: :mod:`~hybrid.simulation.settings` (what a run is asked to do),
:mod:`~hybrid.simulation.compiled` (the model's functions per mode),
:mod:`~hybrid.simulation.boundary` (decisions at a point),
:mod:`~hybrid.simulation.events` (the watch of a stay and its arming),
:mod:`~hybrid.simulation.dense` (step interpolants),
:mod:`~hybrid.simulation.crossing` (the search of a step for the first event),
:mod:`~hybrid.simulation.stay` (one stay, step by step),
:mod:`~hybrid.simulation.loop` (the event loop), :mod:`~hybrid.simulation.recorder`
and :mod:`~hybrid.simulation.result` (what a run returns),
:mod:`~hybrid.simulation.zeno`, :mod:`~hybrid.simulation.failures` (messages),
:mod:`~hybrid.simulation.interrupts` (Ctrl-C), :mod:`~hybrid.simulation.inputs`
(inputs from text), :mod:`~hybrid.simulation.engine` (``simulate``).
"""

from typing import TYPE_CHECKING

from hybrid.lazy import lazy_attributes

if TYPE_CHECKING:
    from hybrid.simulation.engine import simulate
    from hybrid.simulation.result import CAUSES, Jump, Run, Termination
    from hybrid.simulation.settings import METHODS

__all__ = ["CAUSES", "METHODS", "Jump", "Run", "Termination", "simulate"]

__getattr__, __dir__ = lazy_attributes(
    __name__,
    {
        "CAUSES": "hybrid.simulation.result",
        "METHODS": "hybrid.simulation.settings",
        "Jump": "hybrid.simulation.result",
        "Run": "hybrid.simulation.result",
        "Termination": "hybrid.simulation.result",
        "simulate": "hybrid.simulation.engine",
    },
)
