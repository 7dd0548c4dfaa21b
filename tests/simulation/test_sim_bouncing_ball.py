"""Bouncing ball against its closed form (h0 = 10, g = 9.81, e = 0.8).

Dropped from rest at h0, the ball first hits the ground at t1 = sqrt(2 h0 / g)
with speed v0 = sqrt(2 g h0). Each bounce multiplies the speed by e, and the
flight after the k-th impact lasts 2 e^k v0 / g = 2 e^k t1, so

    t_k = t1 (1 + 2 e (1 - e^(k-1)) / (1 - e)),   k = 1, 2, ...

the speed just before impact k is e^(k-1) v0 and just after it e^k v0, and the
impacts accumulate at t1 (1 + e) / (1 - e) (Zeno).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support import Simulate

import hybrid

H0, G, E = 10.0, 9.81, 0.8
T1 = math.sqrt(2 * H0 / G)
V0 = math.sqrt(2 * G * H0)
T_ZENO = T1 * (1 + E) / (1 - E)


def impact_time(k: np.ndarray) -> np.ndarray:
    return T1 * (1 + 2 * E * (1 - E ** (k - 1)) / (1 - E))


def test_the_spec_is_the_closed_form_s_ball(ball: hybrid.Automaton) -> None:
    assert ball.parameters["g"] == G and ball.parameters["e"] == E
    assert ball.initial_vector() == [H0, 0.0]


@pytest.fixture(scope="module")
def run_before_zeno(simulate: Simulate, ball: hybrid.Automaton) -> hybrid.Run:
    """Up to shortly after the 30th impact, well before the Zeno time."""
    t_end = float(impact_time(np.array(30.0))) + 1e-4
    return simulate(ball, t_end=t_end, rtol=1e-10, atol=1e-12, max_jumps=1000)


def test_first_30_impact_times(run_before_zeno: hybrid.Run) -> None:
    run = run_before_zeno
    assert run.termination.cause == "t_end"
    assert len(run.jumps) == 30
    k = np.arange(1, 31, dtype=float)
    error = np.abs(run.jump_times - impact_time(k))
    assert error.max() < 1e-9, f"max |t_k error| = {error.max():.3g} s"
    assert all(jump.edge == "bounce" and jump.label == "bounce" for jump in run.jumps)


def test_velocities_at_impacts(run_before_zeno: hybrid.Run) -> None:
    k = np.arange(1, 31, dtype=float)
    before = np.array([jump.before["v"] for jump in run_before_zeno.jumps])
    after = np.array([jump.after["v"] for jump in run_before_zeno.jumps])
    np.testing.assert_allclose(before, -(E ** (k - 1)) * V0, rtol=0, atol=1e-8)
    np.testing.assert_allclose(after, E**k * V0, rtol=0, atol=1e-8)
    # the reset sets h to 0 exactly; before it, h is 0 up to the event location
    assert all(jump.after["h"] == 0.0 for jump in run_before_zeno.jumps)
    assert max(abs(jump.before["h"]) for jump in run_before_zeno.jumps) < 1e-9


def test_two_rows_per_jump(run_before_zeno: hybrid.Run) -> None:
    run = run_before_zeno
    assert np.all(np.diff(run.t) >= 0), "t never decreases"
    assert set(np.diff(run.j)) <= {0, 1}, "j grows by one at a jump and only there"
    for jump in run.jumps:
        rows = np.flatnonzero(run.t == jump.t)
        assert len(rows) == 2, f"jump at t={jump.t}: rows {rows}"
        pre, post = rows
        assert post == pre + 1
        assert (run.j[pre], run.j[post]) == (jump.j, jump.j + 1)
        assert run["h"][pre] == jump.before["h"] and run["v"][pre] == jump.before["v"]
        assert run["h"][post] == jump.after["h"] and run["v"][post] == jump.after["v"]
    # every other change of j is a jump row pair
    changes = np.flatnonzero(np.diff(run.j))
    assert len(changes) == len(run.jumps)
    assert np.all(run.t[changes] == run.t[changes + 1])


def test_energy_signal_follows_the_state(run_before_zeno: hybrid.Run) -> None:
    run = run_before_zeno
    np.testing.assert_allclose(run["energy"], 0.5 * run["v"] ** 2 + G * run["h"], rtol=1e-14)
    # energy after the k-th bounce: e^(2k) g h0, between bounces it is conserved
    last = run["energy"][-1]
    assert last == pytest.approx(E**60 * G * H0, rel=1e-6)


def test_ends_as_zeno_at_the_accumulation_time(simulate: Simulate, ball: hybrid.Automaton) -> None:
    run = simulate(ball, t_end=20.0, rtol=1e-10, atol=1e-12, max_jumps=10_000)
    term = run.termination
    assert term.cause == "zeno"
    assert term.zeno_time is not None
    assert abs(term.zeno_time - T_ZENO) / T_ZENO < 1e-6, term.zeno_time
    assert term.t < T_ZENO and term.t == run.jumps[-1].t == run.t[-1]
    assert term.j == len(run.jumps) == run.j[-1]
    assert "Zeno" in term.message


def test_zeno_not_reported_when_t_end_comes_first(simulate: Simulate, ball: hybrid.Automaton) -> None:
    run = simulate(ball, t_end=T_ZENO - 0.05, rtol=1e-10, atol=1e-12)
    assert run.termination.cause == "t_end"
    assert run.termination.zeno_time is None
