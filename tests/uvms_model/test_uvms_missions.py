"""The paper's qualitative results, reproduced from the YAML specs.

Independent truths: the paper's text (section 6: mission 1 never leaves the FM
state and gamma stays above gamma_tol; mission 2 falls below gamma_tol,
switches to kinematic state 3 and leaves it when gamma is back at 1; joint
and vehicle velocities stay smooth), and the numpy Davies reference solver in
uvms_model.chain for the fast registered functions.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import hybrid
from uvms_model import functions as fn
from uvms_model.chain import Chain, end_effector_pose, solve_q0, solve_state3
from uvms_model.missions import ABLATIONS, run_mission, specs_dir

RATE_JUMP_BOUND = 1e-9
"""Stated bound on the jump of any joint or vehicle rate at a switch (rad/s, m/s)."""
TRACKING_BOUND = 1e-3
"""The issue's aim: end-effector tracking error under 1 mm."""


@pytest.fixture(scope="module")
def mission_1() -> object:
    return run_mission("uvms_mission_1")


@pytest.fixture(scope="module")
def mission_2() -> object:
    return run_mission("uvms_mission_2")


def _uvms_params() -> dict[str, float]:
    model = hybrid.load(specs_dir() / "uvms_singularity.yaml")
    assert isinstance(model, hybrid.Automaton)
    return dict(model.parameters)


def test_mission_1_stays_in_the_fm_state_above_gamma_tol(mission_1) -> None:  # type: ignore[no-untyped-def]
    run = mission_1.run
    assert run.termination.cause == "t_end"
    assert [loc for loc, _ in mission_1.visited] == ["q0"]
    assert mission_1.min_gamma > _uvms_params()["gamma_tol"]
    # the FM did act: the polarization FSM left rest and the vehicle moved
    assert any(j.target.endswith("polarization.S2") for j in run.jumps)
    assert float(np.max(np.hypot(run["x_rate"], run["y_rate"]))) > 0.05


def test_mission_2_switches_to_state_3_and_back_at_gamma_one(mission_2) -> None:  # type: ignore[no-untyped-def]
    run = mission_2.run
    params = _uvms_params()
    assert run.termination.cause == "t_end"
    locations = [loc for loc, _ in mission_2.visited]
    assert locations[:3] == ["q0", "q1", "q2"]
    epsilon = next(j for j in run.jumps if j.edge == "uvms.epsilon")
    beta = next(j for j in run.jumps if j.edge == "uvms.beta")
    gamma_at = lambda q2: math.sin(q2) / math.sin(params["theta_sv"])  # noqa: E731
    # epsilon fires exactly when gamma falls to gamma_tol, beta when it is back at 1
    assert gamma_at(epsilon.before["q2"]) == pytest.approx(params["gamma_tol"], abs=1e-7)
    assert gamma_at(beta.before["q2"]) == pytest.approx(1.0, abs=1e-7)
    assert epsilon.t < beta.t
    # gamma never reaches the singularity
    assert mission_2.min_gamma > 0.5


@pytest.mark.parametrize("which", ["mission_1", "mission_2"])
def test_tracking_and_smoothness(which: str, request: pytest.FixtureRequest) -> None:
    result = request.getfixturevalue(which)
    assert result.max_tracking_error < TRACKING_BOUND
    assert result.max_rate_jump < RATE_JUMP_BOUND


def test_ablations_show_each_part_is_needed() -> None:
    both = run_mission("uvms_mission_2", ABLATIONS["both (the paper's strategy)"])
    fm_only = run_mission("uvms_mission_2", ABLATIONS["FM only"])
    none = run_mission("uvms_mission_2", ABLATIONS["no strategy"])
    gamma_tol = _uvms_params()["gamma_tol"]
    # no strategy: the arm runs into the singularity and the kinematic solve fails
    assert none.run.termination.cause in ("solver_failure", "nonfinite")
    assert none.min_gamma < 0.01
    # FM only: no switch, but gamma falls far below gamma_tol
    assert [loc for loc, _ in fm_only.visited] == ["q0"]
    assert fm_only.min_gamma < gamma_tol - 0.3
    # both: the automaton catches it at gamma_tol
    assert both.min_gamma > fm_only.min_gamma + 0.3


def test_spec_start_point_is_forward_kinematics_of_the_initial_state() -> None:
    model = hybrid.load(specs_dir() / "uvms_singularity.yaml")
    assert isinstance(model, hybrid.Automaton)
    p = model.parameters
    x0 = dict(zip(model.state_names, model.initial_vector(), strict=True))
    chain = Chain(p["a1"], p["a2"], p["a3"], (p["base_x"], p["base_y"]))
    config = [x0[k] for k in ("x", "y", "phi", "q1", "q2", "q3")]
    xe, ye, phie = end_effector_pose(chain, config)
    assert (xe, ye) == pytest.approx((p["ee_x0"], p["ee_y0"]), abs=1e-12)
    assert phie == pytest.approx(p["ee_heading"], abs=1e-12)


def test_registered_solves_match_the_davies_reference() -> None:
    rng = np.random.default_rng(7)
    chain = Chain()
    geometry = (chain.a1, chain.a2, chain.a3, *chain.b)
    for _ in range(500):
        config = rng.uniform(-3.0, 3.0, 6)
        if abs(math.sin(config[4])) < 0.05:
            continue
        vehicle, ee = rng.normal(size=3), rng.normal(size=3)
        reference = solve_q0(chain, config, vehicle, ee)
        fast = fn.uvms_q0(*config, *vehicle, *ee, *geometry)
        assert fast == pytest.approx(reference[3:6], rel=1e-9, abs=1e-9)
        reference = solve_state3(chain, config, ee, vehicle[2], vehicle[0], vehicle[1])
        fast = fn.uvms_state3(*config, *ee, vehicle[2], vehicle[0], vehicle[1], *geometry)
        assert fast == pytest.approx(reference[[0, 1, 4]], rel=1e-9, abs=1e-9)
        assert fn.uvms_ee(*config, *geometry) == pytest.approx(
            end_effector_pose(chain, config), abs=1e-12
        )


def test_registered_solve_refuses_the_singularity() -> None:
    with pytest.raises(ValueError, match="singularity"):
        fn.uvms_q0(0, 0, 0, 0.3, 0.0, 0.2, 0, 0, 0, 0.1, 0, 0, 1, 1, 0.25, 0.5, 0)


def test_registered_quintic_matches_boundary_values() -> None:
    p0, v0, a0, T, pf = 0.4, -0.3, 0.0, 4.0, 1.2
    assert fn.quintic(2.0, 2.0, p0, v0, a0, T, pf) == pytest.approx((p0, v0, a0))
    assert fn.quintic(6.0, 2.0, p0, v0, a0, T, pf) == pytest.approx((pf, 0.0, 0.0))
    h = 1e-6
    for t in (2.5, 3.7, 5.9):
        p_plus, p_minus = (
            fn.quintic(t + h, 2.0, p0, v0, a0, T, pf)[0],
            fn.quintic(t - h, 2.0, p0, v0, a0, T, pf)[0],
        )
        assert (p_plus - p_minus) / (2 * h) == pytest.approx(
            fn.quintic(t, 2.0, p0, v0, a0, T, pf)[1], abs=1e-8
        )
