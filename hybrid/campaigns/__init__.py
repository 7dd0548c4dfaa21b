"""Campaigns: parameter sweeps and falsification over many runs, local or on Dask.

``hybrid.sweep`` and ``hybrid.falsify`` are the entry points (docs/campaigns.md);
the table of a sweep is a :class:`~hybrid.campaigns.table.SweepTable`, the result of
a falsification a :class:`~hybrid.campaigns.falsify.Falsification`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from hybrid.lazy import lazy_attributes

if TYPE_CHECKING:
    from hybrid.campaigns.falsify import Falsification, falsify
    from hybrid.campaigns.space import Axis
    from hybrid.campaigns.sweep import sweep
    from hybrid.campaigns.table import SweepTable

__all__ = ["Axis", "Falsification", "SweepTable", "falsify", "sweep"]

_lazy_getattr, _lazy_dir = lazy_attributes(
    __name__,
    {
        "Axis": "hybrid.campaigns.space",
        "Falsification": "hybrid.campaigns.falsify",
        "SweepTable": "hybrid.campaigns.table",
        "falsify": "hybrid.campaigns.falsify",
        "sweep": "hybrid.campaigns.sweep",
    },
)


def __getattr__(name: str) -> object:
    return _lazy_getattr(name)


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
