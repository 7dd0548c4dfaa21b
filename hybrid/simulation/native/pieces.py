"""Kernel source: the decisions at a point as one piece, :func:`decide` (by ``ASK_*``).

The stay and the run loop call the decisions through one function pointer
(see :mod:`~hybrid.simulation.native.kernel_types`, "Pieces"), so their code
(:mod:`~hybrid.simulation.native.boundary` and the watch's start) is compiled
once, apart from the loops that use it.

Copied into the kernel module (below the ``kernel`` marker).
"""

from __future__ import annotations

from hybrid.simulation.native.boundary import enabled_at_entry, enabled_at_event, invariant_left_at
from hybrid.simulation.native.buffers import ASK_ENTRY, ASK_EVENT, ASK_LEFT
from hybrid.simulation.native.events import watch_start
from hybrid.simulation.native.kernel_types import Array, Fns, Ints

__all__ = ["decide"]

# --- kernel ---


def decide(ask: int, fns: Fns, tab: Ints, m: int, t: float, x: Array, wf: Array, wi: Ints) -> int:
    """One decision at ``(t, x)`` in mode ``m``.

    ``ASK_ENTRY``: ``enabled_at_entry`` (the transition that fires, -1: none);
    ``ASK_EVENT``: ``enabled_at_event``; ``ASK_LEFT``: ``invariant_left_at``
    (-1: none); ``ASK_WATCH``: the watch of a stay starting here (0).
    """
    if ask == ASK_ENTRY:
        return enabled_at_entry(fns, tab, m, t, x, wf, wi)
    if ask == ASK_EVENT:
        return enabled_at_event(fns, tab, m, t, x, wf, wi)
    if ask == ASK_LEFT:
        return invariant_left_at(fns, tab, m, t, x, wf, wi)
    watch_start(fns, tab, m, t, x, wf, wi)
    return 0
