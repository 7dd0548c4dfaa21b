"""Forbidden states (``properties.forbidden``): proved unreachable, or reported with a witness.

A forbidden entry names locations (per component in a system) and a condition
``when`` on the state. It is *proved unreachable* when no run can be in those
locations at once with ``when`` holding; the proof combines:

- **reachable modes**: the locations must be reachable together (in one
  reachable mode of the product when the components interact, each in its own
  group otherwise);
- **entry boxes and flows**: a component in a location is either *at an entry
  point* (inside the location's entry box, see :mod:`hybrid.analysis.static`)
  or *flowing*: inside the closure of the invariant, within the declared
  bounds, and, for a variable whose derivative has one sign all over that
  region, on the far side of its entry value (``x' >= 0`` keeps ``x`` above the
  lowest value it enters with; ``t`` grows too). An urgent location is never
  flowing;
- the condition, with the signals of those locations, decided over the box
  (intervals, contraction, the exact linear programs of :mod:`hybrid.analysis.solve`).

Components ``when`` reads but the entry does not name are tried in each of
their reachable locations (up to :data:`MAX_COMBINATIONS` combinations; beyond
that, anywhere within their bounds). When the condition may hold somewhere,
the entry is reported as ``property-unproved`` (a warning: not proved, not
refuted either) at its line with a shortest path to the locations as a
*candidate* run; ``hybrid check`` then decides it with ``hybrid reach`` when the
model is affine and a horizon is given (:mod:`hybrid.reach.check`).

Examples
--------
>>> import hybrid
>>> from hybrid.analysis.context import analyse
>>> tank = hybrid.load_text('''
... automaton: tank
... state: {level: {initial: 1, bounds: [0, 10]}}
... locations:
...   filling: {flow: {level: 1}, invariant: level <= 5}
...   draining: {flow: {level: -1}, invariant: level >= 1}
... edges:
...   - {from: filling, to: draining, guard: level >= 5}
...   - {from: draining, to: filling, guard: level <= 1}
... properties:
...   forbidden:
...     - {location: filling, when: level > 6}
...     - {location: draining, when: level < 0.5}
...     - {location: draining, when: level > 4.5}
... ''')
>>> [f.message.split(":")[0] for f in forbidden_states(analyse(tank))]
["forbidden state 'draining with level > 4.5' may be reached"]
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Iterator, Mapping

from hybrid.analysis.context import Analysis, path_text
from hybrid.analysis.findings import Finding, WitnessStep
from hybrid.analysis.solve import Box, Env, conjoin, satisfiable
from hybrid.analysis.static import AutomatonFacts
from hybrid.expr import ir
from hybrid.expr.interval import Interval
from hybrid.model import Forbidden

__all__ = ["MAX_COMBINATIONS", "flowing_box", "forbidden_states"]

MAX_COMBINATIONS = 256
"""Most combinations of locations of the components a condition reads that are tried."""

_TIME = Interval(0.0, math.inf)
_TRUE = ir.BoolConst(True)
Place = tuple[Box, ir.Expr]
"""Where a component may be in a location: a box, and a condition holding there."""


def flowing_box(facts: AutomatonFacts, location: str, rounds: int = 2) -> dict[str, Interval] | None:
    """A box holding every state of a run flowing in ``location`` (``None``: never flowing).

    The location's region (closure of the invariant, within the bounds),
    narrowed by the sign of each derivative over it: a variable that cannot
    decrease there stays at or above the lowest value it enters with, one that
    cannot increase at or below the highest (``t`` never decreases).
    """
    lf = facts.locations[location]
    entry = facts.entries.get(location)
    if lf.region is None or entry is None or facts.automaton.locations[location].urgent:
        return None
    box = dict(lf.region)
    box.setdefault("t", _TIME)
    for _ in range(rounds):
        ev = lf.env.evaluator(box)
        changed = False
        rates = {s: ev.number(lf.flow.get(s, ir.Num(0.0))) for s in facts.automaton.state_names}
        rates["t"] = Interval.point(1.0)
        for name, rate in rates.items():
            start = entry.get(name)
            current = box.get(name, _TIME if name == "t" else Interval(-math.inf, math.inf))
            if start is None:
                continue
            lo, hi = current.lo, current.hi
            if rate.lo >= 0:
                lo = max(lo, start.lo)
            if rate.hi <= 0:
                hi = min(hi, start.hi)
            if lo > hi:
                return None
            if (lo, hi) != (current.lo, current.hi):
                box[name] = Interval(lo, hi)
                changed = True
        if not changed:
            break
    return box


def _places(facts: AutomatonFacts, location: str) -> list[Place]:
    """Where a run may be in ``location``: flowing (with its closed invariant), or entering."""
    found: list[Place] = []
    flowing = flowing_box(facts, location)
    if flowing is not None:
        found.append((flowing, facts.locations[location].closed))
    entry = facts.entries.get(location)
    if entry is not None:
        found.append((dict(entry), _TRUE))
    return found


def _merge(boxes: list[Box]) -> dict[str, Interval] | None:
    """The intersection of boxes over the same instant (a name absent from one is free there)."""
    merged: dict[str, Interval] = {}
    for box in boxes:
        for name, value in box.items():
            old = merged.get(name)
            if old is None:
                merged[name] = value
                continue
            meet = old.intersect(value)
            if meet is None:
                return None
            merged[name] = meet
    return merged


def _combinations(analysis: Analysis, entry: Forbidden) -> Iterator[dict[int, str | None]]:
    """Per combination: component -> location (``None``: anywhere within its bounds)."""
    system = analysis.system
    index = {c.name: i for i, c in enumerate(system.components)}
    fixed = {
        (0 if system.single or not comp else index[comp]): loc
        for comp, loc in entry.locations.items()
    }
    read = set() if entry.when is None else ir.names_in(entry.when)
    others = sorted({system.providers[n] for n in read if n in system.providers} - set(fixed))
    choices: list[list[str | None]] = []
    for i in others:
        automaton = system.components[i].automaton
        choices.append([name for name in automaton.locations if analysis.reached(i, name)])
    if math.prod(len(c) for c in choices) > MAX_COMBINATIONS:
        choices = [[None] for _ in others]
    for combo in itertools.product(*choices):
        yield {**fixed, **dict(zip(others, combo, strict=True))}


def _may_hold(analysis: Analysis, entry: Forbidden, combo: dict[int, str | None]) -> bool:
    """Whether ``when`` may hold with each component of ``combo`` in its location."""
    options: list[list[Place]] = []
    signals: dict[str, ir.Expr] = {}
    opaque: frozenset[str] = frozenset()
    for i, loc in combo.items():
        facts = analysis.facts[i]
        opaque |= facts.opaque
        if loc is None:
            options.append([(dict(facts.bounds), _TRUE)])
            continue
        signals.update(facts.locations[loc].env.signals)
        options.append(_places(facts, loc))
    inputs = [f.inputs for f in analysis.facts]
    env = Env(signals, opaque)
    when = entry.when or _TRUE
    for places in itertools.product(*options):
        box = _merge([*(b for b, _ in places), *inputs])
        if box is None:
            continue
        if satisfiable(conjoin(when, *(c for _, c in places)), env, box):
            return True
    return False


def _witness(analysis: Analysis, combo: Mapping[int, str | None]) -> tuple[WitnessStep, ...] | None:
    """A shortest path to a mode with the components of ``combo`` in their locations
    (group by group), or ``None`` when no explored mode has them."""
    reach = analysis.exploration
    system = analysis.system
    mode = list(system.initial_mode)
    steps: list[WitnessStep] = []
    paths = []
    for members, tables, exploration in reach.parts:
        wanted = {
            k: tables.components[k].index[loc]
            for k, i in enumerate(members)
            if (loc := combo.get(i)) is not None
        }
        code = exploration.first_matching(wanted) if wanted else 0
        if code is None:
            return None
        origin = exploration.origin(code)
        for k, i in enumerate(members):
            mode[i] = tables.components[k].locations[origin[k]]
        paths.append((members, tables, exploration.path_to(code)))
    steps.append((None, system.mode_name(tuple(mode))))
    for members, tables, path in paths:
        for transition, local in path:
            for k, i in enumerate(members):
                mode[i] = tables.components[k].locations[local[k]]
            steps.append((tables.transition_name(transition), system.mode_name(tuple(mode))))
    return tuple(steps)


def forbidden_states(analysis: Analysis) -> list[Finding]:
    """The forbidden entries not proved unreachable, each with a candidate path."""
    found: list[Finding] = []
    for entry in analysis.system.properties.forbidden:
        for combo in _combinations(analysis, entry):
            located = {i: loc for i, loc in combo.items() if loc is not None}
            if not all(analysis.reached(i, loc) for i, loc in located.items()):
                continue
            if not _may_hold(analysis, entry, combo):
                continue
            witness = _witness(analysis, located)
            if witness is None:
                continue  # not together in any reachable mode (or not explored)
            found.append(
                Finding.at(
                    "property-unproved",
                    entry.position,
                    f"forbidden state '{entry.text()}' may be reached: {path_text(witness)}"
                    + _how(analysis, entry, located),
                    where=f"forbidden: {entry.text()}",
                    witness=witness,
                )
            )
            break
    return found


def _how(analysis: Analysis, entry: Forbidden, located: Mapping[int, str]) -> str:
    if entry.when is None:
        return ""
    places = ", ".join(analysis.qualified(i, loc) for i, loc in located.items())
    where = f" in {places}" if places else ""
    return (
        f"; '{entry.when_source}' may hold there{where} (over the entry boxes, the invariants "
        "and the bounds: the state at the end of the path is not simulated)"
    )
