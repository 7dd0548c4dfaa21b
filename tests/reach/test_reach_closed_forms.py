"""Flowpipes against closed forms: they hold the exact reachable set and are not much wider.

- the heater ``x' = -a x + b u`` from a box of ``x`` with ``u`` in a box: the
  system is monotone, so the exact interval hull at ``t`` comes from the extreme
  initial values with the extreme inputs held constant:
  ``x(t) = x0 e^{-at} + (b u / a)(1 - e^{-at})``; over a segment each of those two
  trajectories is monotone, so the segment's exact hull is given by its ends;
- the rotation ``x' = y, y' = -x``: the box rotates rigidly; the exact interval
  hull at ``t`` is ``R(t) c +- |R(t)| r`` (the hull of a rotated box), sampled
  densely inside each segment.

The stated factor: a set is at most 1.01 times as wide as the exact hull over
its time interval, at step 0.01 (measured: 1.0036 for the heater without
inputs, 1.0070 with them, 1.0006 for the rotation over a full turn).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import hybrid
from hybrid.reach.flowpipe import exp_matrices, flowpipe

ROUND = 1e-12
"""Rounding of the closed forms themselves (``1.1 + 0.1`` is ``1.2000000000000002``)."""

HEATER = """
automaton: heater
parameters: {a: 0.7, b: 2.0}
state: {x: {initial: [{lo}, {hi}]}}
inputs: {u: {range: [{ulo}, {uhi}]}}
locations: {on: {flow: {x: -a * x + b * u}}}
"""


def _heater(lo: float, hi: float, ulo: float, uhi: float) -> hybrid.Automaton:
    text = (
        HEATER.replace("{lo}", repr(lo))
        .replace("{hi}", repr(hi))
        .replace("{ulo}", repr(ulo))
        .replace("{uhi}", repr(uhi))
    )
    return hybrid.load_text(text)


def _heater_exact(x0: float, u: float, t: float, a: float = 0.7, b: float = 2.0) -> float:
    return x0 * math.exp(-a * t) + (b * u / a) * (1.0 - math.exp(-a * t))


@pytest.mark.parametrize(("ulo", "uhi"), [(1.0, 1.0), (0.5, 1.5)])
def test_heater_sets_hold_the_exact_hull_and_are_tight(ulo: float, uhi: float) -> None:
    model = _heater(10.0, 12.0, ulo, uhi)
    result = hybrid.reach(model, t_end=5.0, step=0.01)
    assert len(result.sets) == 501  # the initial box at t = 0, then 500 steps
    for s in result.sets:
        t0, t1 = s.t
        ends = [_heater_exact(x, u, t) for x, u in ((10.0, ulo), (12.0, uhi)) for t in (t0, t1)]
        low = min(_heater_exact(10.0, ulo, t) for t in (t0, t1))
        high = max(_heater_exact(12.0, uhi, t) for t in (t0, t1))
        assert s.lo[0] <= low + ROUND * abs(low) and s.hi[0] >= high - ROUND * abs(high), (
            s.t,
            s.lo,
            s.hi,
            ends,
        )
        assert s.hi[0] - s.lo[0] <= 1.01 * (high - low)


def test_heater_step_points_are_exact_without_inputs() -> None:
    a = np.array([[-0.7]])
    pipe = flowpipe(
        a,
        np.zeros((1, 0)),
        np.array([2.0]),
        np.zeros(0),
        np.zeros(0),
        np.array([10.0]),
        np.array([12.0]),
        0.1,
        30,
    )
    for k in (0, 10, 30):
        t = 0.1 * k
        assert pipe.point_lo[k, 0] == pytest.approx(_heater_exact(10.0, 1.0, t), rel=1e-9)
        assert pipe.point_hi[k, 0] == pytest.approx(_heater_exact(12.0, 1.0, t), rel=1e-9)
        assert pipe.point_lo[k, 0] <= _heater_exact(10.0, 1.0, t)
        assert pipe.point_hi[k, 0] >= _heater_exact(12.0, 1.0, t)


ROTATION = """
automaton: rotation
state: {x: {initial: [1.0, 1.2]}, y: {initial: [-0.1, 0.1]}}
locations: {turn: {flow: {x: y, y: -x}}}
"""


def _rotation_hull(t: float) -> tuple[np.ndarray, np.ndarray]:
    r = np.array([[math.cos(t), math.sin(t)], [-math.sin(t), math.cos(t)]])
    c, rad = np.array([1.1, 0.0]), np.array([0.1, 0.1])
    mid = r @ c
    spread = np.abs(r) @ rad
    return mid - spread, mid + spread


def test_rotation_sets_hold_the_rotating_box_and_are_tight() -> None:
    model = hybrid.load_text(ROTATION)
    result = hybrid.reach(model, t_end=2 * math.pi, step=0.01)
    worst = 0.0
    for s in result.sets:
        samples = [_rotation_hull(t) for t in np.linspace(s.t[0], s.t[1], 21)]
        low = np.min([lo for lo, _ in samples], axis=0)
        high = np.max([hi for _, hi in samples], axis=0)
        ok = np.all(s.lo <= low + ROUND * np.abs(low)) and np.all(
            s.hi >= high - ROUND * np.abs(high)
        )
        assert ok, (s.t, s.lo, low, s.hi, high)
        worst = max(worst, float(np.max((s.hi - s.lo) / (high - low))))
    assert worst <= 1.01


def test_exp_matrices_match_their_series() -> None:
    a = np.array([[0.0, 1.0], [-2.0, -0.3]])
    h = 0.2
    phi, phi1, phi2 = exp_matrices(a, h)
    terms = [np.linalg.matrix_power(a, k) for k in range(25)]
    assert np.allclose(phi, sum(t * h**k / math.factorial(k) for k, t in enumerate(terms)))
    assert np.allclose(
        phi1, sum(t * h ** (k + 1) / math.factorial(k + 1) for k, t in enumerate(terms))
    )
    assert np.allclose(
        phi2, sum(t * h ** (k + 2) / math.factorial(k + 2) for k, t in enumerate(terms))
    )


def test_heater_with_a_forbidden_set_is_proved_below_and_refuted_above() -> None:
    model = hybrid.load_text(_heater_text_with_forbidden())
    result = hybrid.reach(model, t_end=5.0, step=0.01)
    verdicts = [p.verdict for p in result.properties]
    assert verdicts == ["proved", "refuted"]
    witness = result.properties[1]
    assert witness.witness is not None and witness.witness_time is not None
    # the witness replays: the same initial point and inputs reach the set again
    replay = hybrid.simulate(
        model,
        witness.witness.t[-1],
        initial=witness.witness_initial,
        inputs=witness.witness_inputs,
        rtol=1e-9,
        atol=1e-12,
        handle_sigint=False,
    )
    assert replay["x"].max() > 4.0


def _heater_text_with_forbidden() -> str:
    # the highest run: x0 = 2, u = 1.5, x(t) = 2 e^{-0.7 t} + (3 / 0.7)(1 - e^{-0.7 t}) < 4.2858:
    # above 4.0 from t = 2.97, never above 4.3
    return (
        HEATER.replace("{lo}", "1.0")
        .replace("{hi}", "2.0")
        .replace("{ulo}", "0.5")
        .replace("{uhi}", "1.5")
        + "properties:\n  forbidden:\n    - {when: x > 4.3}\n    - {when: x > 4.0}\n"
    )


THERMO_CYCLES = """
automaton: thermo
state: {x: {initial: [19, 20]}}
locations:
  on:  {flow: {x: -0.1 * (x - 30)}, invariant: x <= 22}
  off: {flow: {x: -0.1 * x}, invariant: x >= 18}
edges:
  - {from: on, to: off, guard: x >= 22}
  - {from: off, to: on, guard: x <= 18}
properties:
  forbidden:
    - {when: "t >= 50"}
"""


def test_a_proof_cut_by_the_jump_bound_says_from_when() -> None:
    """Ten jumps are over by t = 32.5 for the earliest start: 'proved within t <= 60 and 10
    jumps' said nothing of the runs after (a new user read it as proved to t = 60). The
    earliest 11th jump, closed form: from x0 = 20 on, 10 ln(10/8) to the first switch, then
    five off stays 10 ln(22/18) and five on stays 10 ln(12/8)."""
    model = hybrid.load_text(THERMO_CYCLES)
    first = 10 * math.log(10 / 8) + 5 * 10 * (math.log(22 / 18) + math.log(12 / 8))
    result = hybrid.reach(model, 60.0, max_jumps=10)
    assert result.verdict == "proved" and result.jump_bound_from is not None
    assert first - 0.5 <= result.jump_bound_from <= first  # never later than a run's
    assert "may take jump 11 from t = " in result.properties[0].message
    assert result.as_dict()["jump_bound_from"] == result.jump_bound_from
    # jump 21 comes after t = 60 for every start: nothing is left out
    assert hybrid.reach(model, 60.0, max_jumps=20).jump_bound_from is None


STIFF = """
automaton: stiff
state: {x: {initial: [0, 1]}, y: {initial: [0, 1]}}
locations: {a: {flow: {x: -1000 * x + y, y: -0.1 * y}}}
properties:
  forbidden:
    - {when: x >= 1.5}
"""


def test_an_unknown_from_a_long_step_says_to_shorten_it() -> None:
    """x never exceeds 1 (x' < 0 wherever x > y / 1000 and y <= 1), but at the default
    step of 10 / 4000 the sets of the stiff mode bloat past 1.5: 'unknown', with no word
    about the step (|A| h = 1001 * 0.0025). Ten times shorter, it is proved."""
    model = hybrid.load_text(STIFF)
    (entry,) = hybrid.reach(model, 10.0).properties
    assert entry.verdict == "unknown"
    assert "the step is long against the dynamics (|A| h = 2.5 in a)" in entry.message
    (proved,) = hybrid.reach(model, 10.0, step=2.5e-4).properties
    assert proved.verdict == "proved" and "step is long" not in proved.message
