"""The compiled backend against the scipy backend on every spec of specs/ without library functions.

The bouncing ball (impacts and Zeno time in closed form), the thermostat
(switching times in closed form) and the polarization machine, driven in a
system by a small automaton that defines its input signal.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support import SPECS

import hybrid
from hybrid.compose import as_system, compose

pytest.importorskip("numba")

TOL = {"rtol": 1e-10, "atol": 1e-12, "handle_sigint": False}

DRIVER = """
automaton: driver
parameters: {mean: 1.1, swing: 0.5, rate: 0.7}
state: {phase: {initial: 0.0}}
signals:
  gamma: mean + swing * sin(rate * phase)
locations: {run: {flow: {phase: 1}}}
"""


def agree(model: hybrid.Automaton | hybrid.System, t_end: float, **kwargs: object) -> tuple[hybrid.Run, hybrid.Run]:
    compiled = hybrid.simulate(model, t_end=t_end, backend="compiled", **TOL, **kwargs)  # type: ignore[arg-type]
    reference = hybrid.simulate(model, t_end=t_end, **TOL, **kwargs)  # type: ignore[arg-type]
    assert [(j.edge, j.source, j.target) for j in compiled.jumps] == [
        (j.edge, j.source, j.target) for j in reference.jumps
    ]
    np.testing.assert_allclose(compiled.jump_times, reference.jump_times, rtol=1e-10, atol=1e-9)
    assert compiled.termination.cause == reference.termination.cause
    assert compiled.termination.message == reference.termination.message or (
        compiled.termination.cause == "zeno"
    )
    assert compiled.signal_names == reference.signal_names
    assert compiled.state_names == reference.state_names
    return compiled, reference


def test_bouncing_ball_impacts_and_zeno_time(ball: hybrid.Automaton) -> None:
    compiled, reference = agree(ball, 20.0)
    g, e, h0 = 9.81, 0.8, 10.0
    t1 = math.sqrt(2 * h0 / g)
    impacts = [t1 * (1 + 2 * e * (1 - e ** (k - 1)) / (1 - e)) for k in range(1, 20)]
    np.testing.assert_allclose(compiled.jump_times[:19], impacts, rtol=1e-10, atol=1e-9)
    term = compiled.termination
    assert term.cause == "zeno"
    assert term.zeno_time == pytest.approx(t1 * (1 + e) / (1 - e), rel=1e-9)
    assert term.zeno_time == pytest.approx(reference.termination.zeno_time, rel=1e-10)
    np.testing.assert_allclose(compiled["energy"][:5], reference["energy"][:5], rtol=1e-12)


def test_thermostat_switching_times(thermostat: hybrid.Automaton) -> None:
    compiled, _ = agree(thermostat, 100.0)
    a, t_out, t_heat, low, high = 0.1, 10.0, 30.0, 18.0, 22.0
    times = [math.log((20 - t_out) / (low - t_out)) / a]
    up = math.log((t_heat - low) / (t_heat - high)) / a
    down = math.log((high - t_out) / (low - t_out)) / a
    while len(times) < len(compiled.jumps):
        times.append(times[-1] + (up if len(times) % 2 == 1 else down))
    np.testing.assert_allclose(compiled.jump_times, times, rtol=1e-10, atol=1e-9)
    heating = compiled["heating_power"][compiled.location == "on"]
    assert np.all(heating == pytest.approx(a * (t_heat - t_out)))


def test_parameters_and_initial_values_do_not_recompile(thermostat: hybrid.Automaton) -> None:
    from hybrid.simulation.native.engine import compiled_native

    warmer = thermostat.with_parameters({"T_high": 24.0})
    assert compiled_native(as_system(warmer)) is compiled_native(as_system(thermostat))
    agree(warmer, 60.0, initial={"T": 19.0})


def test_polarization_driven_in_a_system() -> None:
    polarization = hybrid.load(SPECS / "polarization.yaml")
    driver = hybrid.load_text(DRIVER)
    assert isinstance(polarization, hybrid.Automaton) and isinstance(driver, hybrid.Automaton)
    system = compose(driver, polarization, name="driven")
    # the input varies while the flow is linear: cap the step so that RK45 sees every crossing
    compiled, reference = agree(system, 40.0, max_step=0.2)
    assert len(compiled.jumps) >= 4
    assert set(compiled.location) == set(reference.location)
    np.testing.assert_allclose(compiled["theta_p"], reference["theta_p"], atol=1e-12)
    np.testing.assert_allclose(compiled["gamma"], reference["gamma"], rtol=1e-9, atol=1e-9)
