"""The search of one step (hybrid/simulation/crossing.py), rule by rule, on hand-made watches.

These are the cases a compiled backend must reproduce: where the samples fall,
which zero is taken, when a dip is examined, and what a touch is. Each watch is
a function of ``t`` on a straight-line step ``x(t) = t``, so every answer is a
hand computation.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

from hybrid.simulation.crossing import HORIZON_SAMPLES, SAMPLES_PER_STEP, first_event, parts
from hybrid.simulation.dense import StepCurve


class Line(StepCurve):
    """x(t) = t over one step."""

    def at(self, t: float) -> np.ndarray:
        return np.array([t])

    def many(self, ts: np.ndarray) -> np.ndarray:
        return ts.reshape(-1, 1)


class FixedWatch:
    """A watch with every term armed: its value is ``phi(t)``; it records where it was asked."""

    pending = False
    generation = 0

    def __init__(self, phi: Callable[[float], float]) -> None:
        self.asked: list[float] = []

        def value(t: float, x: Any) -> float:
            self.asked.append(float(t))
            return phi(float(x[0]))

        self.value = value


def search(phi: Callable[[float], float], t0: float, t1: float, spacing: float = 1e9) -> Any:
    watch = FixedWatch(phi)
    curve = Line(t0, t1, np.array([t0]), np.array([t1]))
    found, _ = first_event(curve, watch, phi(t0), spacing)
    return found, watch.asked


def test_parts_of_a_step() -> None:
    assert SAMPLES_PER_STEP == 4 and HORIZON_SAMPLES == 1000
    assert parts(1.0, 10.0) == 4  # a short step: 4 parts
    assert parts(8.889, 0.01) == 889  # a long one: parts no longer than the spacing
    assert parts(0.04, 0.01) == 4


def test_the_samples_are_equally_spaced_and_in_order() -> None:
    _, asked = search(lambda t: 1.0, 0.0, 10.0)
    assert asked == [2.5, 5.0, 7.5, 10.0]


def test_the_first_sample_at_or_below_zero_brackets_the_zero() -> None:
    # phi = 4 - t crosses at 4, between the samples 2.5 and 5; later samples are not asked
    found, asked = search(lambda t: 4.0 - t, 0.0, 10.0)
    assert found.kind == "crossing" and found.t == pytest.approx(4.0, abs=1e-14)
    assert asked[:2] == [2.5, 5.0] and 7.5 not in asked


def test_of_zeros_in_different_parts_the_first_is_taken() -> None:
    # sin(t) + 0.5 <= 0 on [7 pi/6, 11 pi/6] and again 2 pi later: the first
    found, _ = search(lambda t: math.sin(t) + 0.5, 0.0, 20.0, spacing=1.0)
    assert found.t == pytest.approx(7 * math.pi / 6, abs=1e-12)


def test_a_dip_before_a_crossing_is_the_earlier_event() -> None:
    # samples 2.5, 5, 7.5, 10: the watch dips below 0 around 2.2 (unseen by the samples)
    # and crosses at 9.5 (seen); the dip's parabola 2.4, 0.025, 3.9 falls below half of
    # 0.025, so it is examined: the first zero is 2.2 - 0.2 = 2
    def phi(t: float) -> float:
        return min(0.5 * (t - 2.2) ** 2 - 0.02, 9.5 - t)

    found, _ = search(phi, 0.0, 10.0)
    assert found.kind == "crossing" and found.t == pytest.approx(2.0, abs=1e-9)


def test_a_shallow_valley_is_not_examined() -> None:
    # 1 + (t - 5)^2 / 10 has a minimum of 1 at 5: the parabola through the samples
    # does not fall half way to 0, nothing is looked for
    found, asked = search(lambda t: 1 + (t - 5) ** 2 / 10, 0.0, 10.0)
    assert found is None and asked == [2.5, 5.0, 7.5, 10.0]


def test_a_touch_within_the_band_is_an_event_at_the_minimum() -> None:
    # (t - 4)^2 touches 0 at 4 without crossing: an event there
    found, _ = search(lambda t: (t - 4.0) ** 2, 0.0, 10.0)
    assert found.kind == "touch" and found.t == pytest.approx(4.0, abs=1e-5)


def test_a_near_miss_above_the_band_is_not_an_event() -> None:
    found, _ = search(lambda t: (t - 4.0) ** 2 + 1e-6, 0.0, 10.0)
    assert found is None


def test_a_kink_between_samples_is_the_documented_limit() -> None:
    # a V-shaped window 0.01 wide between the samples 5 and 7.5: no sample inside, the
    # parabola through 2.5, 5 and 7.5 does not dip: missed (max_step is the lever)
    def phi(t: float) -> float:
        return max(6.0 - t, t - 6.01)

    found, _ = search(phi, 0.0, 10.0)
    assert found is None
    found, _ = search(phi, 0.0, 10.0, spacing=0.004)  # parts of at most 4 ms: seen
    assert found is not None and found.t == pytest.approx(6.0, abs=1e-12)
