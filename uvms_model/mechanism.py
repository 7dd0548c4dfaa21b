r"""Where the dip comes from: :math:`\dot\gamma` split into the motions that cause it.

In q0 and q2 the arm joints are Davies' secondary magnitudes: their rates solve
``Ns Psi_s = -Np Psi_p``, linear in the primary rates (vehicle ``x', y'``, vehicle
heading ``phi'``, end effector ``xe', ye'`` and tool heading ``phie'``). So the elbow's
rate, and with it

.. math::

    \dot\gamma = \operatorname{sgn}(\sin q_2)\cos q_2\,\dot q_2 / \sin\theta_{sv},

is the sum of one term per group of primary rates, each the solve with only that
group's rates non-zero: the vehicle's translation, the vehicle's heading, the end
effector's translation and the tool's heading. In kinematic state 3 (q1) the elbow
is secondary with the vehicle's translation; there the terms are the vehicle's
heading, the end effector's translation, the tool's heading and the primary joints
q1 and q3 (their eq. 9 laws), and the vehicle's translation term is zero.

:func:`gamma_rate_terms` computes the terms on a run's samples; their sum is the
run's ``gamma_dot`` (a test checks it to 1e-9). ``python -m uvms_model.mechanism
[OUT_DIR]`` prints them at mission 2's switches and draws them
(:func:`write_mechanism_figure`).

Examples
--------
>>> from uvms_model.missions import run_mission
>>> result = run_mission("uvms_mission_1", rtol=1e-6, atol=1e-9, dt=1.0)
>>> terms = gamma_rate_terms(result)
>>> sorted(terms)
['end effector', 'joints (state 3)', 'tool heading', 'vehicle', 'vehicle heading']
>>> bool(abs(sum(terms.values()) - result.run["gamma_dot"]).max() < 1e-9)
True
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from uvms_model.functions import uvms_q0, uvms_state3
from uvms_model.missions import MissionResult

__all__ = ["TERMS", "gamma_rate_terms", "main", "write_mechanism_figure"]

TERMS = ("vehicle", "vehicle heading", "end effector", "tool heading", "joints (state 3)")
"""The terms of :func:`gamma_rate_terms`, in the order they are returned."""


def _parameters(result: MissionResult) -> dict[str, float]:
    from hybrid.compose import as_system

    for component in as_system(result.model).components:
        if "theta_sv" in component.automaton.parameters:
            return dict(component.automaton.parameters)
    raise ValueError("no UVMS component in the model")


def gamma_rate_terms(result: MissionResult) -> dict[str, NDArray[np.float64]]:
    """The terms of ``gamma_dot`` on every sample of ``result``'s run.

    Parameters
    ----------
    result : MissionResult
        A simulated mission (:func:`uvms_model.missions.run_mission`).

    Returns
    -------
    dict of str to ndarray
        One array per name of :data:`TERMS`, each of the run's length, in 1/s;
        their sum is ``gamma_dot``.
    """
    run = result.run
    p = _parameters(result)
    geometry = (p["a1"], p["a2"], p["a3"], p["base_x"], p["base_y"])
    n = len(run.t)
    terms = {name: np.zeros(n) for name in TERMS}
    state3 = np.array([loc.split("|")[0].endswith(".q1") for loc in run.location])
    names = ("x", "y", "phi", "q1", "q2", "q3", "x_rate", "y_rate", "phid", "ee_vx", "ee_vy")
    columns = {name: run[name] for name in (*names, "ee_w", "q1_rate", "q3_rate")}
    sin_sv = math.sin(p["theta_sv"])
    for i in range(n):
        x, y, phi, q1, q2, q3, vx, vy, wd, ex, ey = (float(columns[k][i]) for k in names)
        ew = float(columns["ee_w"][i])
        pose = (x, y, phi, q1, q2, q3)
        if state3[i]:  # (xe', ye', phie', phi', q1', q3') of the state-3 solve
            q1d, q3d = float(columns["q1_rate"][i]), float(columns["q3_rate"][i])
            groups = {
                "vehicle heading": (0.0, 0.0, 0.0, wd, 0.0, 0.0),
                "end effector": (ex, ey, 0.0, 0.0, 0.0, 0.0),
                "tool heading": (0.0, 0.0, ew, 0.0, 0.0, 0.0),
                "joints (state 3)": (0.0, 0.0, 0.0, 0.0, q1d, q3d),
            }
            rates = {k: uvms_state3(*pose, *g, *geometry)[2] for k, g in groups.items()}
        else:  # (x', y', phi', xe', ye', phie') of the q0 solve
            groups = {
                "vehicle": (vx, vy, 0.0, 0.0, 0.0, 0.0),
                "vehicle heading": (0.0, 0.0, wd, 0.0, 0.0, 0.0),
                "end effector": (0.0, 0.0, 0.0, ex, ey, 0.0),
                "tool heading": (0.0, 0.0, 0.0, 0.0, 0.0, ew),
            }
            rates = {k: uvms_q0(*pose, *g, *geometry)[1] for k, g in groups.items()}
        scale = math.copysign(1.0, math.sin(q2)) * math.cos(q2) / sin_sv
        for k, q2d in rates.items():
            terms[k][i] = scale * q2d
    return terms


def write_mechanism_figure(result: MissionResult, path: Path, t_from: float = 0.0) -> Path:
    """Draw the terms of :func:`gamma_rate_terms` and ``gamma`` from ``t_from`` on.

    Parameters
    ----------
    result : MissionResult
        The simulated mission.
    path : Path
        PNG file to write.
    t_from : float
        Start of the time axis, s.

    Returns
    -------
    Path
        ``path``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from uvms_model.figures import save_png

    run = result.run
    terms = gamma_rate_terms(result)
    keep = run.t >= t_from
    t = run.t[keep]
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 6), sharex=True)
    ax1.plot(t, run["gamma"][keep], color="k", label="|gamma|")
    p = _parameters(result)
    ax1.axhline(p["gamma_tol"], color="0.4", ls=":", lw=1, label="gamma_tol")
    ax1.axhline(p["gamma_unit"], color="0.4", ls="--", lw=1, label="1 (beta)")
    ax1.legend(fontsize=8)
    for name in TERMS:
        ax2.plot(t, terms[name][keep], label=name)
    ax2.plot(t, run["gamma_dot"][keep], color="k", lw=1, ls="--", label="gamma' (their sum)")
    ax2.axhline(0.0, color="0.6", lw=0.5)
    ax2.set_xlabel("t [s]")
    ax2.set_ylabel("[1/s]")
    ax2.legend(fontsize=8, ncol=2)
    for ax in (ax1, ax2):
        for (loc, start), (_, stop) in zip(
            result.visited, [*result.visited[1:], ("end", float(run.t[-1]))], strict=True
        ):
            color = {"q1": "tab:red", "q2": "tab:orange"}.get(loc)
            if color is not None:
                ax.axvspan(start, stop, color=color, alpha=0.15)
    ax1.set_title(
        f"{result.name}: gamma' split by Davies' solve into the motions that cause it\n"
        "(red: kinematic state 3; orange: q2)",
        fontsize=9,
    )
    return save_png(fig, path)


def main(argv: list[str] | None = None) -> int:
    """Write mission 2's figure of the terms and print them at its switches."""
    from uvms_model.figures import output_folder
    from uvms_model.missions import run_mission

    out = output_folder(argv)
    result = run_mission("uvms_mission_2", dt=0.01)
    terms = gamma_rate_terms(result)
    run = result.run
    for t_switch, edge in result.switches:
        i = int(np.searchsorted(run.t, t_switch)) - 1  # the last sample before the jump
        values = ", ".join(f"{k} {terms[k][i]:+.3f}" for k in TERMS)
        print(f"{edge} at {t_switch:.2f} s (t = {run.t[i]:.2f} s): {values} /s")
    print(f"figure: {write_mechanism_figure(result, out / 'uvms_mission_2_gamma_terms.png', 30.0)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
