"""A process's own peak resident memory, for the benchmarks that report it.

``getrusage``'s ``ru_maxrss`` is the wrong number for a child process on Linux:
it keeps the largest resident size of the process before ``exec``, so a child
of the 450 MB benchmark process reads 450 MB whatever it does. ``VmHWM`` in
``/proc/self/status`` is the peak of the process's own memory since its
``exec`` (or since :func:`reset_peak`); elsewhere ``ru_maxrss`` is the answer.

>>> peak_mb() > 0
True
"""

from __future__ import annotations

import resource
import sys
from pathlib import Path

__all__ = ["peak_mb", "reset_peak"]

_STATUS = Path("/proc/self/status")


def peak_mb() -> float:
    """The process's peak resident memory in MB (MiB: 2**20 bytes)."""
    try:
        for line in _STATUS.read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak / (1024 * 1024) if sys.platform == "darwin" else peak / 1024


def reset_peak() -> bool:
    """Start the peak afresh from the current resident size (Linux); whether it could."""
    try:
        Path("/proc/self/clear_refs").write_text("5")
    except OSError:
        return False
    return True
