"""A compiled run's jumps: kept in arrays, each record built on access, equal to the list."""

from __future__ import annotations

import math
import pickle

import pytest
from support import SPECS

import hybrid
from hybrid.simulation.native.assemble import JumpRecords
from hybrid.simulation.result import Jump

BALL = hybrid.load(SPECS / "bouncing_ball.yaml", parameters={"e": 0.9})
TOL = {"rtol": 1e-10, "atol": 1e-12, "handle_sigint": False}


def test_jumps_are_records_over_arrays_equal_to_the_reference_list() -> None:
    run = hybrid.simulate(BALL, t_end=100.0, max_jumps=12, backend="compiled", **TOL)
    reference = hybrid.simulate(BALL, t_end=100.0, max_jumps=12, backend="scipy", **TOL)
    jumps = run.jumps
    assert isinstance(jumps, JumpRecords) and len(jumps) == 12
    # impact k at t1 (1 + 2 (e + ... + e^(k-1))), t1 = sqrt(2 h0 / g); v := -e v
    t1 = math.sqrt(2 * 10.0 / 9.81)
    impacts = [t1 * (1 + 2 * sum(0.9**i for i in range(1, k))) for k in range(1, 13)]
    assert max(abs(a - b) for a, b in zip(run.jump_times, impacts, strict=True)) < 1e-9
    for k, jump in enumerate(jumps):
        assert isinstance(jump, Jump) and jump.j == k and jump.edge == "bounce"
        assert jump.after["v"] == -0.9 * jump.before["v"] and jump.after["h"] == 0.0
    assert max(abs(a.t - b.t) for a, b in zip(jumps, reference.jumps, strict=True)) < 1e-11
    assert [(j.edge, j.source, j.target, j.enabled, j.chosen_by) for j in jumps] == [
        (j.edge, j.source, j.target, j.enabled, j.chosen_by) for j in reference.jumps
    ]
    assert jumps == list(jumps) and list(jumps) == jumps and jumps == jumps
    assert jumps != list(jumps)[:-1] and jumps != tuple(jumps)
    assert jumps[-1] == jumps[11] == list(jumps)[11]
    assert jumps[2:5] == list(jumps)[2:5] and jumps[::-3] == list(jumps)[::-3]
    with pytest.raises(IndexError):
        jumps[12]
    first = list(jumps)[:1]
    assert jumps + first == [*jumps, jumps[0]] and first + jumps == [jumps[0], *jumps]
    again = pickle.loads(pickle.dumps(run))
    assert type(again.jumps) is list and again.jumps == jumps
    assert list(again.jump_times) == list(run.jump_times)


def test_a_run_without_jumps_has_an_empty_sequence() -> None:
    run = hybrid.simulate(BALL, t_end=0.5, backend="compiled", **TOL)
    assert len(run.jumps) == 0 and not run.jumps and run.jumps == []
    assert run.jump_times.shape == (0,) and list(run.jumps) == []
