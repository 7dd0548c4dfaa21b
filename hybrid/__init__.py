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

from typing import TYPE_CHECKING

from hybrid.compose import System, compose
from hybrid.errors import HybridError, Position, SimulationError, SpecError, UsageError
from hybrid.lazy import lazy_attributes
from hybrid.model import Automaton, Range
from hybrid.reader.loader import load, load_text
from hybrid.version import __version__

if TYPE_CHECKING:
    from hybrid.analysis.findings import Report
    from hybrid.campaigns.falsify import Falsification, falsify
    from hybrid.campaigns.sweep import sweep
    from hybrid.campaigns.table import SweepTable
    from hybrid.reach import ReachResult, reach
    from hybrid.reach.check import check
    from hybrid.simulation.engine import simulate
    from hybrid.simulation.native.many import Ensemble, simulate_many
    from hybrid.simulation.result import Jump, Run, Termination

__all__ = [
    "Automaton",
    "Ensemble",
    "Falsification",
    "HybridError",
    "Jump",
    "Position",
    "Range",
    "ReachResult",
    "Report",
    "Run",
    "SimulationError",
    "SpecError",
    "SweepTable",
    "System",
    "Termination",
    "UsageError",
    "__version__",
    "check",
    "compose",
    "falsify",
    "load",
    "load_text",
    "reach",
    "simulate",
    "simulate_many",
    "sweep",
]

# The simulator (scipy) and the analysis (networkx) load on first use, so that
# `hybrid validate` and `import hybrid` stay quick.
_LAZY = {
    "Jump": "hybrid.simulation.result",
    "Run": "hybrid.simulation.result",
    "Termination": "hybrid.simulation.result",
    "simulate": "hybrid.simulation.engine",
    "simulate_many": "hybrid.simulation.native.many",
    "Ensemble": "hybrid.simulation.native.many",
    "Report": "hybrid.analysis.findings",
    "check": "hybrid.reach.check",
    "sweep": "hybrid.campaigns.sweep",
    "falsify": "hybrid.campaigns.falsify",
    "SweepTable": "hybrid.campaigns.table",
    "Falsification": "hybrid.campaigns.falsify",
    "reach": "hybrid.reach.api",
    "ReachResult": "hybrid.reach.result",
}
_lazy_getattr, _lazy_dir = lazy_attributes(__name__, _LAZY)


def __getattr__(name: str) -> object:
    value = _lazy_getattr(name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
