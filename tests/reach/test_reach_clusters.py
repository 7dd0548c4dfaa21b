"""A guard met by a flowpipe's segments: the boxes queued, one per stretch of contact.

The engine meets all the segments of a stay with a guard at once, a chunk at a
time. Each stretch must be the hull of what meeting each of its segments alone
gives (:func:`hybrid.reach.boxes.meets`, widened by the simulator's band over that
segment), stretches split where a segment misses the guard, also across the
boundary of two chunks.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from hybrid.reach import engine
from hybrid.reach.affine import Rows
from hybrid.reach.boxes import band, meets

T_INDEX = 2
"""Columns: x, y, then time."""
GUARD = (
    Rows(np.array([[1.0, 1.0, 0.0]]), np.array([1.0])),  # x + y <= 1
    Rows(np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]), np.array([-2.0, 3.0])),  # x >= 2, t <= 3
)


def _one_at_a_time(
    segments: list[tuple[np.ndarray, np.ndarray]], entry: float
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Each segment met alone; runs of consecutive indices grouped (index minus rank is
    constant along a run), each run's boxes joined by their elementwise hull."""
    met = [
        (k, meets(lo, hi, GUARD, widen=max(float(band(lo, hi, T_INDEX)), entry)))
        for k, (lo, hi) in enumerate(segments)
    ]
    hits = [(k, box) for k, box in met if box is not None]
    stretches = []
    for _, run in itertools.groupby(enumerate(hits), key=lambda item: item[1][0] - item[0]):
        boxes = [box for _, (_, box) in run]
        stretches.append(
            (np.min([b[0] for b in boxes], axis=0), np.max([b[1] for b in boxes], axis=0))
        )
    return stretches


@pytest.mark.parametrize("seed", range(5))
def test_each_stretch_is_the_hull_of_its_segments_met_one_at_a_time(
    seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(engine, "CLUSTER_CHUNK", 7)  # many chunk boundaries in 60 segments
    monkeypatch.setattr(engine, "MAX_CLUSTERS", 1_000)  # every stretch kept as found
    rng = np.random.default_rng(seed)
    centre = np.cumsum(rng.normal(0.0, 0.6, (60, 2)), axis=0) + np.array([1.0, 0.0])
    radius = rng.uniform(0.0, 0.3, (60, 2))
    t = np.arange(61) * 0.1
    segments = [
        (np.array([*(centre[k] - radius[k]), t[k]]), np.array([*(centre[k] + radius[k]), t[k + 1]]))
        for k in range(60)
    ]
    entry = 1e-9 if seed % 2 else 0.0
    found = engine._clusters(segments, GUARD, T_INDEX, entry)
    expected = _one_at_a_time(segments, entry)
    assert 1 < len(expected) < 60  # contact comes and goes
    assert len(found) == len(expected)
    for (lo, hi), (lo_e, hi_e) in zip(found, expected, strict=True):
        np.testing.assert_array_equal(lo, lo_e)
        np.testing.assert_array_equal(hi, hi_e)


def test_segments_that_miss_the_guard_queue_nothing() -> None:
    far = [(np.array([5.0, 5.0, 4.0]), np.array([6.0, 6.0, 4.1]))] * 3  # x + y > 1, t > 3
    assert engine._clusters(far, GUARD, T_INDEX, 0.0) == []
