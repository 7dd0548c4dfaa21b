"""The ``.cfg`` sets: ``initially`` as intervals and initial locations, ``forbidden`` as properties.

``initially`` is a conjunction. Each conjunct is one of

- a bound on one variable by numbers, as written or after moving terms
  (``10 <= x <= 10.2``, ``x >= 0.002``, ``v == 0``, ``2*x + 1 <= 3``): it narrows
  that variable's interval;
- ``loc(component) == name``: that component starts in that location;
- ``c == number`` for a constant the system leaves open: its value;
- an axis-aligned ellipse or disc, ``(x - a)^2 + k*(y - b)^2 <= r``: its bounding
  box becomes the variables' intervals and its centre their ``nominal`` (the
  box holds the set, so ``check`` reasons over more than SpaceEx's set: sound
  for proving forbidden states unreachable; a witness may start outside the
  disc). A note says so and the YAML keeps the exact set in a comment.

Anything else is refused at its position: our initial sets are boxes. Strict
bounds (``x > 0``) give the closed interval. ``forbidden`` is a disjunction
(``|``) of conjunctions; each becomes one ``properties.forbidden`` entry with
its locations and the rest as the ``when`` condition.

Names are resolved as SpaceEx resolves them: the full name (``osc.osci.y``),
else the one variable whose path ends with it (``y``).
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

from hybrid.errors import Position, SpecError
from hybrid.interchange import sxexpr as sx
from hybrid.interchange.affine import Affine, affine_form
from hybrid.interchange.safexml import SourceText
from hybrid.interchange.translate import condition_text, constant_value

__all__ = ["ForbiddenEntry", "InitialSet", "Resolver", "forbidden_set", "initial_set"]


@dataclass
class Resolver:
    """Finds the variable or component a ``.cfg`` name means."""

    ids: list[str]
    leaves: list[str]
    """Each leaf's instance path joined by ``.`` (a lone base component: its id)."""

    def variable(self, name: str) -> str:
        if name in self.ids:
            return name
        found = [i for i in self.ids if i.endswith("." + name)]
        if len(found) == 1:
            return found[0]
        if found:
            raise KeyError(f"'{name}' is ambiguous: write one of {', '.join(found)}")
        raise KeyError(
            f"'{name}' is not a variable of the system (variables: {', '.join(self.ids)})"
        )

    def leaf(self, name: str, where: Position) -> int:
        if not name and len(self.leaves) == 1:
            return 0
        exact = [i for i, p in enumerate(self.leaves) if p == name]
        found = exact or [i for i, p in enumerate(self.leaves) if p.endswith("." + name)]
        if len(found) == 1:
            return found[0]
        known = ", ".join(self.leaves)
        raise SpecError(
            f"loc({name}): {'ambiguous' if found else 'no such component'} (components: {known})",
            where,
        )


@dataclass
class InitialSet:
    bounds: dict[str, tuple[float, float]] = field(default_factory=dict)
    nominal: dict[str, float] = field(default_factory=dict)
    exact: dict[str, str] = field(default_factory=dict)
    """Variable id -> the non-box constraint its interval comes from, as written."""
    locations: dict[int, str] = field(default_factory=dict)
    """Leaf index -> the SpaceEx name of its initial location (the first, if several)."""
    alternatives: dict[int, list[str]] = field(default_factory=dict)
    """Leaf index -> every initial location, when a union (``|``) gives several."""
    location_positions: dict[int, Position] = field(default_factory=dict)
    constants: dict[str, float] = field(default_factory=dict)
    ranged: set[str] = field(default_factory=set)
    """Constants the initial set gives a range (their interval stays in ``bounds``)."""
    notes: list[str] = field(default_factory=list)


@dataclass
class ForbiddenEntry:
    locations: dict[int, str]
    when: str | None
    positions: dict[int, Position] = field(default_factory=dict)




def _affine(node: sx.Node, resolve: Callable[[str, Position], str]) -> Affine | None:
    """:func:`affine_form` in an unprimed variable (named by ``resolve``)."""

    def leaf(n: sx.Node) -> Affine | None:
        if isinstance(n, sx.Num):
            return None, 0.0, n.value
        if isinstance(n, sx.Name) and not n.primed:
            return resolve(n.name, n.position), 1.0, 0.0
        return None

    return affine_form(node, leaf)


def _squares(
    node: sx.Node, resolve: Callable[[str, Position], str]
) -> tuple[list[tuple[str, float, float, float]], float] | None:
    """``sum w * (a x + b)^2 + k`` as ``([(x, a, b, w)], k)``, else ``None``."""
    if isinstance(node, sx.BinOp) and node.op in "+-":
        left = _squares(node.left, resolve)
        right = _squares(node.right, resolve)
        if left is None or right is None:
            return None
        if node.op == "-":
            if right[0]:
                return None
            return left[0], left[1] - right[1]
        return left[0] + right[0], left[1] + right[1]
    if isinstance(node, sx.BinOp) and node.op == "^" and constant_value(node.right, {}) == 2.0:
        base = _affine(node.left, resolve)
        if base is None or base[0] is None:
            return None
        return [(base[0], base[1], base[2], 1.0)], 0.0
    if isinstance(node, sx.BinOp) and node.op in "*/":
        left_k, right_k = constant_value(node.left, {}), constant_value(node.right, {})
        if node.op == "/":
            k, inner = (1.0 / right_k if right_k else None), node.left
        elif left_k is not None:
            k, inner = left_k, node.right
        else:
            k, inner = right_k, node.left
        if k is None or k <= 0:
            return None
        found = _squares(inner, resolve)
        if found is None or found[1] != 0.0:
            return None
        return [(x, a, b, w * k) for x, a, b, w in found[0]], 0.0
    value = constant_value(node, {})
    return ([], value) if value is not None else None


def _narrow(init: InitialSet, var: str, lo: float, hi: float, where: Position) -> None:
    old_lo, old_hi = init.bounds.get(var, (-math.inf, math.inf))
    lo, hi = max(lo, old_lo) + 0.0, min(hi, old_hi) + 0.0  # no -0.0
    if lo > hi:
        raise SpecError(f"the initial set is empty: no value of '{var}' fits", where)
    init.bounds[var] = (lo, hi)


def _pair(
    init: InitialSet, a: sx.Node, op: str, b: sx.Node, resolve: Callable[[str, Position], str]
) -> bool:
    """Narrow ``init`` by ``a op b`` if it is a bound on one variable; ``False`` if not."""
    left, right = _affine(a, resolve), _affine(b, resolve)
    if left is None or right is None:
        return False
    var = left[0] or right[0]
    if left[0] and right[0] and left[0] != right[0]:
        return False
    coef, const = left[1] - right[1], right[2] - left[2]  # coef * x  op  const
    if var is None or coef == 0:
        return True  # a comparison of numbers: nothing to narrow
    if op == "!=":
        return False
    value = const / coef
    if coef < 0:
        op = {"<=": ">=", "<": ">", ">=": "<=", ">": "<"}.get(op, op)
    if op in ("<=", "<"):
        _narrow(init, var, -math.inf, value, a.position)
    elif op in (">=", ">"):
        _narrow(init, var, value, math.inf, a.position)
    else:
        _narrow(init, var, value, value, a.position)
    return True


def _ellipse(
    init: InitialSet, item: sx.Cmp, resolve: Callable[[str, Position], str], source: str
) -> bool:
    if len(item.ops) != 1 or item.ops[0] not in ("<=", "<", ">=", ">"):
        return False
    lhs, rhs = item.operands
    if item.ops[0] in (">=", ">"):
        lhs, rhs = rhs, lhs
    squares = _squares(lhs, resolve)
    limit = constant_value(rhs, {})
    if squares is None or limit is None or not squares[0]:
        return False
    terms, offset = squares
    radius2 = limit - offset
    if radius2 < 0 or len({t[0] for t in terms}) != len(terms):
        return False
    for var, a, b, w in terms:
        half = math.sqrt(radius2 / w) / abs(a)
        centre = -b / a
        _narrow(init, var, centre - half, centre + half, item.position)
        init.nominal[var] = centre
        init.exact[var] = source
    return True


def initial_set(text: SourceText, resolver: Resolver, open_constants: set[str]) -> InitialSet:
    """Read ``initially`` (see the module docstring)."""
    tree = sx.parse(text)
    if not isinstance(tree, sx.Or):
        return _conjunction(tree, text, resolver, open_constants)
    parts = [_conjunction(item, text, resolver, open_constants) for item in tree.items]
    return _union(parts, tree.items, tree.position)


def _union(parts: list[InitialSet], items: tuple[sx.Node, ...], where: Position) -> InitialSet:
    """A union of conjunctions that differ only in their locations: several initial locations.

    The union must be the same box in every part, and its locations a product
    of one set of locations per component (``loc(a)==p | loc(a)==n``), which is
    exactly "each component starts in one of its initial locations".
    """
    first = parts[0]
    for part, item in zip(parts, items, strict=True):
        if (part.bounds, part.nominal, part.constants, part.ranged) != (
            first.bounds,
            first.nominal,
            first.constants,
            first.ranged,
        ) or set(part.locations) != set(first.locations):
            raise SpecError(
                "an initial set with '|' (a union) has a counterpart only when its parts are "
                "one box in different locations (several initial locations); these parts differ "
                "in their variables: keep one of them",
                item.position,
            )
    leaves = sorted(first.locations)
    choices = {i: list(dict.fromkeys(p.locations[i] for p in parts)) for i in leaves}
    given = {tuple(p.locations[i] for i in leaves) for p in parts}
    if given != set(itertools.product(*(choices[i] for i in leaves))):
        raise SpecError(
            "the parts of this union start the components in combinations of locations, not in "
            "every combination of each one's initial locations (our initial locations are per "
            "component): write every combination, or keep one part",
            where,
        )
    first.alternatives = {i: c for i, c in choices.items() if len(c) > 1}
    for part in parts[1:]:
        first.location_positions.update(
            {i: w for i, w in part.location_positions.items() if i not in first.location_positions}
        )
    return first


def _conjunction(
    tree: sx.Node, text: SourceText, resolver: Resolver, open_constants: set[str]
) -> InitialSet:
    """One conjunction of ``initially``."""
    init = InitialSet()

    def resolve(name: str, where: Position) -> str:
        try:
            return resolver.variable(name)
        except KeyError as exc:
            raise SpecError(str(exc.args[0]), where) from None

    for item in sx.conjuncts(tree):
        if isinstance(item, sx.Or):
            raise SpecError(
                "a union ('|') inside a conjunction of the initial set: write the initial set "
                "as a union of conjunctions (A & B | A & C)",
                item.position,
            )
        if isinstance(item, sx.Cmp) and item.ops == ("==",) and _location(item) is not None:
            comp, loc, where = _location(item)  # type: ignore[misc]
            index = resolver.leaf(comp, where)
            if index in init.locations and init.locations[index] != loc:
                raise SpecError("the initial set names two locations of one component", where)
            init.locations[index] = loc
            init.location_positions[index] = where
            continue
        if isinstance(item, sx.Cmp):
            if all(_pair(init, a, op, b, resolve) for op, a, b in _pairs(item)):
                continue
            written = text.text[_offset(text, item.position) :].split("&")[0].strip()
            if _ellipse(init, item, resolve, written):
                init.notes.append(
                    f"the initial set '{written}' is not a box: its bounding box is used, with "
                    "the centre as nominal point; check reasons over the box (sound for proving "
                    "forbidden states unreachable; a witness may start outside the set)"
                )
                continue
        if isinstance(item, sx.Bool) and item.value:
            continue
        raise SpecError(
            "this part of the initial set is neither a bound on one variable, nor loc(...) == "
            "name, nor an axis-aligned ellipse; our initial sets are boxes: write bounds such as "
            "lo <= x & x <= hi instead (for instance the set's bounding box)",
            item.position,
        )
    for name in list(init.bounds):
        if name in open_constants:
            lo, hi = init.bounds[name]
            if lo != hi:
                if not (math.isfinite(lo) and math.isfinite(hi)):
                    raise SpecError(
                        f"constant '{name}' must be given one value (c == number) or a bounded "
                        "range (lo <= c & c <= hi)",
                        text.where(0),
                    )
                init.ranged.add(name)
                continue
            del init.bounds[name]
            init.constants[name] = lo
    return init


def _pairs(item: sx.Cmp) -> list[tuple[str, sx.Node, sx.Node]]:
    return [
        (op, a, b) for op, a, b in zip(item.ops, item.operands, item.operands[1:], strict=False)
    ]


def _offset(text: SourceText, where: Position) -> int:
    for i in range(len(text.text)):
        if text.where(i) == where:
            return i
    return 0


def _location(item: sx.Cmp) -> tuple[str, str, Position] | None:
    a, b = item.operands
    if isinstance(b, sx.Loc):
        a, b = b, a
    if isinstance(a, sx.Loc) and isinstance(b, sx.Name) and not b.primed:
        return a.component, b.name, a.position
    return None


def forbidden_set(
    text: SourceText, resolver: Resolver, rename: Callable[[str], str]
) -> list[ForbiddenEntry]:
    """Read ``forbidden``: one entry per disjunct (``rename``: variable id -> our name)."""
    tree = sx.parse(text)
    parts = tree.items if isinstance(tree, sx.Or) else (tree,)
    entries: list[ForbiddenEntry] = []

    def name(n: str) -> str:
        return rename(resolver.variable(n))

    for part in parts:
        if not sx.conjuncts(part):
            continue  # forbidden = "" (or true): no entry of its own
        locations: dict[int, str] = {}
        positions: dict[int, Position] = {}
        rest: list[sx.Node] = []
        for item in sx.conjuncts(part):
            found = _location(item) if isinstance(item, sx.Cmp) and item.ops == ("==",) else None
            if found is None:
                rest.append(item)
                continue
            index = resolver.leaf(found[0], found[2])
            if index in locations and locations[index] != found[1]:
                raise SpecError(
                    "this part of the forbidden set names two locations of one component", found[2]
                )
            locations[index] = found[1]
            positions[index] = found[2]
        when = condition_text(sx.And(tuple(rest), part.position), name) if rest else None
        entries.append(ForbiddenEntry(locations, when, positions))
    return entries
