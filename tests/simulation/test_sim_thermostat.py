"""Thermostat switching instants against the closed form of first-order heating and cooling.

Cooling (``off``): T' = -a (T - T_out), so T(t) = T_out + (T(0) - T_out) e^(-a t)
and going from T_from down to T_to takes ln((T_from - T_out) / (T_to - T_out)) / a.
Heating (``on``): T' = a (T_heat - T), so going from T_from up to T_to takes
ln((T_heat - T_from) / (T_heat - T_to)) / a. Start at T = 20 in ``off``: the first
switch (on) is at T_low, then off at T_high, on at T_low, ...
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support import Simulate

import hybrid


def cooling_time(a: float, t_out: float, t_from: float, t_to: float) -> float:
    return math.log((t_from - t_out) / (t_to - t_out)) / a


def heating_time(a: float, t_heat: float, t_from: float, t_to: float) -> float:
    return math.log((t_heat - t_from) / (t_heat - t_to)) / a


def switching_times(p: dict[str, float], n: int, start: float = 20.0) -> list[float]:
    a, t_out, t_heat, low, high = (p[k] for k in ("a", "T_out", "T_heat", "T_low", "T_high"))
    times = [cooling_time(a, t_out, start, low)]
    for k in range(1, n):
        if k % 2:  # on: heat from T_low to T_high
            times.append(times[-1] + heating_time(a, t_heat, low, high))
        else:  # off: cool from T_high to T_low
            times.append(times[-1] + cooling_time(a, t_out, high, low))
    return times


def test_the_spec_starts_where_the_closed_form_does(thermostat: hybrid.Automaton) -> None:
    assert thermostat.initial_location == "off" and thermostat.initial_vector() == [20.0]


def test_ten_periods_of_switching(simulate: Simulate, thermostat: hybrid.Automaton) -> None:
    p = dict(thermostat.parameters)
    expected = np.array(switching_times(p, 20))  # ten periods: ten on and ten off switches
    run = simulate(thermostat, t_end=expected[-1] + 1.0, rtol=1e-12, atol=1e-12)
    assert run.termination.cause == "t_end"
    assert len(run.jumps) == 20
    error = np.abs(run.jump_times - expected)
    assert error.max() < 1e-8, f"max switching-time error {error.max():.3g}"
    assert [jump.edge for jump in run.jumps] == ["turn_on", "turn_off"] * 10
    assert [jump.label for jump in run.jumps] == ["switch_on", "switch_off"] * 10
    for jump in run.jumps:
        level = p["T_low"] if jump.edge == "turn_on" else p["T_high"]
        assert jump.before["T"] == pytest.approx(level, abs=1e-9)
        assert jump.after == jump.before  # no reset: T keeps its value


def test_switching_follows_changed_parameters(simulate: Simulate, thermostat: hybrid.Automaton) -> None:
    overrides = {"a": 0.25, "T_low": 16.0, "T_high": 24.0}
    p = {**thermostat.parameters, **overrides}
    expected = np.array(switching_times(p, 6))
    run = simulate(
        thermostat, t_end=expected[-1] + 0.5, rtol=1e-12, atol=1e-12, parameters=overrides
    )
    assert np.abs(run.jump_times - expected).max() < 1e-8


def test_heating_power_is_a_location_signal(simulate: Simulate, thermostat: hybrid.Automaton) -> None:
    p = dict(thermostat.parameters)
    run = simulate(thermostat, t_end=10.0, rtol=1e-10, atol=1e-12)
    power = run["heating_power"]
    on = run.location == "on"
    assert on.any() and (~on).any()
    assert np.all(power[~on] == 0.0)
    np.testing.assert_allclose(power[on], p["a"] * (p["T_heat"] - p["T_out"]))
