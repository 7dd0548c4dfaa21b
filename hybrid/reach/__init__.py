"""Reachability of affine hybrid automata: sound flowpipes, verdicts on forbidden sets.

See docs/reach.md. :func:`reach` is ``hybrid.reach``; the pieces are
:mod:`~hybrid.reach.flowpipe` (one location's flowpipe), :mod:`~hybrid.reach.boxes`
(guards, invariants, resets on boxes), :mod:`~hybrid.reach.engine` (the hybrid
loop), :mod:`~hybrid.reach.witness` (simulated runs into a forbidden set).

The package is callable: ``hybrid.reach(model, ...)`` is :func:`reach`, whether
``hybrid.reach`` names this package (once imported) or the function.
"""

from __future__ import annotations

import sys
import types
from typing import Any

from hybrid.reach.api import reach
from hybrid.reach.result import PropertyResult, ReachResult, ReachSet

__all__ = ["PropertyResult", "ReachResult", "ReachSet", "reach"]


class _CallablePackage(types.ModuleType):
    """This package, called as :func:`reach` (``hybrid.reach(model, t_end=...)``)."""

    def __call__(self, *args: Any, **kwargs: Any) -> ReachResult:
        return reach(*args, **kwargs)


sys.modules[__name__].__class__ = _CallablePackage
