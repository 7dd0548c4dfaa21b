"""hybrid: hybrid automata in YAML, simulated with exact events, checked in CI.

Examples
--------
>>> import hybrid
>>> model = hybrid.load_text('''
... automaton: tank
... state: {level: {initial: 1.0}}
... locations: {draining: {flow: {level: -0.5}, invariant: level >= 0}}
... ''')
>>> model.name
'tank'
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from hybrid.compose import System, compose
from hybrid.errors import Position, SimulationError, SpecError
from hybrid.model import Automaton
from hybrid.spec.loader import load, load_text

if TYPE_CHECKING:
    from hybrid.analysis import Report, check
    from hybrid.simulation import Jump, Run, Termination, simulate

__all__ = [
    "Automaton",
    "Jump",
    "Position",
    "Report",
    "Run",
    "SimulationError",
    "SpecError",
    "System",
    "Termination",
    "check",
    "compose",
    "load",
    "load_text",
    "simulate",
]

__version__ = "0.1.0"

# The simulator (scipy) and the analysis (networkx) load on first use, so that
# `hybrid validate` and `import hybrid` stay quick.
_LAZY = {
    "Jump": "hybrid.simulation",
    "Run": "hybrid.simulation",
    "Termination": "hybrid.simulation",
    "simulate": "hybrid.simulation",
    "Report": "hybrid.analysis",
    "check": "hybrid.analysis",
}


def __getattr__(name: str) -> Any:
    module = _LAZY.get(name)
    if module is None:
        raise AttributeError(f"module 'hybrid' has no attribute '{name}'")
    import importlib

    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
