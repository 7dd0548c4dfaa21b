"""A compiled run's columns made on first read (``RecordedRun``): the same run, made later.

``simulate(..., backend="compiled")`` copies the loop's points out as one block
and makes ``t``, ``j``, ``location``, ``states`` and ``signals`` from it when one
is first read. Each test holds the columns to a closed form (the bouncing ball's
impacts, its free fall) or to the reference engine's run, and checks that the
columns were not made before they were read.
"""

from __future__ import annotations

import copy
import math
import pickle
import warnings

import numpy as np
import pytest
from support import SPECS

import hybrid
from hybrid.simulation.result import Run

pytest.importorskip("numba")

TOL = {"rtol": 1e-10, "atol": 1e-12, "handle_sigint": False}
BALL = hybrid.load(SPECS / "bouncing_ball.yaml")
G = 9.81
COLUMNS = ("t", "j", "location", "states", "signals")


def made(run: Run) -> list[str]:
    return [name for name in COLUMNS if name in vars(run)]


def test_columns_are_made_on_first_read_and_match_the_reference_engine() -> None:
    run = hybrid.simulate(BALL, t_end=3.0, backend="compiled", **TOL)
    assert made(run) == []
    first = math.sqrt(2 * 10.0 / G)  # dropped from h = 10 at rest
    assert run.jumps[0].t == pytest.approx(first, abs=1e-9)  # the jumps do not need the columns
    assert made(run) == []
    locations = run.location  # one read makes all five
    assert made(run) == list(COLUMNS)
    reference = hybrid.simulate(BALL, t_end=3.0, backend="scipy", **TOL)
    assert locations.tolist() == reference.location.tolist()
    assert run.j.tolist() == reference.j.tolist()
    np.testing.assert_allclose(run.t, reference.t, rtol=0, atol=1e-9)
    np.testing.assert_allclose(run.states, reference.states, rtol=1e-8, atol=1e-9)
    falling = run.j == 0
    np.testing.assert_allclose(
        run["h"][falling], 10.0 - G * run.t[falling] ** 2 / 2, rtol=0, atol=1e-9
    )  # free fall before the first impact
    for column in (run.t, run.j, run.states, run.signals):
        assert column.flags["C_CONTIGUOUS"] and column.flags["OWNDATA"]


def test_a_run_read_after_later_runs_is_still_its_own() -> None:
    """The block is a copy: the thread's scratch arrays, refilled by later runs, are not it."""
    early = hybrid.simulate(BALL, t_end=2.0, backend="compiled", **TOL)
    for t_end in (5.0, 9.0):
        hybrid.simulate(BALL, t_end=t_end, backend="compiled", **TOL)
    assert early.t[-1] == 2.0 and early.t[0] == 0.0
    assert early.j.max() == 1 and len(early) == early.states.shape[0]
    assert early.location[-1] == early.jumps[-1].target


def test_len_does_not_make_the_columns_and_agrees_with_them() -> None:
    run = hybrid.simulate(BALL, t_end=3.0, backend="compiled", **TOL)
    points = len(run)
    assert made(run) == []
    assert points == run.t.shape[0] == run.states.shape[0] == run.location.shape[0]


def test_bounds_are_checked_without_making_the_columns() -> None:
    """Dropped from 30 m the ball passes v = -20 (its bound) at t = 20 / g, before impact."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        run = hybrid.simulate(BALL, t_end=2.4, initial={"h": 30.0}, backend="compiled", **TOL)
    assert made(run) == []
    (excursion,) = run.out_of_bounds
    assert excursion.variable == "v"
    assert excursion.t >= 20.0 / G and excursion.value < -20.0
    assert excursion.value == pytest.approx(-G * excursion.t, rel=1e-9)
    assert [str(w.message) for w in caught if issubclass(w.category, hybrid.BoundsWarning)]
    with pytest.warns(hybrid.BoundsWarning):
        reference = hybrid.simulate(BALL, t_end=2.4, initial={"h": 30.0}, backend="scipy", **TOL)
    assert reference.out_of_bounds[0].variable == "v"


@pytest.mark.parametrize(
    ("spec", "options"),
    [
        ("bouncing_ball.yaml", {"t_end": 3.0, "initial": {"h": 30.0}}),
        ("bouncing_ball.yaml", {"t_end": 30.0, "dt": 0.01}),  # points outgrow the first room
        ("thermostat.yaml", {"t_end": 1e4, "max_jumps": 300}),
    ],
)
def test_the_extremes_kept_by_the_loop_are_those_of_the_points(spec: str, options: dict) -> None:
    model = hybrid.load(SPECS / spec)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", hybrid.BoundsWarning)
        run = hybrid.simulate(model, backend="compiled", **options, **TOL)
        reference = hybrid.simulate(model, backend="scipy", **options, **TOL)
    low, high = run.stored_extremes()
    assert len(run) > (256 if "dt" in options else 0)  # 256: the first room for points
    np.testing.assert_array_equal(low, np.fmin.reduce(run.states, axis=0))
    np.testing.assert_array_equal(high, np.fmax.reduce(run.states, axis=0))
    assert reference.stored_extremes() is None  # worked out from the columns instead
    assert [e.variable for e in run.out_of_bounds] == [e.variable for e in reference.out_of_bounds]


@pytest.mark.parametrize("how", ["pickle", "copy", "deepcopy"])
def test_copies_and_pickles_are_plain_runs_with_the_same_columns(how: str) -> None:
    run = hybrid.simulate(BALL, t_end=3.0, backend="compiled", **TOL)
    other = {
        "pickle": lambda r: pickle.loads(pickle.dumps(r)),
        "copy": copy.copy,
        "deepcopy": copy.deepcopy,
    }[how](run)
    assert type(other) is Run
    assert other.location.tolist() == run.location.tolist()
    np.testing.assert_array_equal(other.t, run.t)
    np.testing.assert_array_equal(other.states, run.states)
    assert list(other.jumps) == list(run.jumps)
    assert not any(name.startswith("_") for name in vars(other))


def test_an_unknown_attribute_is_an_attribute_error() -> None:
    run = hybrid.simulate(BALL, t_end=1.0, backend="compiled", **TOL)
    with pytest.raises(AttributeError, match="'Run' object has no attribute 'time'"):
        _ = run.time  # type: ignore[attr-defined]
    assert not hasattr(run, "_rows_missing")


def test_a_column_set_before_the_others_are_made_is_kept() -> None:
    run = hybrid.simulate(BALL, t_end=3.0, backend="compiled", **TOL)
    mine = np.zeros(3)
    run.signals = mine
    assert run.t[0] == 0.0  # makes the other four
    assert run.signals is mine
    assert run.states.shape == (len(run), 2)
