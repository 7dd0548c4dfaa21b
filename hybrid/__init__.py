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

import sys as _sys
import types as _types

from hybrid.lazy import lazy_attributes
from hybrid.version import __version__

TYPE_CHECKING = False  # typing's own constant would import typing (4 ms) before Ctrl-C is ours
if TYPE_CHECKING:
    from hybrid.analysis.findings import Report
    from hybrid.campaigns.falsify import Falsification, falsify
    from hybrid.campaigns.sweep import sweep
    from hybrid.campaigns.table import SweepTable
    from hybrid.compose import System, compose
    from hybrid.errors import HybridError, Position, SimulationError, SpecError, UsageError
    from hybrid.model import Automaton, Range
    from hybrid.reach import ReachResult, reach
    from hybrid.reach.check import check
    from hybrid.reader.loader import load, load_text
    from hybrid.simulation.bounds import BoundsWarning
    from hybrid.simulation.engine import simulate
    from hybrid.simulation.native.many import Ensemble, simulate_many
    from hybrid.simulation.result import Jump, Run, Termination
    from hybrid.simulation.settings import Settings
del TYPE_CHECKING  # not a name of the package

__all__ = [
    "Automaton",
    "BoundsWarning",
    "Ensemble",
    "Falsification",
    "HybridError",
    "Jump",
    "Position",
    "Range",
    "ReachResult",
    "Report",
    "Run",
    "Settings",
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

# Everything loads on first use: the errors (dataclasses, 12 ms), the reader
# (pydantic), the simulator (scipy) and the analysis (networkx), so that `import
# hybrid` is quick and the command line is inside its Ctrl-C handling (hybrid.__main__)
# before anything but Python's own start-up has run.
_LAZY = {
    "HybridError": "hybrid.errors",
    "Position": "hybrid.errors",
    "SimulationError": "hybrid.errors",
    "SpecError": "hybrid.errors",
    "UsageError": "hybrid.errors",
    "System": "hybrid.compose",
    "Automaton": "hybrid.model",
    "Range": "hybrid.model",
    "BoundsWarning": "hybrid.simulation.bounds",
    "load": "hybrid.reader.loader",
    "load_text": "hybrid.reader.loader",
    "Jump": "hybrid.simulation.result",
    "Run": "hybrid.simulation.result",
    "Termination": "hybrid.simulation.result",
    "Settings": "hybrid.simulation.settings",
    "simulate": "hybrid.simulation.engine",
    "simulate_many": "hybrid.simulation.native.many",
    "Ensemble": "hybrid.simulation.native.many",
    "Report": "hybrid.analysis.findings",
    "check": "hybrid.reach.check",
    "sweep": "hybrid.campaigns.sweep",
    "falsify": "hybrid.campaigns.falsify",
    "SweepTable": "hybrid.campaigns.table",
    "Falsification": "hybrid.campaigns.falsify",
    "ReachResult": "hybrid.reach.result",
}
_lazy_getattr, _lazy_dir = lazy_attributes(__name__, _LAZY)


def __getattr__(name: str) -> object:
    """A lazily loaded name of ``__all__``, or a submodule the docs name (``hybrid.export``,
    ``hybrid.progress``, ``hybrid.errors``): imported on first use, as the names are."""
    try:
        value = _lazy_getattr(name)
    except AttributeError:
        import importlib
        import importlib.util

        if name.startswith("_") or importlib.util.find_spec(f"{__name__}.{name}") is None:
            raise
        value = importlib.import_module(f"{__name__}.{name}")
    globals()[name] = value
    return value


class _Package(_types.ModuleType):
    """``hybrid.compose`` and ``hybrid.reach`` are functions, though each names a module too.

    Importing a submodule sets the package's attribute of that name to the module,
    which would hide the lazily loaded function of the same name; these properties
    keep the functions (and ignore the import system's assignment).
    """

    @property
    def compose(self) -> object:
        from hybrid.compose import compose

        return compose

    @compose.setter
    def compose(self, value: object) -> None:
        pass

    @property
    def reach(self) -> object:
        from hybrid.reach.api import reach

        return reach

    @reach.setter
    def reach(self, value: object) -> None:
        pass


_sys.modules[__name__].__class__ = _Package


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
