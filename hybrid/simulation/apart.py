"""Independent components simulated apart, their runs merged into the system's run.

Components that share no label and read no signal of each other (directly
or through other components) never influence each other: the system's run
is the runs of its *groups* side by side. Simulating their product instead
costs time and memory quadratic in the number of components (every jump of
one component is a new product mode, and every solver step carries every
component), so :func:`simulate_apart` runs each group on its own (with its
interpolants kept) and :func:`merge` interleaves the runs in hybrid time:

- the jumps of all groups, by time, numbered ``j = 0, 1, ...`` for the whole
  system; at one instant in the order the product takes them (priority, then
  the order of the components and of the edges: :mod:`~hybrid.simulation.instants`),
  each listing every group's transitions enabled there;
- the points of every group at its own times, the other groups' states there
  from their interpolants (the solver's dense output, not a straight line),
  their signals computed from those states; two points per jump;
- the run ends where the first group ends other than at ``t_end`` (the others
  are cut there; of groups ending at one instant, one whose jump was due,
  ``zeno`` or ``max_jumps``, before one with nothing enabled, as the product
  jumps while it can), or with cause ``max_jumps`` at the jump after the
  ``max_jumps``-th of the system, or ``zeno`` at the jump that exceeds the cap
  on jumps at one instant, counted over all groups.

What a run of the product would give differs only in numbers below the
solver's tolerance (each group's own steps instead of steps shared by all;
jumps of groups a rounding error apart are one instant, at the first one's
time, as the product decides them).

Examples
--------
>>> import hybrid
>>> system = hybrid.compose(
...     hybrid.load("specs/thermostat.yaml"), hybrid.load("specs/bouncing_ball.yaml")
... )
>>> independent_groups(system)
[(0,), (1,)]
>>> run = hybrid.simulate(system, t_end=3.0)
>>> [(round(jump.t, 3), jump.edge, jump.j) for jump in run.jumps]
[(1.428, 'bouncing_ball.bounce', 0), (2.231, 'thermostat.turn_on', 1)]
"""

from __future__ import annotations

import bisect
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from hybrid.compose import System
from hybrid.held import HeldCache
from hybrid.simulation.compiled import CompiledMode, CompiledModel
from hybrid.simulation.instants import (
    Key,
    first_over_cap,
    inside,
    interleave,
    nearest_rows,
    tolerance,
    transition_key,
)
from hybrid.simulation.layout import run_layout
from hybrid.simulation.monitor import with_group_requirements
from hybrid.simulation.result import Jump, Run, Termination
from hybrid.simulation.settings import Settings

__all__ = ["group_system", "independent_groups", "merge", "simulate_apart"]

GroupRunner = Callable[[System, np.ndarray, Settings], tuple[Run, CompiledModel]]


def independent_groups(system: System) -> list[tuple[int, ...]]:
    """Components linked by a shared label, or a signal or state variable read as an input."""
    parent = list(range(len(system.components)))

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    def join(a: int, b: int) -> None:
        ra, rb = find(a), find(b)
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)

    for owners in system.shared_labels.values():
        for o in owners[1:]:
            join(owners[0], o)
    providers = system.providers  # signals and state variables an input may read
    for i, c in enumerate(system.components):
        for name in c.automaton.inputs:
            if name in providers:
                join(i, providers[name])
    members: dict[int, list[int]] = {}
    for i in range(len(parent)):
        members.setdefault(find(i), []).append(i)
    return sorted(tuple(m) for m in members.values())


def simulate_apart(
    system: System,
    groups: Sequence[tuple[int, ...]],
    x0: np.ndarray,
    settings: Settings,
    run_group: GroupRunner,
) -> Run:
    """Run each group of ``system`` alone (from its part of ``x0``) and merge the runs.

    ``run_group`` gets each group as :func:`group_system` gives it.
    """
    offsets = np.cumsum([0] + [len(c.automaton.states) for c in system.components])
    dense = replace(settings, dense=True)
    parts: list[_Part] = []
    for members in groups:
        sub = group_system(system, members)
        columns = np.concatenate([np.arange(offsets[i], offsets[i + 1]) for i in members])
        run, compiled = run_group(sub, x0[columns.astype(int)], dense)
        parts.append(_Part(members, run, compiled))
    return merge(system, parts, settings)


_GROUPS = HeldCache[System](64)


def group_system(system: System, members: tuple[int, ...]) -> System:
    """The system of ``system``'s components ``members``, with the system requirements it
    owns (:func:`~hybrid.simulation.monitor.with_group_requirements`): the same object
    each time asked.

    Each run of ``system`` runs its groups as these systems, and a system run again is
    not compiled again (:func:`~hybrid.simulation.reuse.compiled_model`).
    """

    def make() -> System:
        components = tuple(system.components[i] for i in members)
        group = System(system.name, components, file=system.file, position=system.position)
        return with_group_requirements(system, group)

    return _GROUPS.get((id(system), members), system, make)


@dataclass
class _Part:
    members: tuple[int, ...]
    run: Run
    compiled: CompiledModel

    def __post_init__(self) -> None:
        self.modes: dict[str, CompiledMode] = {m.name: m for m in self.compiled._modes.values()}
        self.segments = sorted(self.run.segments, key=lambda s: (s[0], s[1]))
        self.rows: dict[tuple[float, int], int] = {}
        for k, (t, j) in enumerate(zip(self.run.t.tolist(), self.run.j.tolist(), strict=True)):
            self.rows.setdefault((t, j), k)
        self.location_at = {
            int(j): str(loc) for j, loc in zip(self.run.j, self.run.location, strict=True)
        }
        self._keys: dict[tuple[str, str], Key] = {}

    def key(self, jump: Jump, name: str) -> Key:
        """The rank in the system of transition ``name``, enabled where ``jump`` leaves."""
        found = self._keys.get((jump.source, name))
        if found is None:
            view = next(
                tr.view for tr in self.modes[jump.source].transitions if tr.name == name
            )
            found = self._keys[(jump.source, name)] = transition_key(view, self.members)
        return found

    def fill(
        self,
        times: np.ndarray,
        lj: np.ndarray,
        states: np.ndarray,
        xs: np.ndarray,
        signals: np.ndarray,
        ss: np.ndarray,
    ) -> None:
        """Write this group's states (columns ``xs``) and signals (``ss``) at every row.

        ``times`` and ``lj`` (this group's hybrid time) give the rows: values come
        from this group's own points where it has one, else from the interpolant
        of its stay (one vectorised call per stay), signals computed from them.
        """
        own = np.array(
            [self.rows.get((t, j), -1) for t, j in zip(times.tolist(), lj.tolist(), strict=True)]
        )
        nearest_rows(self.run, self.segments, times, lj, own)  # a rounding error before one
        exact = own >= 0
        if exact.any():
            states[np.ix_(exact, xs)] = self.run.states[own[exact]]
            if ss.size:
                signals[np.ix_(exact, ss)] = self.run.signals[own[exact]]
        todo = ~exact
        for j, t0, t1, sol in self.segments:
            if not todo.any():
                break
            mask = todo & (lj == j) & (times >= t0) & (times <= t1)
            if mask.any():
                if len(xs):
                    values = np.asarray(sol(times[mask]), dtype=float).reshape(len(xs), -1).T
                else:  # a group without state variables (a controller of locations only)
                    values = np.empty((int(mask.sum()), 0))
                states[np.ix_(mask, xs)] = values
                if ss.size:
                    mode = self.modes[self.location_at[j]]
                    signals[np.ix_(mask, ss)] = [
                        mode.outputs(t, x)
                        for t, x in zip(times[mask].tolist(), values, strict=True)
                    ]
                todo &= ~mask
        if todo.any():  # pragma: no cover - every row is a point or inside a stay
            raise RuntimeError("a point of a group is neither stored nor inside a stay")

    def location_columns(self, lj: np.ndarray) -> list[list[str]]:
        """Per member component, its location (``comp.loc``) at each row."""
        by_j = {j: name.split("|") for j, name in self.location_at.items()}
        table = np.array([by_j[j] for j in sorted(by_j)], dtype=object)
        order = {j: k for k, j in enumerate(sorted(by_j))}
        picked = table[np.array([order[j] for j in lj.tolist()], dtype=int)]
        return [picked[:, m].tolist() for m in range(len(self.members))]


def merge(system: System, parts: Sequence[_Part], settings: Settings) -> Run:
    """The system's run from the runs of its groups (see the module's docstring)."""
    ends = [p.run.termination for p in parts]
    early = [k for k, e in enumerate(ends) if e.cause != "t_end"]
    first = min((ends[k].t for k in early), default=settings.t_end)
    stopper = min(  # of ends at one instant, one where a jump was due (the product jumps on)
        (k for k in early if ends[k].t - first <= tolerance(first)),
        key=lambda k: (ends[k].cause not in ("zeno", "max_jumps"), ends[k].t, k),
        default=None,
    )
    t_stop = settings.t_end if stopper is None else ends[stopper].t
    merged = interleave(
        [[jump for jump in p.run.jumps if jump.t <= t_stop + tolerance(t_stop)] for p in parts],
        lambda g, jump, name: parts[g].key(jump, name),
    )
    events = [(jump.t, g, jump.j, jump) for g, jump, _ in merged]
    # a group's own points between an instant and its own time of a jump there are left out
    skipped: list[list[tuple[float, float]]] = [[] for _ in parts]
    for g, jump, own in merged:
        if own > jump.t:
            skipped[g].append((jump.t, own))
    termination_cause = None
    over = first_over_cap([e[0] for e in events], settings.max_jumps_per_instant)
    if len(events) > settings.max_jumps and (over is None or settings.max_jumps <= over):
        t_stop = events[settings.max_jumps][0]
        events = events[: settings.max_jumps]
        termination_cause = "max_jumps"
    elif over is not None:
        t_stop, last = events[over][0], events[over][3].edge
        events = events[:over]
        termination_cause = "zeno"
    # the hybrid time of each group after k jumps of the system
    local = np.zeros((len(events) + 1, len(parts)), dtype=np.int64)
    for k, (_, g, _, _) in enumerate(events):
        local[k + 1] = local[k]
        local[k + 1, g] += 1
    jump_times = [e[0] for e in events]

    rows: list[tuple[float, int]] = [(settings.t_start, 0)]
    for k, (t, _, _, _) in enumerate(events):
        rows += [(t, k), (t, k + 1)]
    for g, p in enumerate(parts):
        for t, j in zip(p.run.t.tolist(), p.run.j.tolist(), strict=True):
            if t > t_stop or inside(skipped[g], t):
                continue
            big_j = _global_j(local, g, j, t, jump_times)
            if big_j is not None:
                rows.append((t, big_j))
    rows.append((t_stop, len(events)))
    rows = sorted(set(rows))

    names = system.state_names
    signal_names = system.signal_columns
    times = np.array([t for t, _ in rows], dtype=float)
    big_js = np.array([j for _, j in rows], dtype=np.int64)
    states = np.empty((len(rows), len(names)))
    signals = np.empty((len(rows), len(signal_names)))
    state_col = {n: k for k, n in enumerate(names)}
    signal_col = {n: k for k, n in enumerate(signal_names)}
    per_component: list[list[str]] = [[] for _ in system.components]
    for g, p in enumerate(parts):
        lj = local[big_js, g]
        xs = np.array([state_col[n] for n in p.run.state_names], dtype=int)
        ss = np.array([signal_col[n] for n in p.run.signal_names], dtype=int)
        p.fill(times, lj, states, xs, signals, ss)
        for i, column in zip(p.members, p.location_columns(lj), strict=True):
            per_component[i] = column
    locations: list[str] = []
    named: dict[tuple[str, ...], str] = {}  # one name per location, as the run's other points
    for key in zip(*per_component, strict=True):
        name = named.get(key)
        if name is None:
            name = named[key] = "|".join(key)
        locations.append(name)

    index = {row: r for r, row in enumerate(rows)}
    jumps: list[Jump] = []
    for k, (t, _g, _, jump) in enumerate(events):
        before, after = index[(t, k)], index[(t, k + 1)]
        jumps.append(
            replace(
                jump,
                j=k,
                source=locations[before],
                target=locations[after],
                before=dict(zip(names, states[before].tolist(), strict=True)),
                after=dict(zip(names, states[after].tolist(), strict=True)),
            )
        )
    where = locations[-1]
    if termination_cause == "max_jumps":
        message = f"reached max_jumps={settings.max_jumps}"
        termination = Termination("max_jumps", t_stop, len(events), message, location=where)
    elif termination_cause == "zeno":
        message = (
            f"{settings.max_jumps_per_instant} jumps at the same instant: a cycle of "
            f"transitions takes no time (last: {last})"
        )
        termination = Termination(
            "zeno", t_stop, len(events), message, zeno_time=t_stop, location=where
        )
    elif stopper is None:
        termination = Termination("t_end", t_stop, len(events), "reached t_end", location=where)
    else:
        termination = replace(ends[stopper], j=len(events), location=where)
    return Run(
        model=system.name,
        state_names=tuple(names),
        signal_names=tuple(signal_names),
        t=np.array([t for t, _ in rows], dtype=float),
        j=np.array([j for _, j in rows], dtype=np.int64),
        location=np.array(locations, dtype=object),
        states=states,
        signals=signals,
        jumps=jumps,
        termination=termination,
        settings=settings.as_dict(),
        segments=_segments(parts, local, jump_times, settings, t_stop) if settings.dense else [],
        units=run_layout(system)["units"],
    )


def _global_j(
    local: np.ndarray, g: int, j: int, t: float, jump_times: Sequence[float]
) -> int | None:
    """The system's hybrid time of a point of group ``g`` at ``(t, j)``, or ``None`` if cut."""
    # the system's jumps after which group g is in its hybrid time j
    candidates = np.flatnonzero(local[:, g] == j)
    if candidates.size == 0:
        return None
    first, last = int(candidates[0]), int(candidates[-1])
    # among them, the last one whose jump happened at or before t (flow points sit after jumps)
    k = bisect.bisect_right(jump_times, t)
    return max(first, min(last, k))


class _Joined:
    """The system's interpolant over one of its stays: every group's, side by side."""

    def __init__(self, pieces: list[tuple[_Piecewise, np.ndarray]], width: int) -> None:
        self.pieces = pieces
        self.width = width

    def __call__(self, t: float | np.ndarray) -> np.ndarray:
        ts = np.atleast_1d(np.asarray(t, dtype=float))
        out = np.empty((self.width, ts.size))
        for piece, cols in self.pieces:
            out[cols] = piece(ts)
        return out if np.ndim(t) else out[:, 0]


class _Piecewise:
    """One group's interpolants of its stays at one hybrid time, as one callable."""

    def __init__(self, stays: list[tuple[int, float, float, object]]) -> None:
        self.stays = sorted(stays, key=lambda s: s[1])
        self.starts = [s[1] for s in self.stays]

    def __call__(self, ts: np.ndarray) -> np.ndarray:
        cols = []
        for t in ts.tolist():
            k = max(0, bisect.bisect_right(self.starts, t) - 1)
            sol: Callable[[float], np.ndarray] = self.stays[k][3]  # type: ignore[assignment]
            cols.append(np.asarray(sol(t), dtype=float).reshape(-1))
        return np.stack(cols, axis=1)


def _segments(
    parts: Sequence[_Part],
    local: np.ndarray,
    jump_times: Sequence[float],
    settings: Settings,
    t_stop: float,
) -> list[tuple[int, float, float, object]]:
    """With ``dense``: one joined interpolant per stay of the system between its jumps."""
    columns, start = [], 0
    for p in parts:
        columns.append(np.arange(start, start + len(p.run.state_names)))
        start += len(p.run.state_names)
    result: list[tuple[int, float, float, object]] = []
    bounds = zip([settings.t_start, *jump_times], [*jump_times, t_stop], strict=True)
    for k, (t0, t1) in enumerate(bounds):
        if t1 <= t0:
            continue
        pieces = []
        for g, p in enumerate(parts):
            stays = [s for s in p.segments if s[0] == int(local[k, g])]
            if not stays:
                break
            pieces.append((_Piecewise(stays), columns[g]))
        else:
            result.append((k, t0, t1, _Joined(pieces, start)))
    return result
