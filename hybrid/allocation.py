"""Pausing the cyclic garbage collector around allocation-heavy, cycle-free work.

Building a model or analysing one allocates many small objects and almost no
cycles; with the collector running, its full passes over the growing heap make
the work grow faster than its input (measured: loading 4,000 locations took
5.8 s instead of 2.2 s).

Examples
--------
>>> import gc
>>> with gc_paused():
...     gc.isenabled()
False
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager

__all__ = ["gc_paused"]


@contextmanager
def gc_paused() -> Iterator[None]:
    """Disable the cyclic collector inside the block; restore its previous state after."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()
