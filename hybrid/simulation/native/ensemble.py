"""Kernel source: many runs of one model in one compiled loop, threads over runs.

Each run has its own parameters, initial point and mode, and its own events
and termination: it is :func:`~hybrid.simulation.native.loop.run_one` (the
``run`` piece, called through its pointer) on its row of the chunk's buffers. ``prange`` spreads the runs over numba's threads
(``numba.set_num_threads`` or ``NUMBA_NUM_THREADS`` bound them). A run that
fills its row stops with ``I_OVERFLOW``; Python runs it again alone, with
room for more.

Copied into the kernel module (below the ``kernel`` marker) and
compiled with ``parallel=True``.
"""

from __future__ import annotations

from hybrid.simulation.native.buffers import FP_RUN
from hybrid.simulation.native.kernel_types import (
    RUN_FN_T,
    Array,
    Array2,
    Array3,
    Ints,
    Ints2,
    function_at,
)

__all__ = ["run_many"]

prange = range  # the generated module binds numba's prange here

# --- kernel ---


def run_many(fp: Ints, tab: Ints, params: Array2, x0s: Array2, t0: float, m0: int,
             cfg_f: Array, cfg_i: Ints, pts: Array3, jps: Array3, sts: Array3, oi: Ints2,
             of: Array2, flag: Ints, wf: Array2, wi: Ints2) -> None:  # fmt: skip
    """Run ``len(params)`` simulations; run ``r`` fills row ``r`` of every array."""
    run = function_at(fp[FP_RUN], fp[FP_RUN + 1], RUN_FN_T)
    for r in prange(params.shape[0]):
        run(fp, tab, params[r], x0s[r], t0, m0, cfg_f, cfg_i, pts[r], jps[r], sts[r], oi[r],
            of[r], flag, wf[r], wi[r])  # fmt: skip
