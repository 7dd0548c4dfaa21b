"""Input ranges: the bounds every location's invariant puts on a free input.

A variable of a component that nothing changes and the system leaves free is
an input. If every location's invariant bounds it by the same numbers
(``-0.1 <= w & w <= 0.1``, or with named constants, ``-max_drift <= d <=
max_drift``, by their values), those bounds are its ``range`` and leave the
invariants (a comment keeps them).

Examples
--------
>>> from hybrid.interchange.safexml import SourceText
>>> item = sx.parse(SourceText("m.xml", "-c <= w <= 2*c"))
>>> bound(item, "w", {"c": 0.5}), bound(item, "w", {})
((-0.5, 1.0), None)
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

from hybrid.interchange import sxexpr as sx
from hybrid.interchange.outputs import reads
from hybrid.interchange.sxmodel import Component
from hybrid.interchange.translate import constant_value

if TYPE_CHECKING:
    from hybrid.interchange.template import LocationInfo

__all__ = ["bound", "input_ranges"]


def bound(
    item: sx.Node, var: str, values: Mapping[str, float] | None = None
) -> tuple[float, float] | None:
    """The interval a conjunct puts on ``var`` if it is a bound by numbers, else ``None``."""
    if not isinstance(item, sx.Cmp):
        return None
    lo, hi = -float("inf"), float("inf")
    found = False
    for op, a, b in zip(item.ops, item.operands, item.operands[1:], strict=False):
        a_is = isinstance(a, sx.Name) and a.name == var and not a.primed
        b_is = isinstance(b, sx.Name) and b.name == var and not b.primed
        a_val = constant_value(a, values or {})
        b_val = constant_value(b, values or {})
        if a_is and b_val is not None:
            value, side = b_val, op
        elif b_is and a_val is not None:
            value, side = (
                a_val,
                {"<=": ">=", "<": ">", ">=": "<=", ">": "<", "==": "=="}.get(op, op),
            )
        else:
            return None
        found = True
        if side in ("<=", "<"):
            hi = min(hi, value)
        elif side in (">=", ">"):
            lo = max(lo, value)
        elif side == "==":
            lo, hi = max(lo, value), min(hi, value)
        else:
            return None
    return (lo, hi) if found else None


def input_ranges(
    comp: Component,
    free: list[str],
    locations: list[LocationInfo],
    notes: list[str],
    values: Mapping[str, float],
) -> dict[str, tuple[float, float]]:
    ranges: dict[str, tuple[float, float]] = {}
    for var in free:
        per_location: list[tuple[float, float] | None] = []
        for loc in locations:
            bounds = [b for b in (bound(c, var, values) for c in loc.invariant) if b is not None]
            if not bounds:
                per_location.append(None)
                continue
            lo = max(b[0] for b in bounds)
            hi = min(b[1] for b in bounds)
            per_location.append((lo, hi))
        if not per_location or any(r is None for r in per_location) or len(set(per_location)) > 1:
            notes.append(
                f"component '{comp.id}': input '{var}' is not bounded by the same numbers in "
                "every location's invariant, so it gets no range"
            )
            continue
        first = per_location[0]
        assert first is not None
        ranges[var] = first
        named = sorted(
            {
                n
                for loc in locations
                for c in loc.invariant
                if bound(c, var, values)
                for n in reads(c)
            }
            - {var}
        )
        notes.append(
            f"component '{comp.id}': '{var}' is changed by nothing and bounded in every "
            f"invariant: it is a free input with range [{first[0]:g}, {first[1]:g}] (simulate "
            "holds it at the midpoint; check and reach take the range)"
        )
        if named:
            notes.append(
                f"component '{comp.id}': the bounds of input '{var}' are written with the "
                f"constants {', '.join(named)}: with their values its range is "
                f"[{first[0]:g}, {first[1]:g}]"
            )
        for loc in locations:
            kept = []
            for c in loc.invariant:
                if bound(c, var, values) is not None:
                    loc.removed.append(f"input range of {var}")
                else:
                    kept.append(c)
            loc.invariant = kept
    return ranges
