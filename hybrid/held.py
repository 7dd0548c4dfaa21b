"""Values kept per key (of object ids, with the objects held): the caches of one process.

A key made of ``id()`` values is only valid while its objects live; each entry holds
them, so no other object can take one of their ids while the entry stands. At most
``size`` entries are kept (the oldest dropped); threads share a cache, and a value made
twice at once by two of them is kept once, the first.

Examples
--------
>>> cache = HeldCache[str](2)
>>> a = object()
>>> cache.get((id(a),), a, lambda: "made")
'made'
>>> cache.get((id(a),), a, lambda: "made again")
'made'
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

__all__ = ["HeldCache"]

T = TypeVar("T")


class HeldCache(Generic[T]):
    """Values per key, each entry holding the objects whose ids the key holds."""

    def __init__(self, size: int) -> None:
        self._size = size
        self._entries: dict[Hashable, tuple[object, T]] = {}
        self._lock = threading.Lock()

    def get(self, key: Hashable, held: object, make: Callable[[], T]) -> T:
        """The value of ``key``, made by ``make()`` (outside the lock) if it has none yet;
        ``held``: the objects whose ids ``key`` holds."""
        with self._lock:
            hit = self._entries.get(key)
        if hit is None:
            made = (held, make())
            with self._lock:
                if key not in self._entries and len(self._entries) >= self._size:
                    self._entries.pop(next(iter(self._entries)))
                hit = self._entries.setdefault(key, made)
        return hit[1]
