"""What ``simulate`` remembers between calls gives what a fresh call would give.

The settings of a call are remembered by the objects passed
(:func:`hybrid.simulation.settings.merged_values`), and the bounded variables of a
model by its tuples and the tolerances (:func:`hybrid.simulation.bounds.bound_excursions`).
Numbers equal as numbers but not the same value for a run (``0.0`` and ``-0.0``;
``1``, ``1.0`` and ``True``) must never stand for each other, and a tolerance
changed must move the bounds: each test alternates such values and holds every
answer to the value given (its type and sign) or to a hand computation.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support import SPECS

import hybrid
from hybrid.errors import UsageError
from hybrid.model import StateVar
from hybrid.simulation.bounds import bound_excursions
from hybrid.simulation.settings import Settings, merged, merged_values

THERMO = hybrid.load(SPECS / "thermostat.yaml")
NAMES = ("t_start", "max_jumps", "dense", "rtol")


def _sign(x: float) -> float:
    return math.copysign(1.0, x)


def test_signed_zeros_and_number_types_are_never_one_anothers_settings() -> None:
    zero, negative = 0.0, float("-0.0")
    for _ in range(2):  # the second round answers from the memo
        a = merged_values(None, 10.0, NAMES, (zero, 5, True, 1e-8))
        b = merged_values(None, 10.0, NAMES, (negative, 5, 1, 1e-8))
        c = merged_values(None, 10, NAMES, (zero, 5, 1.0, 1e-8))
        assert (_sign(a.t_start), _sign(b.t_start)) == (1.0, -1.0)
        assert (type(a.dense), type(b.dense), type(c.dense)) == (bool, int, float)
        assert (type(a.t_end), type(c.t_end)) == (float, int)
        assert a == merged(None, 10.0, t_start=zero, max_jumps=5, dense=True, rtol=1e-8)


def test_the_same_objects_give_the_same_settings_and_other_objects_their_own() -> None:
    held = Settings(t_end=3.0, rtol=1e-7)
    first = merged_values(held, None, NAMES, (None, 7, None, None))
    assert merged_values(held, None, NAMES, (None, 7, None, None)) is first
    assert (first.t_end, first.rtol, first.max_jumps) == (3.0, 1e-7, 7)
    # an equal number made afresh: the same settings (equal), whether remembered or not
    again = merged_values(held, None, NAMES, (None, int("7"), None, None))
    assert again == first
    other = merged_values(Settings(t_end=3.0, rtol=1e-5), None, NAMES, (None, 7, None, None))
    assert other.rtol == 1e-5
    unhashable = merged_values(held, np.float64(2.0), NAMES, (None, 7, None, None))
    assert unhashable.t_end == 2.0 and type(unhashable.t_end) is np.float64


def test_a_bad_value_is_refused_every_time_it_is_given() -> None:
    for _ in range(2):
        with pytest.raises(UsageError, match="rtol must be at least"):
            merged_values(None, 10.0, NAMES, (None, None, None, 2.0))
        with pytest.raises(UsageError, match="max_jumps must be a whole number"):
            merged_values(None, 10.0, NAMES, (None, 5.0, None, None))


def test_runs_alternating_signed_zeros_and_flags_keep_their_own(backend: str) -> None:
    """t_start 0.0 / -0.0 and dense True / 1 in turn: each run starts and records what it was given."""
    for _ in range(2):
        for t0, dense in ((0.0, True), (float("-0.0"), 1), (0.0, 1), (float("-0.0"), True)):
            run = hybrid.simulate(THERMO, 2.0, t_start=t0, dense=dense, rtol=1e-9, atol=1e-12,
                                  backend=backend, handle_sigint=False)  # fmt: skip
            assert _sign(run.settings["t_start"]) == _sign(t0) == _sign(run.t[0])
            assert run.settings["dense"] is dense or (
                type(run.settings["dense"]) is type(dense) and run.settings["dense"] == dense
            )
            # T' = -0.1 (T - 10) from 20 in off (no switch before T = 18): T(2) = 10 + 10 e^-0.2
            assert run.states[-1, 0] == pytest.approx(10 + 10 * math.exp(-0.2), rel=1e-7)


def test_bounds_follow_the_tolerances_and_the_columns() -> None:
    """x in [0, 1]: a point at 1 + 1e-6 is beyond with atol 1e-9, within with atol 1e-5."""
    x, y = StateVar("x", 0.5, lower=0.0, upper=1.0), StateVar("y", 0.0, lower=-1.0)
    declared = (x, y)
    t, j = np.array([0.0, 1.0, 2.0]), np.array([0, 0, 1])
    xy = np.array([[0.5, 0.0], [1.0 + 1e-6, 0.0], [0.5, -1.5]])
    for _ in range(2):
        tight = bound_excursions(declared, ("x", "y"), t, j, xy, rtol=0.0, atol=1e-9)
        assert [(e.variable, e.t, e.j) for e in tight] == [("x", 1.0, 0), ("y", 2.0, 1)]
        loose = bound_excursions(declared, ("x", "y"), t, j, xy, rtol=0.0, atol=1e-5)
        assert [(e.variable, e.t, e.value) for e in loose] == [("y", 2.0, -1.5)]
        # the same declared variables, columns in the other order
        swapped = bound_excursions(declared, ("y", "x"), t, j, xy[:, ::-1], rtol=0.0, atol=1e-9)
        assert [(e.variable, e.t) for e in swapped] == [("x", 1.0), ("y", 2.0)]
        # rtol scales with |bound|: 1e-5 * |-1| lets y reach -1 - 1e-5 and no further
        near, only_y = np.array([[0.0], [-1 - 9e-6], [0.0]]), (y,)
        for rtol, out in ((1e-5, False), (0.0, True), (1e-5, False), (1e-6, True)):
            found = bound_excursions(only_y, ("y",), t, j, near, rtol=rtol, atol=1e-12)
            assert bool(found) is out, rtol
