"""Functional machine: the documented wiring, ranges and the rest property."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from uvms_model.functional_machine import (
    functional_machine,
    functional_machine_output,
    functional_machine_rate,
    functional_machine_units,
    sigmoid,
    smooth_ramp,
)

gammas = st.floats(0.05, 1.42)
biases = st.floats(-20.0, 20.0)


def test_hand_computed_value() -> None:
    g, theta_p, g_min = 0.8, -0.5, 0.65
    a = 1.0 / g
    w = (a - g) / g
    y1 = 1.0 / (1.0 + math.exp(-(w * a + theta_p)))
    y2 = 1.0 / (1.0 + math.exp(-(w * abs(a - g_min) + theta_p)))
    units = functional_machine_units(g, theta_p, g_min)
    assert units.x1 == a and units.x2 == abs(a - g_min) and units.weight == w
    assert units.y1 == pytest.approx(y1, rel=1e-15) and units.y2 == pytest.approx(y2, rel=1e-15)
    assert functional_machine(g, theta_p, g_min) == pytest.approx(0.5 * (y1 + y2), rel=1e-15)
    s_tanh = functional_machine(g, theta_p, g_min, "tanh")
    expected = 0.5 * (math.tanh(w * a + theta_p) + math.tanh(w * abs(a - g_min) + theta_p))
    assert s_tanh == pytest.approx(expected, rel=1e-15)


@given(gammas, biases)
def test_ranges_and_monotone_in_bias(g: float, theta_p: float) -> None:
    s = functional_machine(g, theta_p)
    assert 0.0 <= s <= 1.0
    assert -1.0 <= functional_machine(g, theta_p, activation="tanh") <= 1.0
    assert functional_machine(g, theta_p + 0.5) >= s


@given(st.floats(1.0, 1.42), st.floats(-20.0, 0.0), st.floats(0.0, 0.5))
def test_tanh_output_rests_when_gamma_at_least_one(g: float, theta_p: float, ramp: float) -> None:
    assert functional_machine_output(g, theta_p, activation="tanh", ramp=ramp) == 0.0


@given(st.floats(0.05, 0.99), st.floats(0.0, 0.5))
def test_tanh_output_moves_below_one_and_stays_below_the_reflex(g: float, ramp: float) -> None:
    s = functional_machine_output(g, 0.0, activation="tanh", ramp=ramp)
    assert 0.0 < s <= 1.0  # s alpha E never exceeds the reflex command alpha E of section 3.2


@given(st.floats(0.0, 1.0), st.floats(0.01, 0.5))
def test_smooth_ramp_is_c2_and_a_ramp(u: float, width: float) -> None:
    value, slope = smooth_ramp(u, width)
    assert 0.0 <= value <= u and 0.0 <= slope <= 1.875  # max slope of u sigma(u/w)
    if u >= width:
        assert (value, slope) == (u, 1.0)
    h = 1e-7
    if h < u < width - h:
        fd = (smooth_ramp(u + h, width)[0] - smooth_ramp(u - h, width)[0]) / (2 * h)
        assert fd == pytest.approx(slope, abs=1e-6)
    # C1 at both ends: the slope tends to 0 at 0 and to 1 at the width
    assert smooth_ramp(1e-9 * width, width)[1] < 1e-12
    assert smooth_ramp(width * (1 - 1e-6), width)[1] == pytest.approx(1.0, abs=1e-9)


@given(st.floats(0.3, 1.4), st.floats(-1.0, 1.0), st.floats(-1.0, 2.0), st.floats(-1.0, 1.0))
def test_rate_is_the_time_derivative(
    g: float, g_dot: float, theta: float, theta_dot: float
) -> None:
    h = 1e-6

    def s(dt: float) -> float:
        return functional_machine_output(g + dt * g_dot, theta + dt * theta_dot, 0.65, "tanh", 0.1)

    fd = (s(h) - s(-h)) / (2 * h)
    rate = functional_machine_rate(g, g_dot, theta, theta_dot, 0.65, "tanh", 0.1)
    assert rate == pytest.approx(fd, abs=1e-5)


def test_sigmoid_is_overflow_safe_and_rejects_unknown_activation() -> None:
    assert sigmoid(-1e6) == 0.0 and sigmoid(1e6) == 1.0 and sigmoid(0.0) == 0.5
    with pytest.raises(ValueError):
        functional_machine(0.5, 0.0, activation="relu")  # type: ignore[arg-type]
