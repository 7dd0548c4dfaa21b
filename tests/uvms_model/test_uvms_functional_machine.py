"""Functional machine: the documented wiring, ranges and the rest property."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from uvms_model.functional_machine import (
    functional_machine,
    functional_machine_clipped,
    functional_machine_units,
    sigmoid,
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


@given(st.floats(1.0, 1.42), st.floats(-20.0, 0.0))
def test_clipped_tanh_rests_when_gamma_at_least_one(g: float, theta_p: float) -> None:
    assert functional_machine_clipped(g, theta_p) == 0.0


@given(st.floats(0.05, 0.99))
def test_clipped_tanh_moves_below_one(g: float) -> None:
    assert 0.0 < functional_machine_clipped(g, 0.0) <= 1.0


def test_sigmoid_is_overflow_safe_and_rejects_unknown_activation() -> None:
    assert sigmoid(-1e6) == 0.0 and sigmoid(1e6) == 1.0 and sigmoid(0.0) == 0.5
    with pytest.raises(ValueError):
        functional_machine(0.5, 0.0, activation="relu")  # type: ignore[arg-type]
