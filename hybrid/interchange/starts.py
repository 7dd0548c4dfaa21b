"""Where each instance starts: its initial location(s) and state, from the ``.cfg``'s initial set.

A component the ``.cfg`` gives no ``loc(...)`` for may start in every location whose
invariant the initial box can meet (decided by interval arithmetic: a location is
left out only when its invariant provably fails over the whole box); those whose
invariant holds at the nominal point come first, so ``simulate`` starts in one.
"""

from __future__ import annotations

import math
from typing import Any

from hybrid.errors import Position, SpecError
from hybrid.expr.interval import Interval
from hybrid.expr.ranges import can_fail, can_hold
from hybrid.interchange import sxexpr as sx
from hybrid.interchange.cfg import SpaceExConfig
from hybrid.interchange.flatten import Leaf
from hybrid.interchange.initial import InitialSet
from hybrid.interchange.inputs import bound
from hybrid.interchange.template import Template
from hybrid.interchange.translate import condition_ir

__all__ = ["exact_comment", "location_name", "start_of"]


def exact_comment(exact: list[str]) -> str:
    """The YAML comment for initial intervals that bound a set that is not a box."""
    return (
        "the .cfg's initial set " + " and ".join(exact) + " is not a box: these intervals are "
        "its bounding box, nominal its centre"
    )


def location_name(t: Template, spaceex_name: str, where: Position) -> str:
    """Our name of the location SpaceEx calls ``spaceex_name`` (``loc(...) == name`` at ``where``)."""
    loc = t.location(spaceex_name)
    if loc is None:
        raise SpecError(
            f"component '{t.component.id}' has no location '{spaceex_name}' (locations: "
            f"{', '.join(loc.spaceex_name for loc in t.locations)})",
            where,
        )
    return loc.name


def start_of(
    leaf: Leaf, t: Template, init: InitialSet, config: SpaceExConfig | None
) -> dict[str, Any]:
    """``{location: ..., state: {...}}`` for one instance, from the initial set."""
    state: dict[str, Any] = {}
    box: dict[str, Interval] = {}
    point: dict[str, Interval] = {}
    notes: list[str] = []
    where_cfg = config.initially.where(0) if config and config.initially else Position("<cfg>")
    invariant = _initial_invariant(leaf, t, init)
    for inner in t.states:
        outer = leaf.variables[inner]
        ours = t.names[inner]
        if config is None or config.initially is None:
            lo = hi = 0.0
        elif outer in init.bounds:
            lo, hi = init.bounds[outer]
        else:
            lo, hi = float("-inf"), float("inf")
        if invariant is not None and config is not None and config.initially is not None:
            lo, hi = _intersect(leaf, inner, outer, (lo, hi), invariant, notes, where_cfg)
        if not (math.isfinite(lo) and math.isfinite(hi)):
            where = config.initially.where(0) if config and config.initially else Position("<cfg>")
            how = "unbounded" if math.isfinite(lo) or math.isfinite(hi) else "free (any number)"
            raise SpecError(
                f"the initial set leaves '{outer}' {how}: bound it in the .cfg's initially "
                f"(e.g. {outer} == 0, or lo <= {outer} & {outer} <= hi)",
                where,
            )
        nominal = init.nominal.get(outer, (lo + hi) / 2) + 0.0  # no -0.0
        if lo == hi:
            state[ours] = lo
        elif outer in init.nominal:
            state[ours] = {"initial": [lo, hi], "nominal": nominal}
        else:
            state[ours] = [lo, hi]
        box[ours] = Interval(lo, hi)
        point[ours] = Interval(nominal, nominal)
    for inner, (lo, hi) in t.ranges.items():
        box[t.names[inner]] = Interval(lo, hi)
        point[t.names[inner]] = Interval((lo + hi) / 2, (lo + hi) / 2)
    chosen = _initial_locations(leaf, t, init, box, point, config)
    exact = sorted(
        {init.exact[leaf.variables[s]] for s in t.states if leaf.variables[s] in init.exact}
    )
    found: dict[str, Any] = {
        "location": chosen[0] if len(chosen) == 1 else chosen,
        "state": state,
        "exact": exact,
        "notes": notes,
    }
    if leaf.index in init.alternatives:
        found["locations_comment"] = "the .cfg's initial set is a union over these locations"
    return found


def _initial_invariant(
    leaf: Leaf, t: Template, init: InitialSet
) -> tuple[str, list[sx.Node]] | None:
    """The name and invariant of the one location the instance starts in, if it is known."""
    if leaf.index in init.locations and leaf.index not in init.alternatives:
        loc = t.location(init.locations[leaf.index])
    elif len(t.locations) == 1:
        loc = t.locations[0]
    else:
        return None
    return None if loc is None else (loc.name, loc.invariant)


def _intersect(
    leaf: Leaf,
    inner: str,
    outer: str,
    interval: tuple[float, float],
    invariant: tuple[str, list[sx.Node]],
    notes: list[str],
    where: Position,
) -> tuple[float, float]:
    """``interval`` within the numeric bounds the initial location's invariant puts on ``inner``.

    SpaceEx's initial states are those of the initial set that satisfy the
    invariant: a variable the ``.cfg`` leaves free (the constant-input variants'
    ``u' == 0`` with ``0.8 <= u <= 1`` in the invariant) starts anywhere in its bounds.
    """
    values = {k: v for k, v in leaf.constants.items() if v is not None}
    lo, hi = interval
    name, items = invariant
    for item in items:
        found = bound(item, inner, values)
        if found is not None:
            lo, hi = max(lo, found[0]), min(hi, found[1])
    if lo > hi:
        raise SpecError(
            f"the initial set and the invariant of the initial location '{name}' leave no value "
            f"of '{outer}'",
            where,
        )
    if (lo, hi) != interval:
        was = (
            "leaves it free"
            if not any(map(math.isfinite, interval))
            else (f"gives [{interval[0]:g}, {interval[1]:g}]")
        )
        notes.append(
            f"the .cfg {was} for '{outer}'; with the invariant of the initial location "
            f"'{name}' (SpaceEx's initial states satisfy it) it starts in [{lo:g}, {hi:g}]"
        )
    return lo + 0.0, hi + 0.0


def _initial_locations(
    leaf: Leaf,
    t: Template,
    init: InitialSet,
    box: dict[str, Interval],
    point: dict[str, Interval],
    config: SpaceExConfig | None,
) -> list[str]:
    if leaf.index in init.locations:
        where = init.location_positions[leaf.index]
        names = init.alternatives.get(leaf.index, [init.locations[leaf.index]])
        return [location_name(t, name, where) for name in names]
    if config is None or config.initially is None:
        return [t.locations[0].name]
    rename = {**t.names, **{k: repr(v) for k, v in leaf.constants.items() if v is not None}}

    def name(n: str) -> str:
        return rename[n]

    possible: list[tuple[bool, str]] = []
    for loc in t.locations:
        cond = condition_ir(sx.And(tuple(loc.invariant), leaf.component.position), name)
        if can_hold(cond, box):
            possible.append((not can_fail(cond, point), loc.name))
    if not possible:
        raise SpecError(
            f"no location of '{leaf.name}' has an invariant that the initial set meets",
            config.initially.where(0),
        )
    return [n for holds, n in possible if holds] + [n for holds, n in possible if not holds]
