"""The split of gamma' into the motions that cause it (uvms_model.mechanism).

Independent truths: the spec's closed-form ``gamma_dot`` (the terms must add up to
it: Davies' solve is linear in the primary rates), the numpy reference solve of
:mod:`uvms_model.chain` (each q0 term recomputed with ``solve_q0``), and the
definition of kinematic state 3 (the vehicle is secondary there: no vehicle term).
"""

from __future__ import annotations

import math
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest

from uvms_model.chain import Chain, solve_q0
from uvms_model.mechanism import TERMS, gamma_rate_terms, write_mechanism_figure
from uvms_model.missions import MissionResult, run_mission


@pytest.fixture(scope="module")
def mission_2() -> MissionResult:
    return run_mission("uvms_mission_2", rtol=1e-8, atol=1e-10, dt=0.05)


@pytest.fixture(scope="module")
def terms(mission_2: MissionResult) -> dict[str, np.ndarray]:
    return gamma_rate_terms(mission_2)


def test_the_terms_add_up_to_gamma_dot(
    mission_2: MissionResult, terms: dict[str, np.ndarray]
) -> None:
    assert list(terms) == list(TERMS)
    total = sum(terms.values())
    np.testing.assert_allclose(total, mission_2.run["gamma_dot"], atol=1e-9)


def test_q0_terms_against_the_reference_solve(
    mission_2: MissionResult, terms: dict[str, np.ndarray]
) -> None:
    run = mission_2.run
    p = dict(mission_2.model.components[0].automaton.parameters)  # type: ignore[union-attr]
    chain = Chain(p["a1"], p["a2"], p["a3"], (p["base_x"], p["base_y"]))
    in_q0 = [i for i, loc in enumerate(run.location) if loc.startswith("uvms.q0")]
    for i in in_q0[:: max(1, len(in_q0) // 40)]:
        config = [float(run[k][i]) for k in ("x", "y", "phi", "q1", "q2", "q3")]
        q2 = config[4]
        scale = math.copysign(1.0, math.sin(q2)) * math.cos(q2) / math.sin(p["theta_sv"])
        vx, vy, wd = (float(run[k][i]) for k in ("x_rate", "y_rate", "phid"))
        ex, ey, ew = (float(run[k][i]) for k in ("ee_vx", "ee_vy", "ee_w"))
        cases = {
            "vehicle": ((vx, vy, 0.0), (0.0, 0.0, 0.0)),
            "vehicle heading": ((0.0, 0.0, wd), (0.0, 0.0, 0.0)),
            "end effector": ((0.0, 0.0, 0.0), (ex, ey, 0.0)),
            "tool heading": ((0.0, 0.0, 0.0), (0.0, 0.0, ew)),
        }
        for name, (vehicle, ee) in cases.items():
            psi = solve_q0(chain, config, vehicle, ee)
            assert terms[name][i] == pytest.approx(scale * psi[4], abs=1e-12), (name, i)
        assert terms["joints (state 3)"][i] == 0.0


def test_at_epsilon_the_vehicle_lowers_gamma_and_the_end_effector_raises_it(
    mission_2: MissionResult, terms: dict[str, np.ndarray]
) -> None:
    """The measured mechanism of mission 2's dip (docs/uvms.md): just before epsilon the
    vehicle's motion lowers gamma and the end effector's own motion raises it; in
    kinematic state 3 the vehicle is secondary (no term) and the tool's heading is what
    brings gamma back to 1."""
    run = mission_2.run
    (t_eps, _), (t_beta, _) = mission_2.switches
    before = int(np.searchsorted(run.t, t_eps)) - 1
    assert terms["vehicle"][before] < -0.3
    assert terms["end effector"][before] > 0.2
    state3 = np.array([loc.startswith("uvms.q1") for loc in run.location])
    assert state3.any()
    assert np.all(terms["vehicle"][state3] == 0.0)
    late = state3 & (run.t > t_eps + 2.0) & (run.t < t_beta)
    assert np.all(terms["tool heading"][late] > 0.0)
    assert np.all(np.abs(terms["joints (state 3)"][late]) < 1e-9)  # q1, q3 at rest


def test_figure(mission_2: MissionResult, tmp_path: Path) -> None:
    path = write_mechanism_figure(mission_2, tmp_path / "terms.png", 30.0)
    height, width, _ = matplotlib.image.imread(path).shape
    assert width >= 700 and height >= 500
