"""Room on the interpreter's frame stack for deep or call-heavy work (CPython gh-142183).

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
:data:`RESERVED_SLOTS` slots of stack; :func:`in_frame_room` makes a function
do so whenever it is called. No chunk has that much room, so CPython maps one
of 1 MiB for the frame, and the call's own frames fill the rest of that chunk
(about 66,000 slots, thousands of frames deep) before one needs another. A
chunk is mapped, not written: the slots nobody uses cost no memory. It costs
about 10 us a call (mapping and unmapping the chunk), so it goes around whole
pieces of work: a compile, a run on the scipy backend, a load, a check, a reach,
an import, the replay of a compiled run's requirements; one made in the room
already (``check`` running ``reach``) is a plain call there. Where chunks are
kept back this changes nothing but that.

The same crossings slow down any Python work that calls one function many
times from one depth, at some depths of the caller's. Called from 80 depths
(0 to 237) of a script on Python 3.11, a run of UVMS mission 2 on the scipy
backend cost 87 to 415 ms (15 depths over 100 page faults a run, up to 41,000);
`check` of it 65 to 131 ms, its `load` 11 to 44 ms, a `reach` of the thermostat
67 to 215 ms, an import of ARCH's building model 144 to 381 ms.

Examples
--------
>>> with_frame_room(sum, [1, 2, 3])
6
>>> @in_frame_room
... def total(*values, start=0):
...     return sum(values, start)
>>> total(1, 2, start=3)
6
"""

from __future__ import annotations

import contextlib
import functools
import sys
import threading
from collections.abc import Callable
from typing import Any, ParamSpec, TypeVar

__all__ = ["RESERVED_SLOTS", "in_frame_room", "with_frame_room"]

P = ParamSpec("P")
T = TypeVar("T")

RESERVED_SLOTS = 65_000
"""Stack slots the calling frame asks for: CPython rounds a new chunk up to a power of two
times 16 KiB holding the frame and 1,000 slots more, here 1 MiB (131,072 slots)."""


def _call(fn: Callable[..., Any], args: tuple[Any, ...], kwargs: dict[str, Any]) -> Any:
    # this frame's object made now (its slots are allocated, not written): an exception
    # leaving the frame later needs none made, which out of memory turned a MemoryError
    # into "SystemError: error return without exception set"
    _frame_object(0)
    return fn(*args, **kwargs)


_frame_object = sys._getframe


# an interpreter whose code objects cannot be given more stack makes plain calls (no room)
with contextlib.suppress(AttributeError, TypeError, ValueError):
    _call.__code__ = _call.__code__.replace(co_stacksize=RESERVED_SLOTS)


_INSIDE = threading.local()
"""Whether this thread's call is in the room already (``inside``)."""


def with_frame_room(fn: Callable[P, T], *args: P.args, **kwargs: P.kwargs) -> T:
    """``fn(*args, **kwargs)``, called from a frame whose chunk leaves its callees about
    66,000 slots.

    Called in the room already (``check`` running ``reach``, a spec loaded while another
    is), it calls ``fn`` plainly: a second room's frame would fit in what is left of the
    first chunk and leave its callees a few hundred slots there.
    """
    if getattr(_INSIDE, "inside", False):
        return fn(*args, **kwargs)
    _INSIDE.inside = True
    try:
        result: T = _call(fn, args, kwargs)
    finally:
        _INSIDE.inside = False
    return result


def in_frame_room(fn: Callable[P, T]) -> Callable[P, T]:
    """``fn``, calling itself with :func:`with_frame_room` (a decorator)."""

    @functools.wraps(fn)
    def roomy(*args: P.args, **kwargs: P.kwargs) -> T:
        return with_frame_room(fn, *args, **kwargs)

    return roomy
