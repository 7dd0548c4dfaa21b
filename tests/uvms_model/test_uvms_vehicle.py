"""The vehicle law of q0 (eq. 8 with a smooth speed limit) and its rate."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from uvms_model.vehicle import SATURATION_ORDER, limited_velocity, limited_velocity_rate

component = st.floats(-2.0, 2.0, allow_nan=False)
limits = st.floats(0.05, 1.0)


@given(component, component, limits)
def test_never_faster_than_the_limit_and_same_direction(cx: float, cy: float, v_max: float) -> None:
    vx, vy = limited_velocity(cx, cy, v_max)
    assert math.hypot(vx, vy) < v_max or (cx, cy) == (0.0, 0.0)
    # a scaling of the command, never a turn: the cross product vanishes
    assert abs(vx * cy - vy * cx) <= 1e-12 * max(1.0, cx * cx + cy * cy)
    assert vx * cx + vy * cy >= 0.0


def test_closed_form_values() -> None:
    v_max = 0.3
    # h(r) = (1 + (r / v_max)^n)^(-1/n): at the limit itself 2^(-1/4)
    vx, vy = limited_velocity(v_max, 0.0, v_max)
    assert vx == pytest.approx(v_max * 2.0 ** (-1.0 / SATURATION_ORDER), rel=1e-15)
    assert vy == 0.0
    # half the limit: h = (1 + 1/16)^(-1/4) = 0.98496...
    vx, _ = limited_velocity(0.5 * v_max, 0.0, v_max)
    assert vx / (0.5 * v_max) == pytest.approx((1.0 + 0.5**4) ** -0.25, rel=1e-15)


@given(component, component, component, component, limits)
def test_rate_is_the_time_derivative(
    cx: float, cy: float, dx: float, dy: float, v_max: float
) -> None:
    h = 1e-6
    plus = limited_velocity(cx + h * dx, cy + h * dy, v_max)
    minus = limited_velocity(cx - h * dx, cy - h * dy, v_max)
    rate = limited_velocity_rate(cx, cy, dx, dy, v_max)
    for p, m, r in zip(plus, minus, rate, strict=True):
        assert (p - m) / (2 * h) == pytest.approx(r, abs=1e-6 * (1 + abs(dx) + abs(dy)))
