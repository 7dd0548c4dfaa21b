"""(3) UVMS mission 2: the whole composed simulation against plain solve_ivp.

Two baselines, the same method and tolerances over the same 60 s:

- a hand-written event-free ``solve_ivp`` of the kinematic ODE of location q0
  (the registered functions, the polarization bias held at S2's). The model
  has since gained a seventh state (the tool's lean), a bias that follows a
  quintic law after each switch and jumps into q1 and q2, so this is no longer
  the mission's flow: it is kept as the row it always was;
- ``solve_ivp`` of the same flow: the model's own right-hand side of each mode
  the mission passes through (as the engine compiles it), integrated from each
  jump's post-jump state to the next jump's time, the jumps taken where the
  engine found them. What the engine adds over it is its own work: the search
  for events, the signals at every stored point, the requirement monitor, the
  jumps;
- the same, with ``t`` handed to the right-hand side as a Python float:
  ``solve_ivp`` passes a numpy scalar, whose arithmetic in the model's
  functions is slower, and the engine's solver converts it (the engine's
  stepped flow), so this row says how much of the difference is that.

Also reported: the real-time factor.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from scipy.integrate import solve_ivp

import hybrid
from bench.harness import Comparison, compare
from uvms_model import functions as fn
from uvms_model.missions import specs_dir

__all__ = ["run"]

RTOL, ATOL = 1e-8, 1e-10


def baseline_factory() -> Any:
    model = hybrid.load(specs_dir() / "uvms_singularity.yaml")
    assert isinstance(model, hybrid.Automaton)
    p = dict(model.parameters)
    theta_p = 0.95  # S2's bias (polarization.yaml)
    geometry = (p["a1"], p["a2"], p["a3"], p["base_x"], p["base_y"])
    path_args = (
        p["turns"],
        p["centre_dx"],
        p["centre_dy"],
        p["ee_x0"],
        p["ee_y0"],
        p["duration"],
        p["epsilon_path"],
        p["ee_heading"],
        p["path_direction"],
        p["heading_follow"],
    )
    x0 = np.array(model.initial_vector()[:6])
    sin_sv = np.sin(p["theta_sv"])
    k, vmax, heading, khead = p["k_track"], p["v_max"], p["heading"], p["k_heading"]

    def rhs(t: float, state: Any) -> list[float]:
        x, y, phi, q1, q2, q3 = state.tolist()
        gamma = abs(np.sin(q2)) / sin_sv
        alpha = 1.0 / gamma
        ex, ey, ephi = fn.uvms_ee(x, y, phi, q1, q2, q3, *geometry)
        px, py, pphi, pvx, pvy, pw, *_ = fn.uvms_path(t, *path_args)
        vx, vy, we = pvx + k * (px - ex), pvy + k * (py - ey), pw + k * (pphi - ephi)
        s = fn.uvms_fm(gamma, theta_p, p["gamma_min"], p["fm_ramp"])
        u, w = fn.uvms_vehicle(s * alpha * vx, s * alpha * vy, vmax)
        phid = khead * (heading - phi)
        q1d, q2d, q3d = fn.uvms_q0(x, y, phi, q1, q2, q3, u, w, phid, vx, vy, we, *geometry)
        return [u, w, phid, q1d, q2d, q3d]

    def go() -> Any:
        return solve_ivp(rhs, (0.0, 60.0), x0, method="RK45", rtol=RTOL, atol=ATOL)

    return go


def same_flow_factory(model: Any, reference: hybrid.Run, float_time: bool = False) -> Any:
    """``solve_ivp`` of the model's own flow, mode by mode between ``reference``'s jumps.

    ``float_time``: the right-hand side is given ``float(t)`` (solve_ivp passes numpy scalars).
    """
    from hybrid.simulation.compiled import CompiledModel

    compiled = CompiledModel(model)
    segments = []
    for k in range(len(reference.jumps) + 1):
        rows = np.flatnonzero(reference.j == k)
        first, last = rows[0], rows[-1]
        name = str(reference.location[first])
        key = tuple(part.split(".", 1)[1] for part in name.split("|"))
        rhs = compiled.mode(key).rhs
        if float_time:
            rhs = _float_time(rhs)
        span = (float(reference.t[first]), float(reference.t[last]))
        segments.append((rhs, span, reference.states[first].copy()))

    def go() -> list[Any]:
        return [
            solve_ivp(rhs, span, x0, method="RK45", rtol=RTOL, atol=ATOL)
            for rhs, span, x0 in segments
        ]

    return go


def _float_time(rhs: Any) -> Any:
    def flow(t: Any, x: Any) -> Any:
        return rhs(float(t), x)

    return flow


def run(repeats: int = 5) -> list[Comparison]:
    model = hybrid.load(specs_dir() / "uvms_mission_2.yaml")

    def ours() -> hybrid.Run:
        return hybrid.simulate(model, t_end=60.0, rtol=RTOL, atol=ATOL, handle_sigint=False)

    same_flow = same_flow_factory(model, ours())
    flow = compare(
        "UVMS mission 2, 60 s, the same flow",
        ("hybrid.simulate (composed, with events)", ours),
        ("solve_ivp of the model's own flow between the same jumps", same_flow),
        repeats=repeats,
    )
    flow.extra = {"baseline_steps": int(sum(len(r.t) - 1 for r in same_flow()))}
    floated = compare(
        "UVMS mission 2, 60 s, the same flow given t as a float",
        ("hybrid.simulate (composed, with events)", ours),
        (
            "solve_ivp of the model's own flow between the same jumps, t as a float",
            same_flow_factory(model, ours(), float_time=True),
        ),
        repeats=repeats,
    )

    baseline = baseline_factory()
    c = compare(
        "UVMS mission 2, 60 s",
        ("hybrid.simulate (composed, with events)", ours),
        ("hand-written solve_ivp of q0, no events", baseline),
        repeats=repeats,
    )
    start = time.perf_counter()
    run = ours()
    wall = time.perf_counter() - start
    c.extra = {
        "real_time_factor": 60.0 / wall,
        "jumps": len(run.jumps),
        "baseline_status": int(baseline().status),
    }
    return [c, flow, floated]


if __name__ == "__main__":
    for result in run():
        print(result.line(), result.extra)
