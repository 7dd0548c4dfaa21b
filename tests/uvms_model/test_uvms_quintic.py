"""Quintic transition law: boundary values and an independent 6x6 solve."""

from __future__ import annotations

import numpy as np
import pytest

from uvms_model import functions as fn
from uvms_model.quintic import Quintic, quintic_coefficients, quintic_state, transition_target

N_RANDOM = 1000


def random_boundary(rng: np.random.Generator) -> tuple[float, ...]:
    t0 = float(rng.uniform(-10.0, 50.0))
    tf = t0 + float(rng.uniform(0.2, 10.0))
    p0, v0, a0, pf, vf, af = (float(v) for v in rng.uniform(-3.0, 3.0, 6))
    return t0, p0, v0, a0, tf, pf, vf, af


def test_boundary_values() -> None:
    rng = np.random.default_rng(11)
    for _ in range(N_RANDOM):
        t0, p0, v0, a0, tf, pf, vf, af = random_boundary(rng)
        law = Quintic.from_boundary(t0, p0, v0, a0, tf, pf, vf, af)
        T = tf - t0
        scale = max(1.0, abs(p0), abs(pf), abs(v0) * T, abs(vf) * T, abs(a0) * T**2, abs(af) * T**2)
        for t, (p, v, a) in ((t0, (p0, v0, a0)), (tf, (pf, vf, af))):
            got = law.evaluate(t, clamp=False)
            assert abs(got[0] - p) <= 1e-12 * scale
            assert abs(got[1] - v) <= 1e-12 * scale / T
            assert abs(got[2] - a) <= 1e-12 * scale / T**2


def test_matches_independent_linear_solve() -> None:
    rng = np.random.default_rng(12)
    for _ in range(N_RANDOM):
        t0, p0, v0, a0, tf, pf, vf, af = random_boundary(rng)
        T = tf - t0
        m = np.array(
            [
                [1, 0, 0, 0, 0, 0],
                [0, 1, 0, 0, 0, 0],
                [0, 0, 2, 0, 0, 0],
                [1, T, T**2, T**3, T**4, T**5],
                [0, 1, 2 * T, 3 * T**2, 4 * T**3, 5 * T**4],
                [0, 0, 2, 6 * T, 12 * T**2, 20 * T**3],
            ],
            dtype=float,
        )
        ref = np.linalg.solve(m, [p0, v0, a0, pf, vf, af])
        got = np.array(quintic_coefficients(t0, p0, v0, a0, tf, pf, vf, af))
        scale = max(1.0, abs(p0), abs(pf), abs(v0) * T, abs(vf) * T, abs(a0) * T**2, abs(af) * T**2)
        powers = T ** np.arange(6)
        np.testing.assert_allclose(got * powers, ref * powers, rtol=0, atol=1e-10 * scale)
        law = Quintic.from_boundary(t0, p0, v0, a0, tf, pf, vf, af)
        for t in np.linspace(t0, tf, 7):
            p_ref = np.polynomial.polynomial.polyval(t - t0, ref)
            assert law.position(float(t)) == pytest.approx(p_ref, abs=1e-10 * scale)


def test_clamping_continues_the_boundary_states() -> None:
    law = Quintic.from_boundary(2.0, 1.0, 0.3, -0.2, 5.0, transition_target(1.0, 0.8))
    assert law.pf == 1.25
    # before t0: the start state's Taylor extension, p0 + v0 tau + a0 tau^2 / 2 (tau = -1)
    assert law.evaluate(1.0) == pytest.approx((1.0 - 0.3 - 0.1, 0.3 + 0.2, -0.2), abs=1e-15)
    # after tf with vf = af = 0: held at rest at pf
    assert law.evaluate(7.0) == (1.25, 0.0, 0.0)
    assert law.evaluate(7.0, clamp=False) != (1.25, 0.0, 0.0)
    assert law.velocity(5.0) == pytest.approx(0.0, abs=1e-12)
    assert law.acceleration(5.0) == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(ValueError):
        quintic_coefficients(1.0, 0.0, 0.0, 0.0, 1.0, 1.0)


def test_clamped_law_is_continuous_at_both_ends() -> None:
    rng = np.random.default_rng(13)
    for _ in range(200):
        t0, p0, v0, a0, tf, pf, vf, af = random_boundary(rng)
        law = Quintic.from_boundary(t0, p0, v0, a0, tf, pf, vf, af)
        _, _, _, c3, c4, c5 = law.coeffs
        T = tf - t0
        jerk = 6 * abs(c3) + 24 * abs(c4) * T + 60 * abs(c5) * T**2  # bounds the jerk on [t0, tf]
        rate = max(jerk, abs(v0) + abs(a0) * T, abs(vf) + abs(af) * T, abs(a0), abs(af), 1.0)
        for t in (t0, tf):
            h = 1e-9 * max(1.0, abs(t))
            inside = np.array(law.evaluate(t, clamp=False))
            for side in (t - h, t + h):
                # continuous p, v, a move by at most (their largest derivative) * h within h
                assert np.allclose(law.evaluate(side), inside, rtol=0, atol=4 * rate * h)


def test_registered_law_is_the_same_evaluation() -> None:
    """The function the specs call, ``Quintic`` and ``quintic_state`` agree bit for bit."""
    rng = np.random.default_rng(14)
    for _ in range(N_RANDOM):
        t0, p0, v0, a0, tf, pf, _, _ = random_boundary(rng)
        law = Quintic.from_boundary(t0, p0, v0, a0, t0 + (tf - t0), pf)
        for t in rng.uniform(t0 - 1.0, tf + 1.0, 5):
            expected = law.evaluate(float(t))
            assert quintic_state(float(t), t0, p0, v0, a0, t0 + (tf - t0), pf) == expected
            assert fn.quintic(float(t), t0, p0, v0, a0, tf - t0, pf) == expected


def test_velocity_and_acceleration_are_derivatives() -> None:
    law = Quintic.from_boundary(0.0, 0.2, -0.4, 0.1, 3.0, 1.1, 0.2, -0.3)
    h = 1e-5
    for t in np.linspace(0.1, 2.9, 15):
        p_p, v_p, _ = law.evaluate(float(t) + h)
        p_m, v_m, _ = law.evaluate(float(t) - h)
        _, v, a = law.evaluate(float(t))
        assert (p_p - p_m) / (2 * h) == pytest.approx(v, abs=1e-8)
        assert (v_p - v_m) / (2 * h) == pytest.approx(a, abs=1e-8)


def test_after_its_end_the_law_is_its_end_state_and_a_bad_duration_still_raises() -> None:
    # past tf the end state continues with constant acceleration: pf + vf tau + af tau^2 / 2
    assert quintic_state(7.0, 2.0, 1.0, 0.3, -0.2, 5.0, 1.25, 0.5, 0.25) == (
        1.25 + 2.0 * (0.5 + 0.125 * 2.0),
        0.5 + 0.25 * 2.0,
        0.25,
    )
    for tf in (1.0, 0.5, float("nan")):  # no law ends at or before it starts, even long after
        with pytest.raises(ValueError):
            quintic_state(9.0, 1.0, 0.0, 0.0, 0.0, tf, 1.0)
