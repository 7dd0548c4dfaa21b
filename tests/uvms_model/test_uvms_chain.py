"""Chain kinematics and Davies' partitions against independent truths.

Analytic determinants (secondary columns in the listed order):

* q0, secondary (q1, q2, q3): columns [1, Pky, -Pkx], k = 1, 2, 3. Subtracting the first
  column leaves det = (P2 - P1) x (P3 - P1) = a1 e(t1) x (a1 e(t1) + a2 e(t2))
  = a1 a2 sin(t2 - t1) = a1 a2 sin q2 (positive sign).
* kinematic state 3, secondary (x, y, q2): Ns = [[0, 0, 1], [1, 0, P2y], [0, 1, -P2x]];
  expanding along the first row, det = (+1) * det[[1, 0], [0, 1]] = +1 (sign +1, not -1).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
import pytest

from uvms_model.chain import (
    EE_SECONDARY,
    Q0_SECONDARY,
    STATE3_SECONDARY,
    Chain,
    det_ns,
    end_effector_pose,
    forward_kinematics,
    network_matrix,
    primary_indices,
    solve_partition,
    solve_q0,
    solve_state3,
)

N_RANDOM = 1000
FD_STEP = 1e-5
FloatArray = npt.NDArray[np.float64]


def random_chain(rng: np.random.Generator) -> Chain:
    a1, a2, a3 = rng.uniform(0.2, 2.0, size=3)
    bx, by = rng.uniform(-1.0, 1.0, size=2)
    return Chain(float(a1), float(a2), float(a3), (float(bx), float(by)))


def random_config(rng: np.random.Generator, min_abs_sin_q2: float = 0.0) -> FloatArray:
    while True:
        cfg: FloatArray = np.concatenate(
            [rng.uniform(-5.0, 5.0, 2), rng.uniform(-math.pi, math.pi, 4)]
        )
        if abs(math.sin(cfg[4])) >= min_abs_sin_q2:
            return cfg


def ee_velocity_fd(chain: Chain, cfg: FloatArray, rates: FloatArray) -> FloatArray:
    """Central difference of the end-effector pose along the configuration rates."""
    plus = np.array(end_effector_pose(chain, cfg + FD_STEP * rates), dtype=np.float64)
    minus = np.array(end_effector_pose(chain, cfg - FD_STEP * rates), dtype=np.float64)
    return (plus - minus) / (2.0 * FD_STEP)


def homogeneous_fk(chain: Chain, cfg: FloatArray) -> FloatArray:
    """Independent forward kinematics by 3x3 homogeneous transforms."""

    def rot(t: float) -> FloatArray:
        c, s = math.cos(t), math.sin(t)
        return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])

    def trans(dx: float, dy: float) -> FloatArray:
        return np.array([[1.0, 0.0, dx], [0.0, 1.0, dy], [0.0, 0.0, 1.0]])

    x, y, phi, q1, q2, q3 = (float(v) for v in cfg)
    h = trans(x, y) @ rot(phi) @ trans(*chain.b)
    h = h @ rot(q1) @ trans(chain.a1, 0.0) @ rot(q2) @ trans(chain.a2, 0.0)
    h = h @ rot(q3) @ trans(chain.a3, 0.0)
    return np.array([h[0, 2], h[1, 2], math.atan2(h[1, 0], h[0, 0])])


def test_forward_kinematics_matches_homogeneous_transforms() -> None:
    rng = np.random.default_rng(1)
    for _ in range(N_RANDOM):
        chain, cfg = random_chain(rng), random_config(rng)
        pose = forward_kinematics(chain, cfg)
        ref = homogeneous_fk(chain, cfg)
        assert abs(pose.xe - ref[0]) < 1e-12 * 10 and abs(pose.ye - ref[1]) < 1e-12 * 10
        dphi = math.remainder(pose.phie - ref[2], 2.0 * math.pi)
        assert abs(dphi) < 1e-12
        assert math.isclose(pose.phie, float(cfg[2] + cfg[3] + cfg[4] + cfg[5]), abs_tol=1e-15)
        assert math.dist(pose.p2, pose.p1) == pytest.approx(chain.a1, rel=1e-12)
        assert math.dist(pose.p3, pose.p2) == pytest.approx(chain.a2, rel=1e-12)
        assert math.dist(pose.e, pose.p3) == pytest.approx(chain.a3, rel=1e-12)


def test_network_matrix_columns() -> None:
    chain = Chain()
    cfg = np.array([0.3, -0.2, 0.4, 0.5, 1.0, -0.7])
    n = network_matrix(chain, cfg)
    pose = forward_kinematics(chain, cfg)
    assert n.shape == (3, 9)
    np.testing.assert_array_equal(n[:, 0], [0.0, 1.0, 0.0])
    np.testing.assert_array_equal(n[:, 1], [0.0, 0.0, 1.0])
    for col, p in zip((2, 3, 4, 5), (pose.p0, pose.p1, pose.p2, pose.p3), strict=True):
        np.testing.assert_array_equal(n[:, col], [1.0, p[1], -p[0]])
    np.testing.assert_array_equal(n[:, 6], [-0.0, -1.0, -0.0])
    np.testing.assert_array_equal(n[:, 7], [-0.0, -0.0, -1.0])
    np.testing.assert_array_equal(n[:, 8], [-1.0, -pose.ye, pose.xe])


def test_det_ns_q0_is_a1_a2_sin_q2() -> None:
    rng = np.random.default_rng(2)
    for _ in range(N_RANDOM):
        chain, cfg = random_chain(rng), random_config(rng)
        scale = max(1.0, float(np.max(np.abs(network_matrix(chain, cfg))))) ** 2
        expected = chain.a1 * chain.a2 * math.sin(cfg[4])
        assert abs(det_ns(chain, cfg, Q0_SECONDARY) - expected) <= 1e-12 * scale


def test_det_ns_state3_is_plus_one() -> None:
    rng = np.random.default_rng(3)
    for _ in range(N_RANDOM):
        chain, cfg = random_chain(rng), random_config(rng)
        scale = max(1.0, float(np.max(np.abs(network_matrix(chain, cfg))))) ** 2
        assert abs(det_ns(chain, cfg, STATE3_SECONDARY) - 1.0) <= 1e-12 * scale


def test_end_effector_twist_matches_finite_differences() -> None:
    rng = np.random.default_rng(4)
    for _ in range(N_RANDOM):
        chain, cfg = random_chain(rng), random_config(rng)
        rates = rng.uniform(-1.0, 1.0, 6)
        psi = solve_partition(network_matrix(chain, cfg), EE_SECONDARY, rates)
        np.testing.assert_array_equal(psi[:6], rates)
        np.testing.assert_allclose(psi[6:], ee_velocity_fd(chain, cfg, rates), rtol=0, atol=1e-7)


def test_q0_joint_rates_reproduce_commanded_end_effector_velocity() -> None:
    rng = np.random.default_rng(5)
    for _ in range(N_RANDOM):
        chain, cfg = random_chain(rng), random_config(rng, min_abs_sin_q2=0.2)
        vehicle, ee = rng.uniform(-1.0, 1.0, 3), rng.uniform(-1.0, 1.0, 3)
        psi = solve_q0(chain, cfg, vehicle, ee)
        np.testing.assert_array_equal(psi[:3], vehicle)
        np.testing.assert_array_equal(psi[6:], ee)
        fd = ee_velocity_fd(chain, cfg, psi[:6])
        np.testing.assert_allclose(fd, ee, rtol=0, atol=1e-7 * max(1.0, float(np.abs(psi).max())))


def test_state3_vehicle_rates_reproduce_commanded_end_effector_velocity() -> None:
    rng = np.random.default_rng(6)
    for _ in range(N_RANDOM):
        chain, cfg = random_chain(rng), random_config(rng)
        ee = rng.uniform(-1.0, 1.0, 3)
        phid, q1d, q3d = rng.uniform(-1.0, 1.0, 3)
        psi = solve_state3(chain, cfg, ee, phid, q1d, q3d)
        assert (psi[2], psi[3], psi[5]) == (phid, q1d, q3d)
        fd = ee_velocity_fd(chain, cfg, psi[:6])
        np.testing.assert_allclose(fd, ee, rtol=0, atol=1e-7 * max(1.0, float(np.abs(psi).max())))


@pytest.mark.parametrize("secondary", [Q0_SECONDARY, STATE3_SECONDARY, EE_SECONDARY])
def test_network_matrix_closes_the_loop(secondary: tuple[int, int, int]) -> None:
    rng = np.random.default_rng(7)
    for _ in range(N_RANDOM):
        chain, cfg = random_chain(rng), random_config(rng, min_abs_sin_q2=0.2)
        n = network_matrix(chain, cfg)
        psi = solve_partition(n, secondary, rng.uniform(-1.0, 1.0, 6))
        scale = max(1.0, float(np.abs(n).max()) * float(np.abs(psi).max()))
        assert float(np.abs(n @ psi).max()) < 1e-12 * scale


def test_singular_partition_raises_clear_error() -> None:
    chain = Chain()
    cfg = np.array([0.0, 0.0, 0.0, 0.3, 0.0, 0.2])  # stretched elbow: q2 = 0
    with pytest.raises(ValueError, match="singular"):
        solve_q0(chain, cfg, (0.0, 0.0, 0.0), (0.1, 0.0, 0.0))
    # The same posture is regular in kinematic state 3.
    psi = solve_state3(chain, cfg, (0.1, 0.0, 0.0), 0.0, 0.0, 0.0)
    assert np.all(np.isfinite(psi))


def test_partition_validation() -> None:
    n = network_matrix(Chain(), np.zeros(6) + 0.5)
    with pytest.raises(ValueError):
        solve_partition(n, (3, 4), np.zeros(7))
    with pytest.raises(ValueError):
        solve_partition(n, (3, 3, 4), np.zeros(6))
    with pytest.raises(ValueError):
        solve_partition(n, (3, 4, 5), np.zeros(5))
    assert primary_indices(Q0_SECONDARY) == (0, 1, 2, 6, 7, 8)
    assert primary_indices(STATE3_SECONDARY) == (2, 3, 5, 6, 7, 8)
    with pytest.raises(ValueError):
        Chain(a1=0.0)
