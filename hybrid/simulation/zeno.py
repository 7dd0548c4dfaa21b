"""Zeno detection from the gaps between jumps.

Two signs, both cheap: many jumps at one instant (a zero-time cycle), and gaps
that shrink geometrically. For gaps ``g_k`` with ratio ``r = g_k / g_(k-1)``
the jumps accumulate at ``t_k + g_k r / (1 - r)``. The detector waits until the
ratio has been steady for a while *and* the gap has shrunk by
``shrink`` from the start of the geometric run, so that a model with many
ordinary jumps, or one that only starts to chatter, is not stopped early.

Examples
--------
>>> z = ZenoDetector()
>>> times = [1 - 0.5**k for k in range(1, 40)]   # accumulate at t = 1
>>> estimate = next(e for e in map(z.update, times) if e is not None)
>>> round(estimate, 12)
1.0
"""

from __future__ import annotations

from collections import deque

__all__ = ["ZenoDetector"]


class ZenoDetector:
    """Feed jump times with :meth:`update`; it returns the accumulation time once Zeno."""

    def __init__(self, window: int = 6, spread: float = 0.02, shrink: float = 1e-3) -> None:
        self.window = window
        self.spread = spread
        self.shrink = shrink
        self.last_t: float | None = None
        self.gaps: deque[float] = deque(maxlen=window + 1)
        self.ratios: deque[float] = deque(maxlen=window)
        self.run_start_gap: float | None = None

    def update(self, t: float) -> float | None:
        """Record a jump at ``t``; the estimated accumulation time if Zeno, else ``None``."""
        if self.last_t is None:
            self.last_t = t
            return None
        gap = t - self.last_t
        self.last_t = t
        if gap <= 0.0:
            return None  # zero-time jumps are counted by the engine's per-instant cap
        gaps = self.gaps
        if gaps:
            ratio = gap / gaps[-1]
            self.ratios.append(ratio)
        gaps.append(gap)
        ratios = self.ratios
        if len(ratios) < self.window:
            return None
        latest = ratios[-1]
        limit = self.spread * latest
        steady = all(0.0 < r < 1.0 and abs(r - latest) <= limit for r in ratios)
        if not steady:
            self.run_start_gap = None
            return None
        if self.run_start_gap is None:
            self.run_start_gap = gaps[0]
        if gap > self.shrink * self.run_start_gap:
            return None
        return t + gap * latest / (1.0 - latest)
