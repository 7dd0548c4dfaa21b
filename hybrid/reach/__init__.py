"""Reachability of affine hybrid automata: sound flowpipes, verdicts on forbidden sets.

``hybrid.reach(model, t_end, *, max_jumps=10, step=None, witness=True)`` is
:func:`hybrid.reach.api.reach`: ``model`` affine (``x' = A x + B u + c`` per
location, affine resets, linear guards and invariants), over ``[0, t_end]`` and
``max_jumps`` jumps, flowpipes of step ``step`` (default ``t_end / 4000``), and
with ``witness`` a search for a simulated run into each forbidden entry the
sets meet. See docs/reach.md. The pieces are :mod:`~hybrid.reach.flowpipe`
(one location's flowpipe), :mod:`~hybrid.reach.boxes` (guards, invariants,
resets on boxes), :mod:`~hybrid.reach.engine` (the hybrid loop),
:mod:`~hybrid.reach.witness` (simulated runs into a forbidden set) and
:mod:`~hybrid.reach.check` (``hybrid check`` deciding forbidden entries with it).

``hybrid.reach`` is that function, also once this package is imported (the
``hybrid`` package keeps the name for it). Its modules load on first use
(``hybrid check`` without a reach horizon needs none).

Examples
--------
>>> import hybrid
>>> m = hybrid.load_text('''
... automaton: decay
... state: {x: {initial: [1, 2]}}
... locations: {l: {flow: {x: -x}}}
... properties: {forbidden: [{when: x > 2.5}, {when: x > 1.9}]}
... ''')
>>> r = hybrid.reach(m, 1.0, max_jumps=0, step=0.01)
>>> [p.verdict for p in r.properties], r.verdict
(['proved', 'refuted'], 'refuted')
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from hybrid.lazy import lazy_attributes

if TYPE_CHECKING:
    from hybrid.reach.api import reach
    from hybrid.reach.result import PropertyResult, ReachResult, ReachSet

__all__ = ["PropertyResult", "ReachResult", "ReachSet", "reach"]

_LAZY = {
    "reach": "hybrid.reach.api",
    "PropertyResult": "hybrid.reach.result",
    "ReachResult": "hybrid.reach.result",
    "ReachSet": "hybrid.reach.result",
}
__getattr__, __dir__ = lazy_attributes(__name__, _LAZY)
