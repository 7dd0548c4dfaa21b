"""A compiled run's jumps: kept in arrays, each :class:`Jump` built when it is asked for.

A :class:`~hybrid.simulation.result.Jump` is a frozen dataclass with two
dicts of states: about a kilobyte each, ten times its numbers, and building
the records of a short run cost about half of its compiled loop. A compiled
:class:`~hybrid.simulation.result.Run` holds :class:`JumpRecords` instead: a
read-only sequence over the arrays the loop filled (copied out), equal to the
list of records the reference engine builds, whose items are built on
access (``run.jumps[k]``, iterating); ``run.jump_times`` reads its array.

Examples
--------
>>> import hybrid
>>> from pathlib import Path
>>> ball = hybrid.load(Path("specs/bouncing_ball.yaml"))
>>> run = hybrid.simulate(ball, t_end=5.0, backend="compiled", handle_sigint=False)
>>> jumps = run.jumps
>>> len(jumps), jumps[0].edge, round(jumps[0].t, 6), jumps[-1] == list(jumps)[-1]
(2, 'bounce', 1.427843, True)
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import Any, overload

import numpy as np
from numpy.typing import NDArray

from hybrid.simulation.native import buffers as b
from hybrid.simulation.native.names import Layout
from hybrid.simulation.result import Jump

__all__ = ["JumpRecords", "jump_records"]


class JumpRecords(Sequence[Jump]):
    """The jumps of one compiled run, as arrays; a :class:`Jump` per item on access.

    It keeps the rows the loop filled (one copy: time, hybrid time, transition,
    key, state before and after, enabled flags) and reads its columns when asked.
    Compares equal to a list of the same jumps (and to another such sequence);
    pickles as that list.
    """

    __slots__ = ("_d", "_layout", "_rows")

    def __init__(self, layout: Layout, rows: NDArray[np.float64], d: int) -> None:
        self._layout, self._rows, self._d = layout, rows, d

    @property
    def times(self) -> NDArray[np.float64]:
        """The jump times (a copy)."""
        return self._rows[:, b.J_T].copy()

    def __len__(self) -> int:
        return int(self._rows.shape[0])

    @overload
    def __getitem__(self, index: int) -> Jump: ...

    @overload
    def __getitem__(self, index: slice) -> list[Jump]: ...

    def __getitem__(self, index: int | slice) -> Jump | list[Jump]:
        if isinstance(index, slice):
            rows = range(len(self))[index]
            return self._build(rows) if rows.step == 1 else self._build(range(len(self)))[index]
        n = len(self)
        k = index + n if index < 0 else index
        if not 0 <= k < n:
            raise IndexError("jump index out of range")
        return self._build(range(k, k + 1))[0]

    def __iter__(self) -> Iterator[Jump]:
        return iter(self._build(range(len(self))))

    def __eq__(self, other: object) -> bool:
        if isinstance(other, JumpRecords) or type(other) is list:
            return list(self) == list(other)
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]

    def __add__(self, other: Sequence[Jump]) -> list[Jump]:
        return [*self, *other]

    def __radd__(self, other: Sequence[Jump]) -> list[Jump]:
        return [*other, *self]

    def __repr__(self) -> str:
        return repr(list(self))

    def __reduce__(self) -> tuple[Any, ...]:
        return (list, (list(self),))

    def _build(self, rows: range) -> list[Jump]:
        """The records of ``rows`` (consecutive): fields copied from each key's, set at once.

        Jump is a frozen dataclass without slots, and its generated ``__init__``
        costs an ``object.__setattr__`` per field; the states' dicts are built in bulk.
        """
        if not rows:
            return []
        lo, hi = rows.start, rows.stop
        layout, names, d = self._layout, self._layout.state_names, self._d
        block = self._rows[lo:hi]
        x, y, z = b.J_X, b.J_X + d, b.J_X + 2 * d
        width = block.shape[1] - z
        if layout.packed:
            keys: Any = block[:, b.J_KEY].tolist()
        else:
            keys = layout.jump_keys(block[:, b.J_TR], block[:, z:])
        befores = _state_dicts(names, block[:, x:y].T.tolist(), hi - lo)
        afters = _state_dicts(names, block[:, y:z].T.tolist(), hi - lo)
        seen, fields_of = layout.choices, layout.fields
        new, set_field = object.__new__, object.__setattr__
        jumps: list[Jump] = []
        append = jumps.append
        for t, j, key, before, after in zip(block[:, b.J_T].tolist(),
                                            block[:, b.J_J].astype(np.int64).tolist(),
                                            keys, befores, afters, strict=True):  # fmt: skip
            fields = (seen.get(key) or fields_of(key, width)).copy()
            fields["t"], fields["j"], fields["before"], fields["after"] = t, j, before, after
            jump = new(Jump)
            set_field(jump, "__dict__", fields)
            append(jump)
        return jumps


def jump_records(layout: Layout, buf: b.RunArrays) -> JumpRecords:
    """The jumps of the run in ``buf`` (one run's arrays), copied out of it (one copy)."""
    return JumpRecords(layout, buf.jps[: int(buf.oi[b.I_JUMPS])].copy(), len(layout.state_names))


def _state_dicts(names: tuple[str, ...], columns: list[list[float]],
                 n: int) -> list[dict[str, float]]:  # fmt: skip
    """``dict(zip(names, row))`` per row of the ``n`` rows of ``columns`` (one list per name);
    for one or two names a dict display (a third of the cost)."""
    if len(names) == 1:
        (a,) = names
        return [{a: v} for v in columns[0]]
    if len(names) == 2:
        a, c = names
        return [{a: u, c: v} for u, v in zip(*columns, strict=True)]
    if not names:
        return [{} for _ in range(n)]
    return [dict(zip(names, row)) for row in zip(*columns, strict=True)]  # noqa: B905 (each row holds len(names) values)
