"""The comparison's baselines (uvms_model.baselines, specs/uvms_baseline.yaml).

Independent truths: the end effector's forward kinematics (the Jacobian by central
differences of :func:`uvms_model.functions.uvms_ee`), numpy's least-squares solve
(the pseudoinverse's rates are its minimum-norm solution), the task's definition
(task priority tracks its primary task exactly: ``J u = b``), and the strategy's
"no strategy" ablation (the arm-only baseline must fail where it does).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np
import pytest

import hybrid
from uvms_model.baselines import METHODS, jacobian, resolve
from uvms_model.compare import MISSION_PARAMETERS, baseline_run, headline, main, measure
from uvms_model.functions import uvms_ee
from uvms_model.missions import ABLATIONS, run_mission, specs_dir

GEOMETRY = (1.0, 1.2, 0.25, 0.7, 0.0)


def _fd_jacobian(config: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """End-effector pose rates per free rate (x, y, q1, q2, q3) and per phi, by differences."""
    h = 1e-6
    cols = []
    for k in (0, 1, 3, 4, 5, 2):
        plus, minus = config.copy(), config.copy()
        plus[k] += h
        minus[k] -= h
        cols.append(
            (np.array(uvms_ee(*plus, *GEOMETRY)) - np.array(uvms_ee(*minus, *GEOMETRY))) / (2 * h)
        )
    stacked = np.array(cols).T
    return stacked[:, :5], stacked[:, 5]


def test_the_jacobian_is_the_forward_kinematics_derivative() -> None:
    rng = np.random.default_rng(3)
    for _ in range(20):
        config = rng.uniform(-math.pi, math.pi, 6)
        jac, jphi = jacobian(*config, *GEOMETRY)
        fd, fd_phi = _fd_jacobian(config)
        np.testing.assert_allclose(jac, fd, atol=1e-7)
        np.testing.assert_allclose(jphi, fd_phi, atol=1e-7)


@pytest.fixture(scope="module")
def pinv_run() -> hybrid.Run:
    return baseline_run("uvms_mission_2", 1, t_end=30.0)


def test_pseudoinverse_rates_are_the_least_squares_solution(pinv_run: hybrid.Run) -> None:
    run = pinv_run
    assert run.termination.cause == "t_end"
    for i in range(0, len(run.t), 150):
        config = np.array([run[k][i] for k in ("x", "y", "phi", "q1", "q2", "q3")])
        jac, jphi = _fd_jacobian(config)
        b = np.array([run["ee_vx"][i], run["ee_vy"][i], run["ee_w"][i]]) - jphi * run["phid"][i]
        expected = np.linalg.lstsq(jac, b, rcond=None)[0]  # the minimum-norm solution
        got = np.array([run[k][i] for k in ("x_rate", "y_rate", "q1_rate", "q2_rate", "q3_rate")])
        np.testing.assert_allclose(got, expected, atol=1e-6)


def test_task_priority_tracks_its_primary_task() -> None:
    run = baseline_run("uvms_mission_2", 4, {"k_null": 1.0})
    assert run.termination.cause == "t_end"
    assert float(np.max(run["tracking_error"])) < 1e-6  # m
    for i in range(0, len(run.t), 200):
        config = np.array([run[k][i] for k in ("x", "y", "phi", "q1", "q2", "q3")])
        jac, jphi = _fd_jacobian(config)
        u = np.array([run[k][i] for k in ("x_rate", "y_rate", "q1_rate", "q2_rate", "q3_rate")])
        b = np.array([run["ee_vx"][i], run["ee_vy"][i], run["ee_w"][i]]) - jphi * run["phid"][i]
        np.testing.assert_allclose(jac @ u, b, atol=1e-6)
    # and its null-space task keeps the elbow away from the arm's singularity
    assert float(np.min(run["gamma"])) > 1.2


def test_arm_only_fails_where_the_no_strategy_ablation_does() -> None:
    arm = baseline_run("uvms_mission_2", 0, t_end=20.0)
    none = run_mission("uvms_mission_2", ABLATIONS["no strategy"], dt=0.01)
    assert arm.termination.cause == none.run.termination.cause == "solver_failure"
    assert arm.termination.t == pytest.approx(none.run.termination.t, abs=0.05)
    assert float(np.max(np.hypot(arm["x_rate"], arm["y_rate"]))) == 0.0


def test_methods_by_hand_on_one_configuration() -> None:
    config = (0.0, 0.0, 0.0, 0.4, -1.4, -1.3)
    args = (*config, 0.1, -0.05, 0.02, 0.01, *GEOMETRY)
    jac, jphi = jacobian(*config, *GEOMETRY)
    b = np.array([0.1, -0.05, 0.02]) - 0.01 * jphi
    for code in METHODS:
        u = resolve(code, *args, 4.0, 0.2, 1.0)
        if code == 3:  # damped: J u = J J^T (J J^T + l^2 I)^-1 b, not b
            jjt = jac @ jac.T
            np.testing.assert_allclose(jac @ u, jjt @ np.linalg.solve(jjt + 0.04 * np.eye(3), b))
        else:
            np.testing.assert_allclose(jac @ u, b, atol=1e-12)
    assert np.all(resolve(0, *args)[:2] == 0.0)
    # the weighted pseudoinverse minimises u^T W u: the vehicle moves less as w grows
    speeds = [np.hypot(*resolve(2, *args, w)[:2]) for w in (1.0, 4.0, 16.0)]
    assert speeds[0] > speeds[1] > speeds[2]
    with pytest.raises(ValueError, match="unknown method"):
        resolve(7, *args)


def test_the_baseline_spec_shares_the_strategys_values() -> None:
    baseline = hybrid.load(specs_dir() / "uvms_baseline.yaml")
    strategy = hybrid.load(specs_dir() / "uvms_singularity.yaml")
    assert isinstance(baseline, hybrid.Automaton) and isinstance(strategy, hybrid.Automaton)
    shared = set(baseline.parameters) & set(strategy.parameters)
    assert len(shared) >= 20
    assert {k: baseline.parameters[k] for k in shared} == {
        k: strategy.parameters[k] for k in shared
    }
    start_b = dict(zip(baseline.state_names, baseline.initial_vector(), strict=True))
    start_s = dict(zip(strategy.state_names, strategy.initial_vector(), strict=True))
    assert {k: start_b[k] for k in start_b} == {k: start_s[k] for k in start_b}
    assert MISSION_PARAMETERS["uvms_mission_2"] == {"turns": 1.5, "centre_dy": 0.0}


def test_measure_on_a_run_and_the_table(tmp_path: Path, pinv_run: hybrid.Run) -> None:
    metrics = measure(pinv_run, GEOMETRY)
    assert metrics.rest_time == 0.0 and metrics.starts == 0  # the vehicle always moves
    t = pinv_run.t
    v = np.hypot(pinv_run["x_rate"], pinv_run["y_rate"])
    # the midpoint rule against the trapezoidal rule on the 10 ms grid: O(dt^2) apart
    assert metrics.speed_energy == pytest.approx(float(np.trapezoid(v**2, t)), rel=1e-5)
    assert metrics.min_sigma > 0.5  # the whole Jacobian stays well conditioned


@pytest.mark.fuzz
@pytest.mark.skipif(
    os.environ.get("HYBRID_FUZZ", "0") in ("", "0"),
    reason="the whole comparison (about a minute) runs under make fuzz (HYBRID_FUZZ=1)",
)
def test_the_comparison_writes_its_table_and_figures(tmp_path: Path) -> None:
    assert main([str(tmp_path)]) == 0
    text = (tmp_path / "compare.md").read_text()
    assert text.count("| the paper's strategy |") == 2
    assert text.count("| task priority + manipulability (k_null 1) |") == 2
    for mission in ("uvms_mission_1", "uvms_mission_2"):
        assert (tmp_path / f"{mission}_compare.png").stat().st_size > 10_000


def test_the_demos_headline() -> None:
    table = headline()
    rows = [line for line in table.splitlines() if line.startswith("| ") and "---" not in line]
    assert [row.split(" | ")[0] for row in rows[1:]] == [
        "| the paper's strategy",
        "| pseudoinverse",
        "| task priority + manipulability (k_null 0.5)",
    ]
    assert all("t_end at 60.0 s" in row for row in rows[1:])
