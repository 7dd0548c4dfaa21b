"""The Python API ``hybrid.simulate``: overrides of parameters, initial conditions, inputs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from support import SPECS

import hybrid

TOL = {"rtol": 1e-10, "atol": 1e-12}

DRIVEN = """
automaton: driven
inputs: [u]
state: {x: {initial: 0.0}}
signals: {doubled: 2*u}
locations:
  A: {flow: {x: u}}
"""


def test_parameter_overrides(ball: hybrid.Automaton) -> None:
    moon = hybrid.simulate(ball, t_end=4.0, parameters={"g": 1.62, "e": 0.5}, **TOL)
    first = moon.jumps[0]
    assert first.t == pytest.approx(math.sqrt(2 * 10.0 / 1.62), abs=1e-9)
    assert first.after["v"] == pytest.approx(0.5 * math.sqrt(2 * 1.62 * 10.0), abs=1e-8)
    assert moon.settings["t_end"] == 4.0
    assert ball.parameters["g"] == 9.81, "the loaded model is not changed"


def test_parameters_when_loading(tmp_path: object) -> None:
    model = hybrid.load(SPECS / "bouncing_ball.yaml", parameters={"e": 0.7})
    run = hybrid.simulate(model, t_end=2.0, **TOL)
    assert run.jumps[0].after["v"] == pytest.approx(0.7 * math.sqrt(2 * 9.81 * 10.0), abs=1e-8)


def test_unknown_parameter_is_a_spec_error(ball: hybrid.Automaton) -> None:
    with pytest.raises(hybrid.SpecError, match="unknown parameter 'gg'"):
        hybrid.simulate(ball, t_end=1.0, parameters={"gg": 1.0})


def test_initial_state_override(ball: hybrid.Automaton) -> None:
    run = hybrid.simulate(ball, t_end=2.0, initial={"h": 5.0}, **TOL)
    assert run["h"][0] == 5.0 and run.t[0] == 0.0
    assert run.jumps[0].t == pytest.approx(math.sqrt(2 * 5.0 / 9.81), abs=1e-9)
    thrown = hybrid.simulate(ball, t_end=3.0, initial={"h": 0.0, "v": 5.0}, **TOL)
    # thrown up from the ground at 5 m/s: the guard h <= 0 (v > 0) is not enabled at
    # the start; it lands at t = 2 v / g
    assert thrown.jumps[0].t == pytest.approx(2 * 5.0 / 9.81, abs=1e-9)


def test_unknown_initial_state_is_an_error(ball: hybrid.Automaton) -> None:
    with pytest.raises((hybrid.SpecError, hybrid.SimulationError), match="hh"):
        hybrid.simulate(ball, t_end=1.0, initial={"hh": 1.0})


def test_initial_location_override() -> None:
    thermostat = hybrid.load(SPECS / "thermostat.yaml")
    run = hybrid.simulate(thermostat, t_end=5.0, initial_location="on", **TOL)
    assert run.location[0] == "on"
    jump = run.jumps[0]
    # heating from 20 to T_high = 22 with a = 0.1, T_heat = 30
    assert jump.edge == "turn_off"
    assert jump.t == pytest.approx(math.log((30 - 20) / (30 - 22)) / 0.1, abs=1e-9)
    with pytest.raises(hybrid.SpecError, match="unknown initial location 'of'"):
        hybrid.simulate(thermostat, t_end=1.0, initial_location="of")


def test_external_input_as_a_function_of_t() -> None:
    model = hybrid.load_text(DRIVEN)
    run = hybrid.simulate(model, t_end=10.0, inputs={"u": math.cos}, dt=0.1, **TOL)
    assert run.termination.cause == "t_end"
    np.testing.assert_allclose(run["x"], np.sin(run.t), atol=1e-8)
    np.testing.assert_allclose(run["doubled"], 2 * np.cos(run.t), atol=1e-12)
    assert len(run) == 101


def test_missing_or_unknown_input_is_a_simulation_error() -> None:
    model = hybrid.load_text(DRIVEN)
    with pytest.raises(hybrid.SimulationError, match="input 'u' needs a value"):
        hybrid.simulate(model, t_end=1.0)
    with pytest.raises(hybrid.SimulationError, match="'w' is not a declared input"):
        hybrid.simulate(model, t_end=1.0, inputs={"u": math.cos, "w": math.sin})


GUARDED_BY_INPUT = """
automaton: gate
inputs: [u]
state: {x: {initial: 1}}
locations:
  a: {flow: {x: 0}, invariant: u >= 0}
  b: {flow: {x: 0}}
edges:
  - {from: a, to: b, guard: u <= -1}
"""


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_an_input_function_giving_nan_ends_the_run_naming_it(bad: float) -> None:
    """u read only by a guard and an invariant: a NaN made both false, and the run
    reported t_end; a flow reading it said "x' = nan" without naming the input."""
    model = hybrid.load_text(GUARDED_BY_INPUT)
    run = hybrid.simulate(model, t_end=3.0, inputs={"u": lambda t: 1.0 if t < 1 else bad},
                          handle_sigint=False)  # fmt: skip
    term = run.termination
    assert term.cause == "nonfinite" and 1.0 <= term.t < 1.01, term
    assert f"input 'u' gave {bad} at t=" in term.message


def test_dense_output_and_max_jumps(ball: hybrid.Automaton) -> None:
    run = hybrid.simulate(ball, t_end=10.0, max_jumps=3, dense=True, **TOL)
    assert run.termination.cause == "max_jumps" and len(run.jumps) == 3
    # the run flows on after the third jump and stops where a fourth would be taken
    t1 = math.sqrt(2 * 10.0 / 9.81)
    t4 = t1 * (1 + 2 * 0.8 * (1 - 0.8**3) / (1 - 0.8))
    assert run.termination.j == 3 and run.termination.t == pytest.approx(t4, abs=1e-9)
    assert run.t[-1] == run.termination.t and run.j[-1] == 3
    assert len(run.segments) == 4
    j, t0, t1, interpolant = run.segments[0]
    assert (j, t0) == (0, 0.0) and t1 == run.jumps[0].t
    assert interpolant(0.5)[0] == pytest.approx(10.0 - 9.81 * 0.25 / 2, abs=1e-9)


@pytest.mark.parametrize(
    ("settings", "message"),
    [
        ({"t_end": -1.0}, "t_end must be"),
        ({"t_end": math.inf}, "t_end must be"),
        ({"t_end": 1.0, "rtol": 0.0}, "rtol must be at least 2.22e-14"),
        ({"t_end": 1.0, "max_step": -1.0}, "max_step must be > 0"),
        ({"t_end": 1.0, "dt": 0.0}, "dt must be > 0"),
        ({"t_end": 1.0, "method": "Euler"}, "unknown method 'Euler'"),
        ({"t_end": 1.0, "max_jumps": -1}, "max_jumps must be >= 0"),
    ],
)
def test_bad_settings_are_simulation_errors(
    ball: hybrid.Automaton, settings: dict[str, object], message: str
) -> None:
    with pytest.raises(hybrid.SimulationError, match=message):
        hybrid.simulate(ball, **settings)  # type: ignore[arg-type]


@pytest.mark.parametrize("method", ["RK45", "RK23", "DOP853", "Radau", "BDF", "LSODA"])
def test_every_method_finds_the_first_impact(ball: hybrid.Automaton, method: str) -> None:
    run = hybrid.simulate(ball, t_end=2.0, method=method, rtol=1e-8, atol=1e-10)
    assert run.jumps[0].t == pytest.approx(math.sqrt(2 * 10.0 / 9.81), abs=1e-6)
