"""Output variables and unused variables of a SpaceEx base component.

- An *output variable*: a real variable no flow nor jump changes, which every
  location's invariant defines by an equation ``y == e`` (``e`` not reading
  ``y``), as the ARCH-COMP Building writes ``y1 == x25``. In SpaceEx the
  invariant ties ``y`` to ``e`` at every instant; ours is the signal ``y: e``
  (a location whose ``e`` differs from the first location's overrides it in
  its own ``signals``). The equations leave the invariants.
- An *unused variable*: an input that nothing of the component reads (no
  flow, invariant, guard, reset or signal, once the bounds that became its
  range are out of the invariants): dropped, with a note.

Examples
--------
>>> from hybrid.interchange.safexml import SourceText
>>> from hybrid.interchange import sxexpr as sx
>>> inv = {"1": sx.conjuncts(sx.parse(SourceText("m.xml", "y == 2*x & x <= 3")))}
>>> found = output_equations(["y"], inv)
>>> item, definition = found["y"]["1"]
>>> sorted(found), type(definition).__name__, item is inv["1"][0]
(['y'], 'BinOp', True)
>>> sorted(identifiers(["2 * x + sin(y)", "x <= 1e-3 * z1"]))
['sin', 'x', 'y', 'z1']
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from typing import TYPE_CHECKING

from hybrid.errors import Position
from hybrid.interchange import sxexpr as sx
from hybrid.interchange.sxmodel import Component
from hybrid.interchange.translate import Rename, condition_text, number_text

if TYPE_CHECKING:
    from hybrid.interchange.template import EdgeInfo, LocationInfo

__all__ = [
    "definition",
    "identifiers",
    "output_equations",
    "outputs",
    "read_names",
    "reads",
    "unused",
]

_TOKEN = re.compile(r"(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?|([A-Za-z_][A-Za-z0-9_]*)")


def reads(node: sx.Node, *, primed: bool = False) -> set[str]:
    """The unprimed variable names a SpaceEx tree reads (primed ones too with ``primed``)."""
    found: set[str] = set()
    stack = [node]
    while stack:
        current = stack.pop()
        if isinstance(current, sx.Name):
            if primed or not current.primed:
                found.add(current.name)
        elif isinstance(current, sx.Neg):
            stack.append(current.operand)
        elif isinstance(current, sx.BinOp):
            stack.extend((current.left, current.right))
        elif isinstance(current, sx.Call):
            stack.extend(current.args)
        elif isinstance(current, sx.Cmp):
            stack.extend(current.operands)
        elif isinstance(current, sx.And | sx.Or):
            stack.extend(current.items)
    return found


def definition(item: sx.Node, var: str) -> sx.Node | None:
    """``e`` if ``item`` is ``var == e`` or ``e == var`` with ``e`` not reading ``var``."""
    if not isinstance(item, sx.Cmp) or item.ops != ("==",):
        return None
    left, right = item.operands
    for side, other in ((left, right), (right, left)):
        named = isinstance(side, sx.Name) and not side.primed and side.name == var
        if named and var not in reads(other) and not _has_prime(other):
            return other
    return None


def _has_prime(node: sx.Node) -> bool:
    stack = [node]
    while stack:
        current = stack.pop()
        if isinstance(current, sx.Name) and current.primed:
            return True
        if isinstance(current, sx.Neg):
            stack.append(current.operand)
        elif isinstance(current, sx.BinOp):
            stack.extend((current.left, current.right))
        elif isinstance(current, sx.Call):
            stack.extend(current.args)
    return False


def output_equations(
    candidates: Iterable[str], invariants: Mapping[str, list[sx.Node]]
) -> dict[str, dict[str, tuple[sx.Node, sx.Node]]]:
    """``{y: {location id: (conjunct, e)}}`` for each candidate every location's invariant defines.

    ``invariants`` maps each location id to its invariant's conjuncts. A
    candidate some location leaves undefined (or defines twice) is not an
    output.
    """
    found: dict[str, dict[str, tuple[sx.Node, sx.Node]]] = {}
    if not invariants:
        return found
    for var in candidates:
        per_location: dict[str, tuple[sx.Node, sx.Node]] = {}
        for lid, items in invariants.items():
            defs = [(c, d) for c in items if (d := definition(c, var)) is not None]
            if len(defs) != 1:
                break
            per_location[lid] = defs[0]
        else:
            found[var] = per_location
    return found


def identifiers(texts: Iterable[str]) -> set[str]:
    """Every name in texts of our expression language (functions included)."""
    found: set[str] = set()
    for text in texts:
        found.update(name for name in _TOKEN.findall(text) if name)
    return found


def outputs(
    comp: Component,
    inputs: list[str],
    locations: list[LocationInfo],
    rename: Rename,
    notes: list[str],
    origins: dict[tuple[str | int, ...], Position],
) -> dict[str, dict[str, str]]:
    """The output variables (see the module docstring), their equations taken out of the invariants."""
    found = output_equations(inputs, {loc.id: loc.invariant for loc in locations})
    signals: dict[str, dict[str, str]] = {}
    for var, per_location in found.items():
        signals[var] = {}
        for loc in locations:
            item, value = per_location[loc.id]
            loc.invariant = [c for c in loc.invariant if c is not item]
            loc.removed.append(f"the definition of the output {var}")
            signals[var][loc.name] = number_text(value, rename)
            origins.setdefault(("signals", rename(var)), item.position)
            origins[("locations", loc.name, "signals", rename(var))] = item.position
        shown = next(iter(signals[var].values()))
        notes.append(
            f"component '{comp.id}': variable '{var}' is an output: every location's invariant "
            f"defines it ({var} == {shown}{', ...' if len(set(signals[var].values())) > 1 else ''}),"
            f" so it is the signal {rename(var)}"
        )
    return signals


def read_names(
    locations: list[LocationInfo],
    edges: list[EdgeInfo],
    signals: dict[str, dict[str, str]],
    names: dict[str, str],
) -> set[str]:
    """Our names the component's flows, invariants, guards, resets and outputs read."""
    texts: list[str] = []
    for loc in locations:
        texts.extend(loc.flow.values())
        texts.extend(condition_text(c, names.__getitem__) for c in loc.invariant)
    for edge in edges:
        texts.append(edge.guard)
        texts.extend(edge.reset.values())
    for per_location in signals.values():
        texts.extend(per_location.values())
    return identifiers(texts)


def unused(
    comp: Component,
    inputs: list[str],
    constants: list[str],
    read: set[str],
    names: dict[str, str],
    notes: list[str],
) -> tuple[list[str], list[str]]:
    """The inputs and the constants nothing of the component reads (``read``: our names its
    flows, invariants, guards, resets and outputs read, once input bounds became ranges)."""
    dropped = [i for i in inputs if names[i] not in read]
    for var in dropped:
        notes.append(
            f"component '{comp.id}': variable '{var}' is declared but nothing reads it (no flow, "
            "invariant, guard, assignment or output): left out"
        )
    idle = [c for c in constants if names[c] not in read]
    for c in idle:
        notes.append(
            f"component '{comp.id}': constant '{c}' is read by nothing kept here (no flow, "
            "invariant, guard, assignment or output): not a parameter here"
        )
    return dropped, idle
