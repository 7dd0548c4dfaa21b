"""Flows that are not equations: ``false`` (no time may pass) and rates bounded by numbers.

- ``<flow>false</flow>``: no time may pass in the location: our ``urgent: true``.
- ``x' >= a & x' <= b`` (any comparisons that bound ``x'`` alone by numbers,
  ``-x' <= -1`` or ``a <= x' <= b`` too, constants by their values): a
  *rectangular* flow, the rate any value of ``[a, b]`` at any instant. Ours is
  a bounded input ``w`` with ``range: [a, b]`` and ``x' = w``: ``simulate``
  holds ``w`` at the midpoint unless told otherwise, ``check`` and ``reach``
  reason over the range. ``a == b`` is the equation ``x' = a``.

Examples
--------
>>> from hybrid.interchange.safexml import SourceText
>>> parts = flow_parts(sx.parse(SourceText("m.xml", "true && -x' <= -1 && x' <= c & y' == x")), {"c": 2.0})
>>> len(parts.equations), parts.rates, parts.urgent
(1, {'x': (1.0, 2.0)}, False)
>>> flow_parts(sx.parse(SourceText("m.xml", "false")), {}).urgent
True
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

from hybrid.errors import SpecError
from hybrid.interchange import sxexpr as sx
from hybrid.interchange.affine import Affine, affine_form
from hybrid.interchange.sxmodel import Component
from hybrid.interchange.translate import constant_value

__all__ = ["FlowParts", "flow_parts", "rate_inputs"]

_FLIP = {"<=": ">=", "<": ">", ">=": "<=", ">": "<", "==": "=="}


@dataclass
class FlowParts:
    """A flow split into its equations, its bounded rates and whether it is ``false``."""

    equations: list[sx.Node] = field(default_factory=list)
    rates: dict[str, tuple[float, float]] = field(default_factory=dict)
    urgent: bool = False


def _linear(node: sx.Node, values: Mapping[str, float]) -> Affine | None:
    """``(x, a, b)`` for ``a * x' + b`` (``x`` ``None`` for a number), else ``None``."""

    def leaf(n: sx.Node) -> Affine | None:
        if isinstance(n, sx.Name) and n.primed:
            return n.name, 1.0, 0.0
        value = constant_value(n, values)
        return None if value is None else (None, 0.0, value)

    return affine_form(node, leaf)


def _rate_bound(item: sx.Cmp, values: Mapping[str, float]) -> tuple[str, float, float] | None:
    """``(x, lo, hi)`` if ``item`` bounds one derivative ``x'`` by numbers, else ``None``."""
    var: str | None = None
    lo, hi = -math.inf, math.inf
    for op, a, b in zip(item.ops, item.operands, item.operands[1:], strict=False):
        left, right = _linear(a, values), _linear(b, values)
        if left is None or right is None or op == "!=":
            return None
        name = left[0] or right[0]
        if name is None or (var is not None and name != var):
            return None
        if left[0] and right[0] and left[0] != right[0]:
            return None
        var = name
        coef, const = left[1] - right[1], right[2] - left[2]  # coef * x'  op  const
        if coef == 0:
            return None
        bound = const / coef
        side = op if coef > 0 else _FLIP[op]
        if side in ("<=", "<"):
            hi = min(hi, bound)
        elif side in (">=", ">"):
            lo = max(lo, bound)
        else:
            lo, hi = max(lo, bound), min(hi, bound)
    return None if var is None else (var, lo, hi)


def flow_parts(node: sx.Node, values: Mapping[str, float]) -> FlowParts:
    """Split a flow; ``values`` are the constants' values (for bounds written with them).

    Raises
    ------
    SpecError
        For a rate bounded on one side only, or an empty range.
    """
    parts = FlowParts()
    bounds: dict[str, tuple[float, float, sx.Cmp]] = {}
    for item in sx.conjuncts(node):
        if isinstance(item, sx.Bool) and not item.value:
            parts.urgent = True
            continue
        if not isinstance(item, sx.Cmp):
            parts.equations.append(item)
            continue
        found = _rate_bound(item, values)
        if found is None or (item.ops == ("==",) and _is_equation(item)):
            parts.equations.append(item)
            continue
        var, lo, hi = found
        old = bounds.get(var)
        if old is not None:
            lo, hi = max(lo, old[0]), min(hi, old[1])
        bounds[var] = (lo, hi, old[2] if old else item)
    if parts.urgent:
        return FlowParts(urgent=True)
    for var, (lo, hi, item) in bounds.items():
        if not (math.isfinite(lo) and math.isfinite(hi)):
            raise SpecError(
                f"the rate of '{var}' is bounded on one side only ({var}' in [{lo}, {hi}]): a "
                "nondeterministic flow has a counterpart here only as a bounded input; bound "
                f"{var}' on both sides (a <= {var}' & {var}' <= b)",
                item.position,
            )
        if lo > hi:
            raise SpecError(f"the rate of '{var}' has an empty range [{lo}, {hi}]", item.position)
        if lo == hi:  # x' == a, written as two bounds
            where = item.position
            parts.equations.append(
                sx.Cmp(("==",), (sx.Name(var, True, where), sx.Num(lo, where)), where)
            )
        else:
            parts.rates[var] = (lo, hi)
    return parts


def _is_equation(item: sx.Cmp) -> bool:
    """``x' == e`` with ``x'`` alone on one side: an equation of the flow, even with numbers."""
    return any(isinstance(o, sx.Name) and o.primed for o in item.operands)


def rate_inputs(
    comp: Component,
    rates: dict[str, dict[str, tuple[float, float]]],
    parsed_flows: dict[str, dict[str, str]],
    names: dict[str, str],
    notes: list[str],
) -> dict[str, tuple[str, tuple[float, float]]]:
    """One input per rectangular rate (variable, range): ``{input: (variable, range)}``.

    Each location's flow of the variable becomes ``x' = input``.
    """
    found: dict[str, tuple[str, tuple[float, float]]] = {}
    for lid, per_var in rates.items():
        for var, bounds in per_var.items():
            name = next((n for n, (v, b) in found.items() if v == var and b == bounds), None)
            if name is None:
                base = f"{names[var]}_rate"
                name, k = base, 1
                while name in names.values() or name in names or name in found:
                    k += 1
                    name = f"{base}{k}"
                found[name] = (var, bounds)
                names[name] = name
                lo, hi = bounds
                notes.append(
                    f"component '{comp.id}': the flow {var}' in [{lo:g}, {hi:g}] is "
                    f"nondeterministic: it is the input {name} with range [{lo:g}, {hi:g}] and "
                    f"{names[var]}' = {name} (simulate holds it at {(lo + hi) / 2:g}; check and "
                    "reach take the range)"
                )
            if var in parsed_flows[lid]:
                raise SpecError(
                    f"the flow of '{var}' is given both as an equation and as bounds",
                    comp.position,
                )
            parsed_flows[lid][var] = name
    return found
