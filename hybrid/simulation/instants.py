"""Jumps of groups simulated apart, put in the order a run of their product takes them.

Components simulated apart (:mod:`~hybrid.simulation.apart`) jump on their
own; the system's run is their jumps interleaved in hybrid time. At one
instant the product of the groups decides as for any model (docs/semantics.md,
"As soon as possible, priority, then file order"): every transition enabled
there, of any group, is a candidate, the highest ``priority`` fires, ties go
to the order of the components in the system, then to the order of the edges
in each file; after the jump the others are still due (see
:func:`hybrid.simulation.boundary.enabled_at_entry`). Since groups do not
influence each other, what is enabled in a group at that instant is what its
own run found at its next jump there, so :func:`interleave` only has to merge
the groups' sequences of jumps by that rule, and to list in each jump every
group's enabled transitions, as the product's run lists them.

**One instant.** Event times are located to about machine precision, and two
groups that reach their levels at one instant in exact arithmetic find times
a few ulps apart (``1 - 2**-53`` by one history, ``1`` by another). The
product stops at the first of them and decides every guard there (within the
band of its boundary), so jumps of different groups within :func:`tolerance`
of the first are one instant: they are ordered by the rule above and take the
first one's time.

:func:`first_over_cap` is the product's cap on jumps at one instant, counted
over all groups.

Examples
--------
>>> from hybrid.simulation.result import Jump
>>> def jump(t, edge):
...     return Jump(t, 0, edge, None, "", "", {}, {}, (edge,))
>>> keys = {"a.go": (0, (0, 0)), "b.go": (-1, (1, 0))}   # b.go has priority 1
>>> merged = interleave([[jump(1.0, "a.go")], [jump(1.0, "b.go")]], lambda g, j, name: keys[name])
>>> [(g, j.edge, j.enabled, j.chosen_by) for g, j, _ in merged]
[(1, 'b.go', ('a.go', 'b.go'), 'priority'), (0, 'a.go', ('a.go',), 'only')]
>>> first_over_cap([0.0, 0.0, 0.0, 1.0], 2)
2
"""

from __future__ import annotations

import bisect
import math
from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np

from hybrid.modes import TransitionView
from hybrid.simulation.result import Jump, Run

__all__ = [
    "Key",
    "first_over_cap",
    "inside",
    "interleave",
    "nearest_rows",
    "tolerance",
    "transition_key",
]

Key = tuple[int, tuple[int, ...]]
"""How a transition ranks at an instant: ``(-priority, its order in the system)``, smallest first."""

KeyOf = Callable[[int, Jump, str], Key]
"""The key of transition ``name`` enabled in group ``g`` at its jump ``jump``."""


def transition_key(view: TransitionView, members: Sequence[int]) -> Key:
    """The key of ``view``, a transition of a group whose components are ``members`` of the system.

    A group's transitions are ordered by ``(component, edge)`` pairs with the
    group's own component numbers; the system's are its own numbers.
    """
    order = tuple(members[v] if k % 2 == 0 else v for k, v in enumerate(view.order))
    return (-view.priority, order)


def tolerance(t: float) -> float:
    """Event times of different groups within this of ``t`` are the instant ``t`` (the band's
    width, ``1e-10 (1 + |t|)``, in time)."""
    return 1e-10 * (1.0 + abs(t))


def interleave(
    runs: Sequence[Sequence[Jump]], key_of: KeyOf
) -> list[tuple[int, Jump, float]]:
    """The jumps of every group (``runs[g]``, each in its own order) as the product takes them.

    Each item is ``(group, jump, its own time)``: jumps of several groups
    within :func:`tolerance` of the first of them are one instant and take its
    time; the jump taken next there is the best-ranked (:data:`Key`) of the
    groups' next jumps at that instant. Its ``enabled``
    becomes every transition enabled at that point of the product (each group's
    next jump at that instant lists its own), in the product's order (of
    components, then of edges: not by priority), and
    ``chosen_by`` is decided among them.
    """
    heads = [0] * len(runs)
    merged: list[tuple[int, Jump, float]] = []
    live = [g for g in range(len(runs)) if runs[g]]
    instant = math.nan
    while live:
        t = min(runs[g][heads[g]].t for g in live)
        if not t - instant <= tolerance(instant):  # a new instant (the first: NaN)
            instant = t
        here = [g for g in live if runs[g][heads[g]].t - instant <= tolerance(instant)]
        ranked = {
            (g, name): key_of(g, runs[g][heads[g]], name)
            for g in here
            for name in runs[g][heads[g]].enabled or (runs[g][heads[g]].edge,)
        }
        g = min(here, key=lambda h: ranked[(h, runs[h][heads[h]].edge)])
        jump = runs[g][heads[g]]
        chosen = ranked[(g, jump.edge)]
        # listed in the product's order of its transitions: components, then edges
        enabled = tuple(name for (_, name), _ in sorted(ranked.items(), key=lambda i: i[1][1]))
        top = sum(1 for k in ranked.values() if k[0] == chosen[0])
        how = "only" if len(ranked) == 1 else "priority" if top == 1 else "file order"
        merged.append((g, replace(jump, t=instant, enabled=enabled, chosen_by=how), jump.t))
        heads[g] += 1
        if heads[g] == len(runs[g]):
            live.remove(g)
    return merged


def inside(windows: Sequence[tuple[float, float]], t: float) -> bool:
    """Whether ``t`` is in one of ``windows`` (``(lo, hi]``, in increasing order): between an
    instant and a group's own time of its jump there, where its own points are left out."""
    k = bisect.bisect_left(windows, (t, -math.inf)) - 1
    return k >= 0 and windows[k][0] < t <= windows[k][1]


def nearest_rows(
    run: Run,
    segments: Sequence[tuple[int, float, float, object]],
    times: np.ndarray,
    lj: np.ndarray,
    own: np.ndarray,
) -> bool:
    """Rows of the system at a group's hybrid time ``lj`` and a time ``times`` that no stay of
    the group covers, within :func:`tolerance` of one of its own points there (the instant
    of a jump the group took a rounding error later): ``own`` is set to that point. True
    if one was."""
    found = False
    todo = np.flatnonzero(own < 0)
    if todo.size == 0 or run.t.size == 0:
        return False
    # first the rows near any own point at all (few: those at the instants of jumps)
    ordered = np.sort(run.t)
    at = np.searchsorted(ordered, times[todo])
    gap = np.minimum(
        np.abs(ordered[np.clip(at, 0, ordered.size - 1)] - times[todo]),
        np.abs(ordered[np.clip(at - 1, 0, ordered.size - 1)] - times[todo]),
    )
    todo = todo[gap <= 1e-10 * (1.0 + np.abs(times[todo]))]
    order = np.lexsort((run.t, run.j))  # own points by (j, t)
    keys_j, keys_t = run.j[order], run.t[order]
    for r in todo.tolist():
        t, j = float(times[r]), int(lj[r])
        lo, hi = np.searchsorted(keys_j, j, "left"), np.searchsorted(keys_j, j, "right")
        if lo == hi:
            continue
        k = lo + int(np.searchsorted(keys_t[lo:hi], t))
        near = [i for i in (k - 1, k) if lo <= i < hi]
        best = min(near, key=lambda i: abs(float(keys_t[i]) - t))
        if abs(float(keys_t[best]) - t) > tolerance(t):
            continue
        if any(s[0] == j and s[1] <= t <= s[2] for s in segments):
            continue  # inside a stay: its interpolant
        own[r], found = int(order[best]), True
    return found


def first_over_cap(times: Sequence[float], cap: int) -> int | None:
    """The index of the first jump that would be the ``cap + 1``-th at one instant, if any."""
    same, last = 0, None
    for k, t in enumerate(times):
        same = same + 1 if t == last else 1
        last = t
        if same > cap:
            return k
    return None
