"""Room on the interpreter's frame stack for numba's compiles (CPython gh-142183).

Since 3.11 CPython keeps a thread's Python frames in chunks of 16 KiB. A call
that finds no room in the current chunk maps a new one, and the chunk is
unmapped as soon as the last frame in it returns, so a call tree that goes back
and forth across a chunk's end maps, faults in and unmaps a chunk every time it
crosses. numba's compiler does that in its deep recursions, at depths that
depend on the caller's: compiling UVMS mission 2's model (the event loop
cached) took about a million page faults and 6 to 8.5 s of system time out of
23 to 27 s. The fix, one chunk kept back (gh-142183, 2026), went into 3.13 and
3.14; 3.11 and 3.12 do not have it.

:func:`with_frame_room` calls a function from a frame that asks for
:data:`RESERVED_SLOTS` slots of stack. No chunk has that much room, so CPython
maps one of 1 MiB for it, and the call's own frames fill the rest of that chunk
(about 66,000 slots, thousands of frames deep) before one needs another. A
chunk is mapped, not written: the slots nobody uses cost no memory. Where
chunks are kept back this changes nothing but one mapping per call.

Examples
--------
>>> with_frame_room(sum, [1, 2, 3])
6
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["RESERVED_SLOTS", "with_frame_room"]

T = TypeVar("T")

RESERVED_SLOTS = 65_000
"""Stack slots the calling frame asks for: CPython rounds a new chunk up to a power of two
times 16 KiB holding the frame and 1,000 slots more, here 1 MiB (131,072 slots)."""


def _call(fn: Callable[..., Any], *args: Any) -> Any:
    return fn(*args)


_call.__code__ = _call.__code__.replace(co_stacksize=RESERVED_SLOTS)


def with_frame_room(fn: Callable[..., T], *args: Any) -> T:
    """``fn(*args)``, called from a frame whose chunk leaves its callees about 66,000 slots."""
    result: T = _call(fn, *args)
    return result
