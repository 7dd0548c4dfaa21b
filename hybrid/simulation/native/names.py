"""Names by index of a compiled model, and the fields of its jumps by key.

The compiled loop records modes, transitions and invariants by number, and a
jump by its transition and the flags of the transitions enabled with it
(packed into one key, ``J_KEY``); :class:`Layout` turns these back into the
names and words of the reference engine's :class:`~hybrid.simulation.result.Jump`.
"""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hybrid.simulation.native import buffers as b
from hybrid.simulation.native.structure import NativeModel

__all__ = ["PACKED_WIDTH", "JumpFields", "Layout"]

JumpFields = dict[str, Any]
"""A :class:`Jump`'s fields in order, ``t``, ``j``, ``before`` and ``after`` to be filled in."""

PACKED_WIDTH = b.PACKED_WIDTH
"""Most transitions a mode may have for a jump's enabled flags to be packed into an int key."""


@dataclass(frozen=True)
class Layout:
    """Names by index: modes, transitions (global order of the tables), invariants."""

    mode_names: NDArray[np.str_]
    transitions: tuple[tuple[int, int, Any], ...]
    """Per global transition: (source mode, place in its mode, NativeTransition)."""
    invariant_first: tuple[int, ...]
    """Per mode, the global index of its first invariant (as ``MODE_INV``)."""
    describe: tuple[tuple[str, str | None, str, str], ...]
    """Per global transition: its name, label, source and target mode names."""
    choices: dict[Hashable, JumpFields]
    """The fields of a jump but its time and states, per :meth:`jump_keys` key seen so far."""
    modes: tuple[Any, ...]
    """The modes (:class:`~hybrid.simulation.native.structure.NativeMode`)."""
    state_names: tuple[str, ...]
    bits: NDArray[np.int64]
    """``1 << k`` for each flag column of a jump (as many as a mode has transitions, at most
    :data:`PACKED_WIDTH`)."""
    packed: bool
    """Whether the compiled loop's ``J_KEY`` holds each jump's key exactly (at most
    :data:`PACKED_WIDTH` flag columns, and every key below ``2**53``)."""

    @classmethod
    def of(cls, native: NativeModel) -> Layout:
        rows: list[tuple[int, int, Any]] = []
        first = [0]
        for m, mode in enumerate(native.modes):
            rows += [(m, k, tr) for k, tr in enumerate(mode.transitions)]
            first.append(first[-1] + len(mode.invariants))
        names = np.array([mode.name for mode in native.modes], dtype=np.str_)
        describe = tuple(
            (tr.view.name, tr.view.label, native.modes[m].name,
             native.modes[native.index[tr.view.target]].name)
            for m, _, tr in rows
        )  # fmt: skip
        width = max(1, *(len(mode.transitions) for mode in native.modes))  # jps' flag columns
        bits = np.left_shift(1, np.arange(min(width, PACKED_WIDTH), dtype=np.int64))
        packed = width <= PACKED_WIDTH and len(rows) << width <= 1 << 53
        return cls(names, tuple(rows), tuple(first), describe, {}, tuple(native.modes),
                   tuple(native.state_names), bits, packed)  # fmt: skip

    def enabled(self, tr: int, flags: bytes) -> tuple[tuple[str, ...], str]:
        """The names of the transitions enabled with ``tr`` chosen, and how it was chosen."""
        m, _, chosen = self.transitions[tr]
        mode = self.modes[m]
        on = [t for k, t in enumerate(mode.transitions) if flags[k]]
        if len(on) <= 1:
            how = "only"
        else:
            top = [t for t in on if t.view.priority == chosen.view.priority]
            how = "priority" if len(top) == 1 else "file order"
        return tuple(t.view.name for t in on), how

    def jump_keys(self, transitions: NDArray[np.float64], flags: NDArray[np.float64]) -> list[Any]:
        """A key per jump for :attr:`choices` from its transition and enabled flags (a row each):
        up to :data:`PACKED_WIDTH` flags, ``tr << width`` plus bit ``k`` per enabled ``k``;
        beyond, ``(tr, flags as bytes)``."""
        on = flags != 0.0
        tr = transitions.astype(np.int64)
        width = on.shape[1]
        if width <= PACKED_WIDTH:
            bits = self.bits if self.bits.size == width else np.left_shift(1, np.arange(width))
            return ((tr << width) | (on.astype(np.int64) @ bits)).tolist()  # type: ignore[no-any-return]
        data = on.astype(np.uint8).tobytes()
        return [(t, data[k * width : (k + 1) * width]) for k, t in enumerate(tr.tolist())]

    def fields(self, key: Any, width: int) -> JumpFields:
        """The fields of a jump of a :meth:`jump_keys` key (or the loop's ``J_KEY``, a float)
        but its time and states (None)."""
        if isinstance(key, (int, float)):
            packed = int(key)
            tr, flags = packed >> width, bytes((packed >> k) & 1 for k in range(width))
        else:
            tr, flags = key
        edge, label, source, target = self.describe[tr]
        enabled, how = self.enabled(tr, flags)
        found = self.choices[key] = {
            "t": None, "j": None, "edge": edge, "label": label, "source": source, "target": target,
            "before": None, "after": None, "enabled": enabled, "chosen_by": how,
        }  # fmt: skip
        return found
