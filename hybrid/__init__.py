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

from hybrid.compose import System, compose
from hybrid.errors import Position, SimulationError, SpecError
from hybrid.model import Automaton
from hybrid.simulate import Jump, Run, Termination, simulate
from hybrid.spec.loader import load, load_text

__all__ = [
    "Automaton",
    "Position",
    "SimulationError",
    "SpecError",
    "System",
    "compose",
    "Jump",
    "Run",
    "Termination",
    "load",
    "load_text",
    "simulate",
]

__version__ = "0.1.0"
