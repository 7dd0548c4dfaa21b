"""Requirements monitored on runs, against closed forms.

The heater of issue 13 cools as x' = -0.1 x from x = 20, so x(t) = 20 e^(-t/10):
``always: x >= 15`` over 5 s has robustness 20 e^-0.5 - 15 (< 0: violated) and
is violated where x = 15, at t = 10 ln(4/3). Windows and ``in:`` scoping are
checked on the same heater and on a sawtooth whose extremes are known by hand;
a dip inside one solver step on a harmonic oscillator (x = cos t, minimum -1 at
t = pi). A requirement never changes the run. Every test runs on both backends: the
compiled backend's runs are shown to the same monitor step by step
(:mod:`hybrid.simulation.native.monitoring`).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import hybrid
from hybrid.simulation.apart import independent_groups
from hybrid.simulation.monitor import join_groups

TIGHT = {"rtol": 1e-10, "atol": 1e-12, "handle_sigint": False}


HEATER = """
automaton: heater
state: {x: {initial: 20.0}}
locations: {cooling: {flow: {x: -0.1*x}}}
requirements:
  - {name: warm, always: "x >= 15"}
  - {name: mild, always: "x >= 12"}
  - {name: early, always: "x >= 15", within: [0, 2]}
  - {name: late, always: "x >= 15", within: [3, 4]}
  - {name: open_end, always: "x >= 15", within: [2, .inf]}
  - {name: cools, eventually: "x <= 15", within: [0, 5]}
  - {name: too_soon, eventually: "x <= 15", within: [0, 2]}
  - {name: strict, always: "x > 12.130613194252668"}
  - {name: both, always: "x >= 14 and x <= 19.5"}
"""


def x_of(t: float) -> float:
    return 20.0 * math.exp(-t / 10.0)


@pytest.fixture(scope="module")
def heater_run(backend: str) -> hybrid.Run:
    return hybrid.simulate(hybrid.load_text(HEATER), t_end=5.0, backend=backend, **TIGHT)


def test_always_robustness_and_crossing_of_the_heater(heater_run: hybrid.Run) -> None:
    warm = heater_run.requirements["warm"]
    assert not warm.holds
    assert warm.robustness == pytest.approx(20 * math.exp(-0.5) - 15, abs=1e-9)
    assert warm.violated_at == pytest.approx(10 * math.log(4 / 3), abs=1e-7)
    mild = heater_run.requirements["mild"]
    assert mild.holds and mild.violated_at is None
    assert mild.robustness == pytest.approx(x_of(5) - 12, abs=1e-9)


def test_windows_cut_the_scope(heater_run: hybrid.Run) -> None:
    early = heater_run.requirements["early"]
    assert early.holds and early.robustness == pytest.approx(x_of(2) - 15, abs=1e-9)
    late = heater_run.requirements["late"]
    # already below 15 when the window opens: violated at its start, robustness at its end
    assert not late.holds and late.violated_at == 3.0
    assert late.robustness == pytest.approx(x_of(4) - 15, abs=1e-9)
    open_end = heater_run.requirements["open_end"]
    assert open_end.violated_at == pytest.approx(10 * math.log(4 / 3), abs=1e-7)


def test_eventually_is_the_largest_margin_in_its_window(heater_run: hybrid.Run) -> None:
    cools = heater_run.requirements["cools"]
    assert cools.holds and cools.violated_at is None
    assert cools.robustness == pytest.approx(15 - x_of(5), abs=1e-9)
    too_soon = heater_run.requirements["too_soon"]
    # never reaches 15 within [0, 2]: violated when the window closes
    assert not too_soon.holds and too_soon.violated_at == 2.0
    assert too_soon.robustness == pytest.approx(15 - x_of(2), abs=1e-9)


def test_strict_and_compound_conditions(heater_run: hybrid.Run) -> None:
    # the margin of x > c is x - c as for x >= c; a run that ends on the level holds
    strict = heater_run.requirements["strict"]
    assert abs(strict.robustness) < 1e-9 and strict.holds
    # min(x - 14, 19.5 - x): -0.5 at t = 0 (violated there), x_of(5) - 14 at the end
    both = heater_run.requirements["both"]
    assert not both.holds and both.violated_at == 0.0
    assert both.robustness == pytest.approx(x_of(5) - 14, abs=1e-9)


def test_a_requirement_never_changes_the_run(backend: str) -> None:
    plain = hybrid.load_text(HEATER.split("requirements:")[0])
    with_reqs = hybrid.simulate(hybrid.load_text(HEATER), t_end=5.0, backend=backend, **TIGHT)
    without = hybrid.simulate(plain, t_end=5.0, backend=backend, **TIGHT)
    assert without.requirements == {}
    assert np.array_equal(with_reqs.t, without.t)
    assert np.array_equal(with_reqs.states, without.states)


# x rises at 1 from 18 to 22 (t = 4), falls at -2 to 18 (t = 6), and so on (period 6)
SAW = """
automaton: saw
state: {x: {initial: 18.0}}
locations:
  up: {flow: {x: 1}}
  down: {flow: {x: -2}}
  never: {}
edges:
  - {from: up, to: down, guard: x >= 22}
  - {from: down, to: up, guard: x <= 18}
requirements:
  - {name: low_in_down, always: "x >= 19", in: down}
  - {name: high_in_up, always: "x <= 21.5", in: up}
  - {name: peak_in_up, eventually: "x >= 23", in: up}
  - {name: stays_never, always: "x >= 100", in: never}
  - {name: reaches_never, eventually: "x >= 0", in: never}
  - {name: late_down, always: "x >= 19", in: down, within: [7, 11]}
"""


def test_in_location_scopes_to_the_time_spent_there(backend: str) -> None:
    run = hybrid.simulate(hybrid.load_text(SAW), t_end=11.0, backend=backend, **TIGHT)
    assert [j.t for j in run.jumps] == pytest.approx([4.0, 6.0, 10.0])
    r = run.requirements
    # in down x falls from 22 to 18; the first time below 19 is at t = 4 + 3/2
    assert r["low_in_down"].robustness == pytest.approx(-1.0, abs=1e-9)
    assert r["low_in_down"].violated_at == pytest.approx(5.5, abs=1e-7)
    # in up x reaches 22 (the pre-jump point at t = 4): above 21.5 from t = 3.5 on
    assert r["high_in_up"].robustness == pytest.approx(-0.5, abs=1e-9)
    assert r["high_in_up"].violated_at == pytest.approx(3.5, abs=1e-7)
    assert r["peak_in_up"].robustness == pytest.approx(-1.0, abs=1e-9)
    assert not r["peak_in_up"].holds and r["peak_in_up"].violated_at == 11.0
    # never entered: `always` holds vacuously, `eventually` fails when the run ends
    assert r["stays_never"].holds and r["stays_never"].robustness == math.inf
    assert not r["reaches_never"].holds and r["reaches_never"].robustness == -math.inf
    assert r["reaches_never"].violated_at == 11.0
    # window [7, 11] meets the second stay in down only from t = 10 (x = 22 there)
    late = r["late_down"]
    assert late.robustness == pytest.approx(22 - 2 * 1.0 - 19, abs=1e-9)
    assert late.holds


OSCILLATOR = """
automaton: oscillator
state: {x: {initial: 1.0}, y: {initial: 0.0}}
locations: {turning: {flow: {x: y, y: -x}}}
requirements:
  - {name: above_minus_one_and_a_half, always: "x >= -1.5"}
  - {name: above_minus_099, always: "x >= -0.99"}
  - {name: reaches_top_again, eventually: "x >= 1", within: [1, 7]}
"""


def test_a_dip_inside_one_step_is_found(backend: str) -> None:
    run = hybrid.simulate(hybrid.load_text(OSCILLATOR), t_end=4.0, backend=backend, **TIGHT)
    # the minimum at t = pi lies inside a step (no stored point near it): it is refined,
    # not read off the samples (a sample a quarter step away would be off by ~1e-4)
    assert np.min(np.abs(run.t - math.pi)) > 1e-3
    r = run.requirements
    assert r["above_minus_one_and_a_half"].robustness == pytest.approx(0.5, abs=1e-9)
    assert r["above_minus_099"].robustness == pytest.approx(-0.01, abs=1e-9)
    assert r["above_minus_099"].violated_at == pytest.approx(math.acos(-0.99), abs=1e-7)
    # the run ends at 4 < 2 pi: the window closes at the end of the run, unmet
    top = r["reaches_top_again"]
    assert not top.holds and top.violated_at == 4.0
    assert top.robustness == pytest.approx(math.cos(1.0) - 1, abs=1e-9)  # at the window start


def test_the_bouncing_ball_touches_its_floor_and_holds(backend: str) -> None:
    text = Path("specs/bouncing_ball.yaml").read_text()
    ball = hybrid.load_text(text + "requirements:\n  - {name: above_floor, always: 'h >= 0'}\n")
    run = hybrid.simulate(ball, t_end=5.0, backend=backend, **TIGHT)
    floor = run.requirements["above_floor"]
    assert floor.holds and abs(floor.robustness) < 1e-9


def test_an_evaluation_error_is_reported_and_the_run_goes_on(backend: str) -> None:
    model = hybrid.load_text(
        HEATER.split("requirements:")[0]
        + "requirements:\n  - {name: rooted, always: 'sqrt(x - 19) >= 0'}\n"
    )
    run = hybrid.simulate(model, t_end=5.0, backend=backend, **TIGHT)
    assert run.termination.cause == "t_end"
    rooted = run.requirements["rooted"]
    assert not rooted.holds and math.isnan(rooted.robustness)
    assert rooted.violated_at == pytest.approx(10 * math.log(20 / 19), abs=0.05)
    assert "sqrt" in rooted.message and "math domain error" in rooted.message


BLOCKER = """
automaton: stopper
state: {c: {initial: 0.0}}
locations: {ticking: {flow: {c: 1}, invariant: c <= 1}}
"""


def test_apart_groups_keep_their_requirements_and_cut_them_at_the_system_end(backend: str) -> None:
    heater = hybrid.load_text(HEATER)
    ball = hybrid.load("specs/bouncing_ball.yaml")
    alone = hybrid.simulate(heater, t_end=5.0, backend=backend, **TIGHT)
    system = hybrid.compose(ball, heater)
    assert independent_groups(system) == [(0,), (1,)]
    together = hybrid.simulate(system, t_end=5.0, backend=backend, **TIGHT)
    for name, expected in alone.requirements.items():
        got = together.requirements[f"heater.{name}"]
        assert (got.holds, got.violated_at is None) == (
            expected.holds,
            expected.violated_at is None,
        )
        assert got.robustness == pytest.approx(expected.robustness, abs=1e-9)
    # another group blocks at t = 1: the heater's requirements are judged up to t = 1
    cut = hybrid.simulate(
        hybrid.compose(hybrid.load_text(BLOCKER), heater), t_end=5.0, backend=backend, **TIGHT
    )
    assert cut.termination.cause == "blocked" and cut.termination.t == pytest.approx(1.0)
    warm = cut.requirements["heater.warm"]
    assert warm.holds and warm.robustness == pytest.approx(x_of(1.0) - 15, abs=1e-9)
    cools = cut.requirements["heater.cools"]
    assert not cools.holds and cools.violated_at == pytest.approx(1.0)


SPANNING = """
system: both
components:
  - spec: BALL
  - spec: HEATER
requirements:
  - {name: sum, always: "h + x >= 20"}
  - {name: own, always: "x >= 15"}
"""


def test_a_requirement_spanning_groups_joins_them(tmp_path: Path, backend: str) -> None:
    base = tmp_path
    (base / "heater.yaml").write_text(HEATER)
    ball = str(Path("specs/bouncing_ball.yaml").resolve())
    text = SPANNING.replace("BALL", ball).replace("HEATER", "heater.yaml")
    (base / "both.yaml").write_text(text)
    system = hybrid.load(base / "both.yaml")
    assert join_groups(system, independent_groups(system)) == [(0, 1)]
    run = hybrid.simulate(system, t_end=3.0, dt=1e-4, backend=backend, **TIGHT)
    sampled = float(np.min(run["h"] + run["x"]) - 20)
    total = run.requirements["sum"]
    assert total.robustness <= sampled + 1e-12
    assert total.robustness == pytest.approx(sampled, abs=1e-6)
    # h + x first reaches 20 on the first fall: h = 10 - 9.81 t^2 / 2, x = 20 e^(-t/10)
    from scipy.optimize import brentq

    first = brentq(lambda t: 10 - 4.905 * t * t + x_of(t) - 20, 0.1, 1.4)
    assert total.violated_at == pytest.approx(first, abs=1e-7)
    assert run.requirements["own"].violated_at == pytest.approx(10 * math.log(4 / 3), abs=1e-7)
