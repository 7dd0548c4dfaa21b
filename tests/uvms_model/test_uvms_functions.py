"""The functions the specs call: fast scalar forms against the numpy reference and closed forms."""

from __future__ import annotations

import math
from itertools import pairwise

import numpy as np
import pytest

from uvms_model import functions as fn
from uvms_model.chain import (
    Q0_SECONDARY,
    STATE3_SECONDARY,
    Chain,
    end_effector_pose,
    joint_point_rates,
    network_matrix,
    network_matrix_rate,
    solve_partition_acceleration,
    solve_q0,
    solve_state3,
)

GEOMETRY = (1.0, 1.0, 0.25, 0.5, 0.0)


def test_registered_solves_match_the_davies_reference() -> None:
    rng = np.random.default_rng(7)
    chain = Chain()
    for _ in range(500):
        config = rng.uniform(-3.0, 3.0, 6)
        if abs(math.sin(config[4])) < 0.05:
            continue
        vehicle, ee = rng.normal(size=3), rng.normal(size=3)
        reference = solve_q0(chain, config, vehicle, ee)
        fast = fn.uvms_q0(*config, *vehicle, *ee, *GEOMETRY)
        assert fast == pytest.approx(reference[3:6], rel=1e-9, abs=1e-9)
        reference = solve_state3(chain, config, ee, vehicle[2], vehicle[0], vehicle[1])
        fast = fn.uvms_state3(*config, *ee, vehicle[2], vehicle[0], vehicle[1], *GEOMETRY)
        assert fast == pytest.approx(reference[[0, 1, 4]], rel=1e-9, abs=1e-9)
        assert fn.uvms_ee(*config, *GEOMETRY) == pytest.approx(
            end_effector_pose(chain, config), abs=1e-12
        )


def _moving_chain(
    rng: np.random.Generator,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """A configuration moving with constant acceleration; its end-effector twist rate by FD."""
    config, rates, accels = rng.uniform(-2, 2, 6), rng.uniform(-1, 1, 6), rng.uniform(-1, 1, 6)

    def ee_rates(t: float) -> np.ndarray:
        c, v = config + rates * t + 0.5 * accels * t * t, rates + accels * t
        r = joint_point_rates(*c, *v, *GEOMETRY)
        return np.array([r[6], r[7], v[2] + v[3] + v[4] + v[5]])

    h = 1e-6
    return config, rates, accels, (ee_rates(h) - ee_rates(-h)) / (2 * h)


def test_acceleration_solves_recover_the_accelerations_of_a_known_motion() -> None:
    """Independent truth: pick every acceleration, read the end effector's by finite differences."""
    rng = np.random.default_rng(8)
    for _ in range(300):
        config, rates, accels, ee_acc = _moving_chain(rng)
        if abs(math.sin(config[4])) < 0.1:
            continue
        q0 = fn.uvms_q0_acc(*config, *rates, *accels[:3], *ee_acc, *GEOMETRY)
        assert q0 == pytest.approx(accels[3:], abs=1e-6)
        s3 = fn.uvms_state3_acc(
            *config, *rates, accels[2], accels[3], accels[5], *ee_acc, *GEOMETRY
        )
        assert s3 == pytest.approx(accels[[0, 1, 4]], abs=1e-6)


def test_fast_acceleration_solves_match_the_numpy_reference() -> None:
    rng = np.random.default_rng(9)
    chain = Chain()
    for _ in range(300):
        config, rates, accels, ee_acc = _moving_chain(rng)
        if abs(math.sin(config[4])) < 0.1:
            continue
        n, ndot = network_matrix(chain, config), network_matrix_rate(chain, config, rates)
        psi = np.concatenate([rates, ee_rates_of(config, rates)])
        ref = solve_partition_acceleration(n, ndot, Q0_SECONDARY, psi, [*accels[:3], *ee_acc])
        fast = fn.uvms_q0_acc(*config, *rates, *accels[:3], *ee_acc, *GEOMETRY)
        assert fast == pytest.approx(ref[3:6], rel=1e-9, abs=1e-9)
        primary = [accels[2], accels[3], accels[5], *ee_acc]
        ref = solve_partition_acceleration(n, ndot, STATE3_SECONDARY, psi, primary)
        fast = fn.uvms_state3_acc(*config, *rates, *primary, *GEOMETRY)
        assert fast == pytest.approx(ref[[0, 1, 4]], rel=1e-9, abs=1e-9)


def ee_rates_of(config: np.ndarray, rates: np.ndarray) -> np.ndarray:
    r = joint_point_rates(*config, *rates, *GEOMETRY)
    return np.array([r[6], r[7], rates[2] + rates[3] + rates[4] + rates[5]])


def test_registered_solve_refuses_the_singularity() -> None:
    with pytest.raises(ValueError, match="singularity"):
        fn.uvms_q0(0, 0, 0, 0.3, 0.0, 0.2, 0, 0, 0, 0.1, 0, 0, 1, 1, 0.25, 0.5, 0)


def test_registered_quintic_matches_boundary_values() -> None:
    p0, v0, a0, T, pf = 0.4, -0.3, 0.2, 4.0, 1.2
    assert fn.quintic(2.0, 2.0, p0, v0, a0, T, pf) == pytest.approx((p0, v0, a0))
    assert fn.quintic(6.0, 2.0, p0, v0, a0, T, pf) == pytest.approx((pf, 0.0, 0.0), abs=1e-12)
    assert fn.uvms_target(0.7, 1.0) == 0.7  # eq. 9 with alpha_j = 1 / gamma_j = 1


def test_registered_path_rates_are_derivatives() -> None:
    args = (1.5, 1.25, 0.0, 1.97, 0.17, 60.0, 0.1, 3.06, 1.0, 1.0)
    h = 1e-5
    for t in (5.0, 23.0, 41.0):
        p, plus, minus = (
            fn.uvms_path(t, *args),
            fn.uvms_path(t + h, *args),
            fn.uvms_path(t - h, *args),
        )
        for k in range(3):
            assert (plus[k] - minus[k]) / (2 * h) == pytest.approx(p[3 + k], abs=1e-7)
            assert (plus[3 + k] - minus[3 + k]) / (2 * h) == pytest.approx(p[6 + k], abs=1e-7)


def test_columns_kept_for_a_configuration_are_its_own_to_the_bit() -> None:
    """The state-3 rates and the accelerations share one configuration's columns; a
    configuration equal as numbers but not to the bit (a zero of the other sign, x = -0.0
    puts -0.0 in the columns) must get its own, and every answer is what it was alone."""
    zero = [0.0, 0.0, 0.0, 0.0, 1.0, 0.0, *GEOMETRY]  # q2 = 1: away from the singularity
    negative = [-0.0, *zero[1:]]
    assert repr(fn._columns(*zero)) != repr(fn._columns(*negative))  # the premise
    rates = (0.1, -0.2, 0.05, 0.3, -0.1, 0.2)
    rng = np.random.default_rng(12)
    moving = [list(_moving_chain(rng)[0]) + list(GEOMETRY) for _ in range(3)]
    sequence = [zero, negative, zero, *moving, moving[0], negative, negative]
    for before, config in pairwise(sequence):
        fn._LAST_COLUMNS[0] = (b"", ())  # alone: nothing kept
        alone = (
            repr(fn._columns(*config)),
            fn.uvms_state3(*config[:6], 0.1, 0.2, 0.3, 0.05, 0.1, 0.2, *config[6:]),
            fn.uvms_q0_acc(*config[:6], *rates, 0.0, 0.1, 0.0, 0.2, 0.1, 0.0, *config[6:]),
        )
        fn._LAST_COLUMNS[0] = (b"", ())
        fn._shared_columns(*before)  # the columns kept are the configuration before's
        kept = (
            repr(fn._shared_columns(*config)),
            fn.uvms_state3(*config[:6], 0.1, 0.2, 0.3, 0.05, 0.1, 0.2, *config[6:]),
            fn.uvms_q0_acc(*config[:6], *rates, 0.0, 0.1, 0.0, 0.2, 0.1, 0.0, *config[6:]),
        )
        assert repr(kept) == repr(alone)
