"""The watch of a stay from its terms' functions (events.watch_factory).

The truth is the definition: the least of the terms, a guard's rho as it is, an
invariant's negated, a disarmed term shifted by the band. A system of many
components watches hundreds of terms, and a watch is made at every stay, so
making one must not cost an object per term (each is one more for the cyclic
garbage collector to count, and a run of a large system makes thousands).
"""

from __future__ import annotations

import gc
import math
from collections.abc import Callable

import numpy as np

from hybrid.allocation import gc_paused
from hybrid.simulation.events import watch_factory

TERMS = 300


def _term(k: int) -> Callable[[float, np.ndarray], float]:
    return lambda t, x: float(x[k % x.size]) * (k + 1) - t


def _by_hand(signs: list[float], shifted: list[bool], b0: float, t: float, x: np.ndarray) -> float:
    values = [
        s * _term(k)(t, x) + (b0 if sh else 0.0)
        for k, (s, sh) in enumerate(zip(signs, shifted, strict=True))
    ]
    return min(values, default=math.inf)


def test_the_watch_is_the_least_signed_shifted_term() -> None:
    rng = np.random.default_rng(11)
    signs = [1.0 if k % 3 else -1.0 for k in range(TERMS)]
    shifted = [k % 5 == 0 for k in range(TERMS)]
    make = watch_factory(tuple(zip(signs, shifted, strict=True)))
    watch = make([_term(k) for k in range(TERMS)], 0.25)
    for _ in range(50):
        t, x = float(rng.uniform(0, 5)), rng.uniform(-3, 3, size=4)
        assert watch(t, x) == _by_hand(signs, shifted, 0.25, t, x)


def test_a_term_that_fails_is_left_out() -> None:
    make = watch_factory(((1.0, False), (1.0, False)))
    watch = make([lambda t, x: math.nan, lambda t, x: 2.0 - t], 0.0)
    assert watch(0.5, np.zeros(1)) == 1.5
    assert make([lambda t, x: math.nan, lambda t, x: math.nan], 0.0)(0.0, np.zeros(1)) == math.inf


def test_a_watch_of_no_term_is_infinite() -> None:
    assert watch_factory(())([], 0.0)(0.0, np.zeros(1)) == math.inf


def test_making_a_watch_of_many_terms_makes_no_object_per_term() -> None:
    signs, shifted = [1.0] * TERMS, [k % 2 == 0 for k in range(TERMS)]
    make = watch_factory(tuple(zip(signs, shifted, strict=True)))
    fns = [_term(k) for k in range(TERMS)]
    make(fns, 0.0)  # anything made once per process is made now
    with gc_paused():
        before = len(gc.get_objects())
        watches = [make(fns, 1e-9) for _ in range(10)]
        made = len(gc.get_objects()) - before
    assert made < 10 * 10, f"{made} objects the collector tracks for 10 watches of {TERMS} terms"
    x = np.array([0.5, -1.0])
    assert watches[-1](1.0, x) == _by_hand(signs, shifted, 1e-9, 1.0, x)
