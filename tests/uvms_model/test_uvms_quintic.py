"""Quintic transition law: boundary values and an independent 6x6 solve."""

from __future__ import annotations

import numpy as np
import pytest

from uvms_model.quintic import Quintic, quintic_coefficients, transition_target

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


def test_clamping_and_paper_target() -> None:
    law = Quintic.from_boundary(2.0, 1.0, 0.3, -0.2, 5.0, transition_target(1.0, 0.8))
    assert law.pf == 1.25
    assert law.evaluate(1.0) == (1.0, 0.3, -0.2)
    assert law.evaluate(7.0) == (1.25, 0.0, 0.0)
    assert law.evaluate(7.0, clamp=False) != (1.25, 0.0, 0.0)
    assert law.velocity(5.0) == pytest.approx(0.0, abs=1e-12)
    assert law.acceleration(5.0) == pytest.approx(0.0, abs=1e-12)
    with pytest.raises(ValueError):
        quintic_coefficients(1.0, 0.0, 0.0, 0.0, 1.0, 1.0)


def test_velocity_and_acceleration_are_derivatives() -> None:
    law = Quintic.from_boundary(0.0, 0.2, -0.4, 0.1, 3.0, 1.1, 0.2, -0.3)
    h = 1e-5
    for t in np.linspace(0.1, 2.9, 15):
        p_p, v_p, _ = law.evaluate(float(t) + h)
        p_m, v_m, _ = law.evaluate(float(t) - h)
        _, v, a = law.evaluate(float(t))
        assert (p_p - p_m) / (2 * h) == pytest.approx(v, abs=1e-8)
        assert (v_p - v_m) / (2 * h) == pytest.approx(a, abs=1e-8)
