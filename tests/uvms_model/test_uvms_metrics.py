"""Mission measures against closed forms."""

from __future__ import annotations

import numpy as np
import pytest

from uvms_model.metrics import (
    jump_steps,
    trapezoid,
    vehicle_energy,
    vehicle_travel_time,
    windowed_change,
)


def test_windowed_change_sees_a_step_the_jump_rows_and_a_ramp() -> None:
    t = np.linspace(0.0, 2.0, 2001)
    # the steepest 20 ms of sin on [0, 2] start at t = 0: sin(0.02) - sin(0)
    assert windowed_change(t, np.sin(t), 0.02) == pytest.approx(np.sin(0.02), rel=1e-12)
    ramp = np.where(t < 1.0, 0.0, 3.0 * (t - 1.0))  # a corner: the slope steps from 0 to 3
    assert windowed_change(t, ramp, 0.02) == pytest.approx(0.06, abs=1e-12)
    # hybrid time: a jump gives two rows with the same t; the step is seen across them
    tj = np.array([0.0, 0.5, 0.5, 1.0])
    assert windowed_change(tj, np.array([0.0, 0.0, 0.25, 0.25]), 1e-3) == 0.25
    with pytest.raises(ValueError):
        windowed_change(t, t, 0.0)


def test_windowed_change_is_blind_to_nothing_between_two_rows_of_a_jump() -> None:
    # the old measure compared the two rows of a jump; a corner a few ms later is still seen
    t = np.array([0.0, 0.010, 0.010, 0.015, 0.020, 0.030])
    v = np.array([0.0, 0.0, 0.0, 0.005, 0.030, 0.030])
    assert jump_steps(t, [0, 0, 1, 1, 1, 1], v) == [(0.010, 0.0)]
    assert windowed_change(t, v, 0.02) == pytest.approx(0.03)


def test_energy_and_travel_time_of_a_trapezoidal_speed_profile() -> None:
    t = np.linspace(0.0, 10.0, 10001)
    speed = np.clip(np.minimum(t - 1.0, 9.0 - t), 0.0, 1.0)  # 0, ramp up, 1, ramp down, 0
    # int v^2 dt = 2 * int_0^1 s^2 ds + 6 * 1 = 2/3 + 6
    assert vehicle_energy(t, speed * 0.6, speed * 0.8) == pytest.approx(6.0 + 2.0 / 3.0, rel=1e-6)
    assert vehicle_travel_time(t, speed, threshold=1e-3) == pytest.approx(8.0 - 2e-3, abs=2e-3)
    assert trapezoid(t, np.ones_like(t)) == pytest.approx(10.0)
