"""Hylaa on one affine instance given as arrays: run by ``bench.reach_building`` in Hylaa's own venv.

Hylaa (``pip install hylaa swiglpk==5.0.10``; 5.0.12 and 5.0.13 break its LPs)
needs none of hybrid: this script reads ``A``, ``B``, the input box, the
initial box and the forbidden set ``G x <= g`` (a conjunction) from an ``.npz`` file
and prints one JSON line: Hylaa's verdict (a concrete error found or not), the
CPU seconds of ``Core.run`` and the step. Hylaa's default mode checks the step
points only (its continuous-time option bounds the error with a matrix norm).
GLPK's wall-clock limit per LP is lifted (:func:`_without_lp_time_limit`).

    python bench/hylaa_driver.py INSTANCE.npz
"""

from __future__ import annotations

import json
import sys
import time

import numpy as np
from scipy.sparse import csr_matrix


def _without_lp_time_limit() -> None:
    """Lift GLPK's limit per LP (Hylaa sets 1 s, then 30 s on a retry).

    GLPK measures it in wall-clock time: on a shared, loaded machine Hylaa's later
    LPs (larger as the steps add input columns) exceed it and the run ends with
    "glp_simplex returned nonzero status (9)", whatever CPU time they took.
    """
    import swiglpk

    simplex = swiglpk.glp_simplex

    def unlimited(lp: object, params: object) -> int:
        params.tm_lim = 2**31 - 1  # type: ignore[attr-defined]
        return int(simplex(lp, params))

    swiglpk.glp_simplex = unlimited


def main(path: str) -> None:
    _without_lp_time_limit()
    from hylaa import lputil
    from hylaa.core import Core
    from hylaa.hybrid_automaton import HybridAutomaton
    from hylaa.settings import HylaaSettings, PlotSettings
    from hylaa.stateset import StateSet

    data = np.load(path)
    a, b = data["a"], data["b"]
    u_lo, u_hi = data["u_lo"], data["u_hi"]
    x_lo, x_hi = data["x_lo"], data["x_hi"]
    mat, rhs = np.atleast_2d(data["mat"]), np.atleast_1d(data["rhs"])
    step, t_end = float(data["step"]), float(data["t_end"])
    n, m = b.shape
    ha = HybridAutomaton()
    mode = ha.new_mode("mode")
    mode.set_dynamics(csr_matrix(a))
    u_mat = np.vstack([np.eye(m), -np.eye(m)])
    u_rhs = np.concatenate([u_hi, -u_lo])
    mode.set_inputs(csr_matrix(b), csr_matrix(u_mat), u_rhs, allow_constants=True)
    error = ha.new_mode("error")
    trans = ha.new_transition(mode, error)
    trans.set_guard(csr_matrix(mat.reshape(-1, n)), rhs.astype(float))  # mat . x <= rhs
    init = lputil.from_box(list(zip(x_lo.tolist(), x_hi.tolist(), strict=True)), mode)
    settings = HylaaSettings(step, t_end)
    settings.plot.plot_mode = PlotSettings.PLOT_NONE
    settings.stdout = HylaaSettings.STDOUT_NONE
    started = time.process_time()
    result = Core(ha, settings).run([StateSet(init, mode)])
    seconds = time.process_time() - started
    print(json.dumps({"unsafe": bool(result.has_concrete_error), "seconds": seconds, "step": step}))


if __name__ == "__main__":
    main(sys.argv[1])
