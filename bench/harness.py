"""Alternating, repeated timing of a contender against its baseline.

Each repeat times the baseline and the contender back to back (alternating which
goes first), so both see the same machine state; the result is the median ratio
contender / baseline with its min and max over the repeats.
"""

from __future__ import annotations

import platform
import statistics
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from typing import Any

__all__ = ["Comparison", "compare", "machine", "time_call"]


@dataclass
class Comparison:
    name: str
    contender: str
    baseline: str
    ratio_median: float
    ratio_min: float
    ratio_max: float
    contender_median_s: float
    baseline_median_s: float
    repeats: int
    extra: dict[str, Any] = field(default_factory=dict)

    def as_dict(self) -> dict[str, Any]:
        return asdict(self)

    def line(self) -> str:
        return (
            f"{self.name}: ratio {self.ratio_median:.3f} (min {self.ratio_min:.3f}, max "
            f"{self.ratio_max:.3f}); contender {self.contender_median_s * 1e3:.3f} ms, "
            f"baseline {self.baseline_median_s * 1e3:.3f} ms"
        )


def time_call(fn: Callable[[], Any], inner: int = 1) -> float:
    """Seconds per call of ``fn``, averaged over ``inner`` calls."""
    start = time.perf_counter()
    for _ in range(inner):
        fn()
    return (time.perf_counter() - start) / inner


def compare(
    name: str,
    contender: tuple[str, Callable[[], Any]],
    baseline: tuple[str, Callable[[], Any]],
    *,
    repeats: int = 9,
    inner: int = 1,
    warmup: int = 1,
    timer: Callable[[Callable[[], Any], int], float] | None = None,
    per: int = 1,
) -> Comparison:
    """Time ``contender`` and ``baseline`` alternately; ratios are contender / baseline.

    ``timer(fn, inner)`` gives the seconds of one call (wall time by default,
    :func:`time_call`); times are divided by ``per`` (runs a call makes).
    """
    timer = timer or time_call
    for _ in range(warmup):
        contender[1]()
        baseline[1]()
    c_times: list[float] = []
    b_times: list[float] = []
    for r in range(repeats):
        if r % 2 == 0:
            b = timer(baseline[1], inner) / per
            c = timer(contender[1], inner) / per
        else:
            c = timer(contender[1], inner) / per
            b = timer(baseline[1], inner) / per
        c_times.append(c)
        b_times.append(b)
    return paired(name, contender[0], baseline[0], c_times, b_times)


def paired(
    name: str,
    contender: str,
    baseline: str,
    c_times: list[float],
    b_times: list[float],
    extra: dict[str, Any] | None = None,
) -> Comparison:
    """The comparison of times taken in pairs: ratio ``i`` is ``c_times[i] / b_times[i]``."""
    ratios = [c / b for c, b in zip(c_times, b_times, strict=True)]
    return Comparison(
        name=name,
        contender=contender,
        baseline=baseline,
        ratio_median=statistics.median(ratios),
        ratio_min=min(ratios),
        ratio_max=max(ratios),
        contender_median_s=statistics.median(c_times),
        baseline_median_s=statistics.median(b_times),
        repeats=len(ratios),
        extra=extra or {},
    )


def machine() -> dict[str, Any]:
    """What the numbers were measured on."""
    import os

    import numpy
    import scipy

    return {
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "cpus": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
    }
