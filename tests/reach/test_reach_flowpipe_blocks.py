"""The flowpipe computed a block of steps at a time is the flowpipe computed step by step.

The recurrences (powers of ``Phi``, centres, the inputs' radius) are carried from
one block to the next; a block boundary anywhere must give the same boxes, up to
the rounding of summing a product in another order (a few units in the last
place, far inside the widening of ``FP_MARGIN``). Step by step is a block of one.
"""

from __future__ import annotations

import numpy as np
import pytest

from hybrid.reach import flowpipe as fp


def _system(n: int, m: int, seed: int) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(seed)
    a = rng.normal(0.0, 1.0, (n, n)) / np.sqrt(n) - 0.5 * np.eye(n)
    b = rng.normal(0.0, 1.0, (n, m))
    c = rng.normal(0.0, 0.1, n)
    x_lo = rng.uniform(-1.0, 0.0, n)
    return a, b, c, -np.ones(m), np.ones(m), x_lo, x_lo + rng.uniform(0.0, 0.5, n)


@pytest.mark.parametrize(("n", "m", "entries"), [(3, 1, 9 * 5), (3, 0, 9 * 7), (40, 2, 1600 * 3)])
def test_blocks_of_steps_give_the_step_by_step_boxes(
    n: int, m: int, entries: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    a, b, c, u_lo, u_hi, x_lo, x_hi = _system(n, m, seed=n + m)
    kept: dict[int, list[int]] = {}

    def pipe(block_entries: int) -> fp.Flowpipe:
        monkeypatch.setattr(fp, "BLOCK_ENTRIES", block_entries)
        calls = kept.setdefault(block_entries, [])

        def keep(k: int, lo: np.ndarray, hi: np.ndarray) -> int:
            calls.append(k)
            return len(lo)

        return fp.flowpipe(a, b, c, u_lo, u_hi, x_lo, x_hi, 0.01, 100, keep, chunk=16)

    one = pipe(1)  # a block of one step: the recurrences only
    blocks = pipe(entries)  # 5, 7 or 3 steps a block: boundaries inside the chunks of 16
    assert kept[1] == kept[entries] == list(range(0, 100, 16))
    for got, want in ((blocks.lo, one.lo), (blocks.hi, one.hi),
                      (blocks.point_lo, one.point_lo), (blocks.point_hi, one.point_hi)):  # fmt: skip
        assert got.shape == want.shape
        np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-15)
    assert np.all(blocks.hi >= blocks.lo)


def test_a_keep_that_stops_cuts_the_pipe_at_the_same_step(monkeypatch: pytest.MonkeyPatch) -> None:
    a, b, c, u_lo, u_hi, x_lo, x_hi = _system(3, 1, seed=7)
    monkeypatch.setattr(fp, "BLOCK_ENTRIES", 9 * 5)

    def keep(k: int, lo: np.ndarray, hi: np.ndarray) -> int:
        return len(lo) if k == 0 else 3  # the second chunk: only its first three segments

    pipe = fp.flowpipe(a, b, c, u_lo, u_hi, x_lo, x_hi, 0.01, 100, keep, chunk=16)
    assert pipe.lo.shape == (19, 3) and pipe.point_lo.shape == (20, 3)
    np.testing.assert_allclose(pipe.tau, np.arange(20) * 0.01)
