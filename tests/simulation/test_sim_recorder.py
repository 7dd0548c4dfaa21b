"""The recorder's columns: what each stored stretch held, in order, whatever its form."""

from __future__ import annotations

import numpy as np

import hybrid
from hybrid.simulation.recorder import _signal_rows


def test_rows_of_one_point_and_arrays_of_several_are_joined_in_order() -> None:
    stretches = [
        [(1.0, 2.0)],  # a jump's point: a list of one row
        np.array([[3.0, 4.0], [5.0, 6.0]]),  # a stay's points: an array
        [(7.0, 8.0)],
        [(9.0, 10.0)],
    ]
    joined = _signal_rows(stretches, 2)
    np.testing.assert_array_equal(joined, np.arange(1.0, 11.0).reshape(5, 2))
    assert _signal_rows([[()], np.empty((3, 0))], 0).shape == (4, 0)  # no signals
    assert _signal_rows([], 3).shape == (0, 3)


def test_a_grid_run_stores_each_points_signal_as_its_location_defines_it() -> None:
    # the thermostat's heating_power is a*(T_heat - T_out) = 2 while on, 0 while off
    run = hybrid.simulate(hybrid.load("specs/thermostat.yaml"), t_end=100.0, dt=0.1)
    on = run.location == "on"
    assert on.any() and (~on).any()
    np.testing.assert_array_equal(run["heating_power"][on], 2.0)
    np.testing.assert_array_equal(run["heating_power"][~on], 0.0)
    assert len(run) > 1000  # stays of many points each, and the jumps' single points
