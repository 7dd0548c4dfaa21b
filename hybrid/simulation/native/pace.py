"""How long a compile takes on this machine, against the benchmark machine's estimates.

A first compiled run says what it compiles and about how long that takes
(:func:`~hybrid.simulation.native.choice.compile_notice`): the kernel's wait
(:data:`~hybrid.simulation.native.choice.KERNEL_COMPILE_S`) and a model's estimate
from its generated source are figures of the benchmark machine, and a machine three
times slower waits three times as long. Each compile a process finishes keeps the
seconds it waited over the seconds estimated (:func:`record`), in ``pace.json`` in
the cache root: one ratio for a compile of the kernel (with its model), one for a
large model's alone (a small one's wait is mostly loading, and keeps none). Later
notices scale their estimates by the ratio of their kind, or else of the other
(:func:`pace`). Nothing here is needed for a run: a cache that cannot be written
keeps no pace, and a pace that cannot be read is none.

Examples
--------
>>> import os, tempfile
>>> from hybrid.simulation.native import cache
>>> os.environ[cache.CACHE_ENV] = tempfile.mkdtemp()
>>> pace("model") is None
True
>>> record(27.0, 9.0, "kernel")
>>> pace("kernel"), pace("model")
(3.0, 3.0)
>>> record(1.5, 1.0, "model")  # a small model's compile: no pace
>>> record(30.0, 15.0, "model")
>>> pace("kernel"), pace("model")
(3.0, 2.0)
>>> del os.environ[cache.CACHE_ENV]
"""

from __future__ import annotations

import contextlib
import json
import math

from hybrid.files import atomic_write
from hybrid.simulation.native.cache import cache_root, exclusive

__all__ = ["KINDS", "MIN_ESTIMATE_S", "PACE_FILE", "PACE_RANGE", "pace", "record"]

KINDS = ("kernel", "model")
"""The kinds of compile a pace is kept for."""

PACE_FILE = "pace.json"
"""The file in the cache root that keeps the last pace of each kind."""
PACE_LOCK = ".pace.lock"
"""Beside it: held while a process reads, changes and writes it."""
MIN_ESTIMATE_S = 5.0
"""A compile estimated shorter keeps no pace: its wait is mostly loading, whatever the
machine (a small model compiled in a process that has compiled before waited 0.34 s
against 1 s estimated, on a machine where the kernel waited 3.3 times its estimate)."""
PACE_RANGE = (0.25, 16.0)
"""The least and most pace kept: beyond, a measurement says more about a stalled or
suspended process than about the machine."""


def record(waited_s: float, estimated_s: float, kind: str) -> None:
    """Keep ``waited_s / estimated_s`` (within :data:`PACE_RANGE`) as this machine's pace
    for a compile of ``kind``: ``"kernel"`` (the kernel, and a model with it) or ``"model"``
    (at least :data:`MIN_ESTIMATE_S` estimated)."""
    if not (estimated_s >= MIN_ESTIMATE_S and math.isfinite(waited_s) and waited_s > 0.0):
        return
    least, most = PACE_RANGE
    entry = {"pace": min(most, max(least, waited_s / estimated_s)),
             "waited_s": waited_s, "estimated_s": estimated_s}  # fmt: skip
    # one process at a time reads, changes and writes the file: two compiles ending together
    # (two test workers, two commands) each keep their kind's pace. A cache that cannot be
    # written (CannotWrite is an OSError) keeps no pace: the run goes on without it, and a
    # later notice says the benchmark machine's figures
    with contextlib.suppress(OSError), exclusive(cache_root() / PACE_LOCK):
        kept = _kept()
        kept[kind] = entry
        with atomic_write(cache_root() / PACE_FILE) as stream:
            stream.write(json.dumps(kept).encode("utf-8"))


def pace(kind: str) -> float | None:
    """This machine's pace for a compile of ``kind`` (see :func:`record`), else for the other
    kind, else ``None``."""
    kept = _kept()
    for name in (kind, *(k for k in KINDS if k != kind)):
        entry = kept.get(name)
        found = entry.get("pace") if isinstance(entry, dict) else None
        if isinstance(found, bool) or not isinstance(found, int | float):
            continue
        if PACE_RANGE[0] <= found <= PACE_RANGE[1]:
            return float(found)
    return None


def _kept() -> dict[str, object]:
    """What ``pace.json`` holds, or nothing when it is missing or damaged."""
    try:
        found = json.loads((cache_root() / PACE_FILE).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return {k: v for k, v in found.items() if k in KINDS} if isinstance(found, dict) else {}
