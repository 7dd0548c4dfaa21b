"""Our robustness agrees with an independent STL monitor (rtamt) where both apply.

rtamt's discrete-time monitor reads a signal at uniform samples; our monitor reads
the continuous trajectory. They apply to the same number where the extremes of the
trajectory over each scope fall on the samples: piecewise-linear flows whose jumps
and window ends lie on the sampling grid (the sawtooth), and monotone flows with
window ends on the grid (the heater). There the two must agree to 1e-9.

``in: loc`` has no STL counterpart; it is written as rtamt's implication
``always((inloc > 0) -> p)`` (and conjunction ``eventually((inloc > 0) and p)``)
with ``inloc`` = +1e6 in the location and -1e6 outside, so points outside never
decide the minimum (maximum).
"""

from __future__ import annotations

import numpy as np
import pytest

import hybrid

rtamt = pytest.importorskip("rtamt", reason="rtamt is in the test extra")

DT = 0.25
BIG = 1e6

SAW = """
automaton: saw
state: {x: {initial: 18.0}}
locations:
  up: {flow: {x: 1}}
  down: {flow: {x: -2}}
edges:
  - {from: up, to: down, guard: x >= 22}
  - {from: down, to: up, guard: x <= 18}
requirements:
  - {name: above, always: "x >= 18.5"}
  - {name: below, always: "x <= 21.5", within: [1, 5]}
  - {name: reaches, eventually: "x >= 21", within: [6, 9]}
  - {name: band, always: "x >= 18.25 and x <= 21.75", within: [2, 8]}
  - {name: either, always: "x <= 19 or x >= 20"}
  - {name: low_in_down, always: "x >= 19", in: down}
  - {name: high_in_up, eventually: "x >= 21.5", in: up, within: [6, 11]}
"""

STL = {
    "above": "always(x >= 18.5)",
    "below": "always[1,5](x <= 21.5)",
    "reaches": "eventually[6,9](x >= 21)",
    "band": "always[2,8]((x >= 18.25) and (x <= 21.75))",
    "either": "always((x <= 19) or (x >= 20))",
    "low_in_down": "always((down > 0) -> (x >= 19))",
    "high_in_up": "eventually[6,11]((up > 0) and (x >= 21.5))",
}

HEATER = """
automaton: heater
state: {x: {initial: 20.0}}
locations: {cooling: {flow: {x: -0.1*x}}}
requirements:
  - {name: warm, always: "x >= 15"}
  - {name: early, always: "x >= 15", within: [0, 2]}
  - {name: cools, eventually: "x <= 15", within: [1, 4]}
"""

HEATER_STL = {
    "warm": "always(x >= 15)",
    "early": "always[0,2](x >= 15)",
    "cools": "eventually[1,4](x <= 15)",
}


def _signals(run: hybrid.Run, locations: tuple[str, ...]) -> dict[str, list[float]]:
    """The run at the grid times, one value per time (a jump keeps x: its two rows agree)."""
    ticks = np.round(run.t / DT).astype(int)
    assert np.allclose(run.t, ticks * DT, atol=1e-9), "every stored point lies on the grid"
    grid, first = np.unique(ticks, return_index=True)
    assert np.array_equal(grid, np.arange(grid[-1] + 1)), "no grid point is missing"
    data: dict[str, list[float]] = {"time": (grid * DT).tolist(), "x": run["x"][first].tolist()}
    for loc in locations:
        data[loc] = [BIG if np.any(run.location[ticks == k] == loc) else -BIG for k in grid]
    return data


def _rtamt(formula: str, signals: dict[str, list[float]]) -> float:
    spec = rtamt.StlDiscreteTimeSpecification()
    for name in signals:
        if name != "time":
            spec.declare_var(name, "float")
    spec.set_sampling_period(int(DT * 1000), "ms", 0.01)
    spec.spec = formula
    spec.parse()
    return float(spec.evaluate(signals)[0][1])


def test_sawtooth_robustness_agrees_with_rtamt() -> None:
    run = hybrid.simulate(hybrid.load_text(SAW), t_end=11.0, dt=DT, rtol=1e-10, atol=1e-12)
    assert [round(j.t, 9) for j in run.jumps] == [4.0, 6.0, 10.0]
    signals = _signals(run, ("up", "down"))
    for name, formula in STL.items():
        ours = run.requirements[name].robustness
        assert ours == pytest.approx(_rtamt(formula, signals), abs=1e-9), name


def test_heater_robustness_agrees_with_rtamt() -> None:
    run = hybrid.simulate(hybrid.load_text(HEATER), t_end=5.0, dt=DT, rtol=1e-12, atol=1e-13)
    signals = _signals(run, ())
    for name, formula in HEATER_STL.items():
        ours = run.requirements[name].robustness
        assert ours == pytest.approx(_rtamt(formula, signals), abs=1e-9), name
