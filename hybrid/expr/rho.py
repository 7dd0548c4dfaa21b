"""Guards as real-valued functions: ``rho <= 0`` exactly when the guard holds.

The rewrite (DESIGN.md): ``a <= b`` and ``a < b`` become ``a - b``;
``a >= b`` and ``a > b`` become ``b - a``; ``a == b`` becomes ``|a - b|``;
``a != b`` becomes ``-|a - b|``; ``and`` is ``max``, ``or`` is ``min``, ``not``
negates; ``true`` is -1 and ``false`` is +1, and so is a comparison that cannot
change (two numbers, ``0 >= 0``, or one expression on both sides, ``x < x``),
whose ``a - b`` would otherwise sit at 0. Away from ``rho = 0`` the sign of
rho decides the guard. On ``rho = 0`` the boolean form decides: a non-strict
comparison (``<=``, ``>=``, ``==``) holds on its boundary, a strict one
(``<``, ``>``, ``!=``) does not. The simulator uses rho for root finding and
the boolean form to decide a guard that sits exactly on its boundary.

**Levels.** An equality in a guard (``a == b``, or ``a >= b and a <= b``, or
``b <= a <= b``) holds only at isolated instants, so its rho ``|a - b|``
never changes sign and a root finder cannot see it. :func:`levels` lists such
equality atoms (their differences ``a - b``, in a fixed order);
:func:`oriented_rho` writes the guard with atom ``i`` as the one-sided
``sign_i * (a - b) <= 0``, which becomes true when the level is reached from
the side ``sign_i`` (``sign_i = 0``, a state exactly on the level: the atom
itself); :func:`snapped` replaces atom ``i`` by a constant (true
when the point is at the level). The simulator watches the oriented form and
decides the snapped one (docs/semantics.md, "Equality guards").

**On the band.** A point an event search found is on a boundary only up to
rounding, so a guard that *sits* there (rho within the band of 0 and not
moving) is not decided by the sign of a rounding error: :func:`within_band`
writes the guard with each comparison whose two sides differ by at most a
width decided as on its boundary (``<=``, ``>=``, ``==`` hold; ``<``, ``>``,
``!=`` do not). With width 0 it is the guard itself.

Examples
--------
>>> from hybrid.expr.parse import Scope, parse_expression
>>> from hybrid.expr.printer import to_source
>>> g = parse_expression("h <= 0 and v < 0", Scope({"h": "state", "v": "state"}), want="bool")
>>> to_source(guard_to_rho(g), {"h": "h", "v": "v"})
'_max(h, v)'
>>> e = parse_expression("x >= 1 and x <= 1 and v > 0", Scope({"x": "state", "v": "state"}), want="bool")
>>> [to_source(d, {"x": "x"}) for d in levels(e)]
['1.0 - x']
>>> to_source(oriented_rho(e, (-1,)), {"x": "x", "v": "v"})
'_max(x - 1.0, -v)'
>>> w = ir.Var("w", ir.PARAM)
>>> to_source(within_band(g, w), {"h": "h", "v": "v", "w": "w"})
'h <= w and v < -w'
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from hybrid.expr import ir

__all__ = [
    "BAND",
    "guard_to_rho",
    "is_strict",
    "level_key",
    "levels",
    "oriented_rho",
    "snapped",
    "structural_key",
    "within_band",
]

BAND = 1e-10
"""The simulator's band per unit of the state's largest magnitude: a rho within
``BAND * (1 + max |x|)`` of 0 counts as on its boundary (docs/semantics.md); the
analysis and reach allow for it where they speak of what a run does."""


def guard_to_rho(node: ir.Expr) -> ir.Expr:
    """The rho expression of a boolean guard or invariant."""
    if isinstance(node, ir.BoolConst):
        return ir.Num(-1.0 if node.value else 1.0, node.col)
    if isinstance(node, ir.Not):
        return _negate(guard_to_rho(node.operand))
    if isinstance(node, ir.BoolOp):
        parts = tuple(guard_to_rho(v) for v in node.values)
        return ir.Call("max" if node.op == "and" else "min", parts, node.col)
    if isinstance(node, ir.Cmp):
        pairs = [
            _comparison(op, node.operands[i], node.operands[i + 1], node.col)
            for i, op in enumerate(node.ops)
        ]
        return pairs[0] if len(pairs) == 1 else ir.Call("max", tuple(pairs), node.col)
    raise TypeError(f"not a condition: {node!r}")


def is_strict(node: ir.Expr) -> bool:
    """True if ``node`` is a single strict comparison (``<``, ``>``, ``!=``)."""
    return isinstance(node, ir.Cmp) and len(node.ops) == 1 and node.ops[0] in ("<", ">", "!=")


_HOLDS = {
    "<": lambda a, b: a < b,
    "<=": lambda a, b: a <= b,
    ">": lambda a, b: a > b,
    ">=": lambda a, b: a >= b,
    "==": lambda a, b: a == b,
    "!=": lambda a, b: a != b,
}


def _constant(op: str, a: ir.Expr, b: ir.Expr) -> bool | None:
    """The value of ``a op b`` if it cannot change (two numbers, or one expression twice)."""
    if isinstance(a, ir.Num) and isinstance(b, ir.Num):
        return bool(_HOLDS[op](a.value, b.value))
    if structural_key(a) == structural_key(b):
        return op in ("<=", ">=", "==")
    return None


def _comparison(op: str, a: ir.Expr, b: ir.Expr, col: int) -> ir.Expr:
    fixed = _constant(op, a, b)
    if fixed is not None:  # no boundary to reach: the rho of `true` / `false`
        return ir.Num(-1.0 if fixed else 1.0, col)
    if op in ("<", "<="):
        return _sub(a, b, col)
    if op in (">", ">="):
        return _sub(b, a, col)
    diff = ir.Call("abs", (_sub(a, b, col),), col)
    return diff if op == "==" else ir.Unary("-", diff, col)


def _sub(a: ir.Expr, b: ir.Expr, col: int) -> ir.Expr:
    if isinstance(b, ir.Num) and b.value == 0.0:
        return a
    if isinstance(a, ir.Num) and a.value == 0.0:
        return ir.Unary("-", b, col)
    return ir.Bin("-", a, b, col)


def _negate(node: ir.Expr) -> ir.Expr:
    if isinstance(node, ir.Unary):
        return node.operand
    if isinstance(node, ir.Num):
        return ir.Num(-node.value, node.col)
    return ir.Unary("-", node, node.col)


# --- equality levels -------------------------------------------------------------------


def structural_key(node: ir.Expr) -> tuple[object, ...]:
    """A key equal for two expressions exactly when they are the same tree (columns ignored)."""
    if isinstance(node, ir.Num | ir.BoolConst):
        return (type(node).__name__, node.value)
    if isinstance(node, ir.Var):
        return ("Var", node.name, node.kind)
    if isinstance(node, ir.Index):
        return ("Index", node.name, node.index)
    if isinstance(node, ir.Call):
        return ("Call", node.func, *map(structural_key, node.args))
    if isinstance(node, ir.Unary):
        return ("Unary", node.op, structural_key(node.operand))
    if isinstance(node, ir.Bin):
        return ("Bin", node.op, structural_key(node.left), structural_key(node.right))
    if isinstance(node, ir.Cmp):
        return ("Cmp", node.ops, *map(structural_key, node.operands))
    if isinstance(node, ir.BoolOp):
        return ("BoolOp", node.op, *map(structural_key, node.values))
    return ("Not", structural_key(node.operand))


Replacement = Callable[[int, ir.Expr, int], ir.Expr]
"""``(index, difference, column) -> boolean node`` that stands for level atom ``index``."""


def level_key(difference: ir.Expr, owners: Sequence[int]) -> str:
    """Which level the atom ``difference`` (of :func:`levels`) of a transition of ``owners``
    (component numbers) is: the owners and the variables it reads, parameters aside.

    Atoms of one component over the same variables at their levels at one point
    are one level reached (``x == b`` and ``x == c`` at ``x = 0.5`` with ``b = c``);
    the simulator's rule "a level reached at an instant is used by the jump whose
    guard reads it" (docs/semantics.md) needs that identity, the same whether the
    parameters are bound to numbers or are slots.

    >>> level_key(ir.Bin("-", ir.Var("x", ir.STATE), ir.Var("b", ir.PARAM)), (1,))
    '1:x'
    """
    skip = ir.names_in(difference, ir.PARAM) | ir.names_in(difference, ir.CONST)
    names = sorted(ir.names_in(difference) - skip)
    return ",".join(map(str, owners)) + ":" + ",".join(names)


def levels(node: ir.Expr) -> tuple[ir.Expr, ...]:
    """The differences ``a - b`` of the equality atoms of a guard, in a fixed order.

    Only atoms that must hold for the guard to hold count (an ``==`` under an even
    number of ``not``, a ``!=`` under an odd number); ``a >= b and a <= b`` (in
    either spelling, or as the chain ``b <= a <= b``) is one atom.
    """
    found: list[ir.Expr] = []

    def record(index: int, difference: ir.Expr, col: int) -> ir.Expr:
        found.append(difference)
        return ir.BoolConst(True, col)

    _rewrite(node, record, True, [0])
    return tuple(found)


def oriented_rho(node: ir.Expr, signs: Sequence[int]) -> ir.Expr:
    """Rho of the guard with level atom ``i`` read as ``signs[i] * (a - b) <= 0`` (``a == b`` if 0)."""

    def one_sided(index: int, difference: ir.Expr, col: int) -> ir.Expr:
        if signs[index] == 0:  # on the level: the atom itself, true while the state stays there
            return ir.Cmp(("==",), (difference, ir.Num(0.0, col)), col)
        side = difference if signs[index] > 0 else _opposite(difference)
        return ir.Cmp(("<=",), (side, ir.Num(0.0, col)), col)

    return guard_to_rho(_rewrite(node, one_sided, True, [0]))


def snapped(node: ir.Expr, at_level: Sequence[bool]) -> ir.Expr:
    """The guard with level atom ``i`` replaced by the constant ``at_level[i]``."""

    def constant(index: int, difference: ir.Expr, col: int) -> ir.Expr:
        return ir.BoolConst(bool(at_level[index]), col)

    return _rewrite(node, constant, True, [0])


def within_band(node: ir.Expr, width: ir.Expr) -> ir.Expr:
    """The guard with each comparison ``a op b`` decided as on its boundary where
    ``|a - b| <= width``: ``a - b <= width`` for ``<=``, ``a - b < -width`` for
    ``<``, ``|a - b| <= width`` for ``==`` (and the mirror images).

    A comparison that cannot change (two numbers, one expression twice) stays as
    it is, as in :func:`guard_to_rho`. ``width`` is an expression the caller binds
    (the band at the point decided).
    """
    if isinstance(node, ir.Not):
        return ir.Not(within_band(node.operand, width), node.col)
    if isinstance(node, ir.BoolOp):
        return ir.BoolOp(node.op, tuple(within_band(v, width) for v in node.values), node.col)
    if not isinstance(node, ir.Cmp):
        return node
    links = [
        _widened(op, node.operands[i], node.operands[i + 1], width, node.col)
        for i, op in enumerate(node.ops)
    ]
    return links[0] if len(links) == 1 else ir.BoolOp("and", tuple(links), node.col)


def _widened(op: str, a: ir.Expr, b: ir.Expr, width: ir.Expr, col: int) -> ir.Expr:
    if _constant(op, a, b) is not None:
        return ir.Cmp((op,), (a, b), col)
    difference = _sub(a, b, col)
    if op in ("==", "!="):
        size = ir.Call("abs", (difference,), col)
        return ir.Cmp(("<=" if op == "==" else ">",), (size, width), col)
    # holds on the boundary: the far edge of the band; does not: the near edge
    edge = width if op in ("<=", ">") else ir.Unary("-", width, col)
    return ir.Cmp((op,), (difference, edge), col)


def _opposite(difference: ir.Expr) -> ir.Expr:
    """``b - a`` for ``a - b``."""
    if isinstance(difference, ir.Bin) and difference.op == "-":
        return ir.Bin("-", difference.right, difference.left, difference.col)
    return _negate(difference)


def _rewrite(
    node: ir.Expr | _Level, replace: Replacement, positive: bool, counter: list[int]
) -> ir.Expr:
    """``node`` with every level atom replaced (``counter`` numbers them in walk order)."""
    if isinstance(node, ir.Not):
        return ir.Not(_rewrite(node.operand, replace, not positive, counter), node.col)
    if isinstance(node, ir.BoolOp):
        values: list[ir.Expr | _Level] = list(node.values)
        if positive and node.op == "and":
            values = _fuse(node.values, node.col)
        rewritten = tuple(_rewrite(v, replace, positive, counter) for v in values)
        return rewritten[0] if len(rewritten) == 1 else ir.BoolOp(node.op, rewritten, node.col)
    if isinstance(node, _Level):
        return _atom(node.difference, replace, positive, counter, node.col)
    if isinstance(node, ir.Cmp):
        if len(node.ops) > 1:
            links: list[ir.Expr] = [
                ir.Cmp((op,), (node.operands[i], node.operands[i + 1]), node.col)
                for i, op in enumerate(node.ops)
            ]
            fused: list[ir.Expr | _Level] = _fuse(links, node.col) if positive else [*links]
            if any(isinstance(v, _Level) for v in fused) or any(
                op in ("==", "!=") for op in node.ops
            ):
                parts = tuple(_rewrite(v, replace, positive, counter) for v in fused)
                return parts[0] if len(parts) == 1 else ir.BoolOp("and", parts, node.col)
            return node
        op = node.ops[0]
        if (op == "==" and positive) or (op == "!=" and not positive):
            a, b = node.operands
            return _atom(_sub(a, b, node.col), replace, positive, counter, node.col)
    return node


def _atom(
    difference: ir.Expr, replace: Replacement, positive: bool, counter: list[int], col: int
) -> ir.Expr:
    index = counter[0]
    counter[0] += 1
    stand_in = replace(index, difference, col)
    return stand_in if positive else ir.Not(stand_in, col)


class _Level:
    """Two comparisons ``a <= b`` and ``a >= b`` of one ``and``, fused into one level atom."""

    __slots__ = ("col", "difference")

    def __init__(self, difference: ir.Expr, col: int) -> None:
        self.difference = difference
        self.col = col


def _bounds(node: ir.Expr) -> tuple[ir.Expr, ir.Expr] | None:
    """``(low, high)`` for a non-strict single comparison ``low <= high``, else None."""
    if isinstance(node, ir.Cmp) and len(node.ops) == 1 and node.ops[0] in ("<=", ">="):
        a, b = node.operands
        return (a, b) if node.ops[0] == "<=" else (b, a)
    return None


def _fuse(values: Sequence[ir.Expr], col: int) -> list[ir.Expr | _Level]:
    """``values`` of an ``and`` with each pair ``a <= b``, ``b <= a`` fused into a :class:`_Level`."""
    bounds = [_bounds(v) for v in values]
    keys = [None if b is None else (structural_key(b[0]), structural_key(b[1])) for b in bounds]
    result: list[ir.Expr | _Level] = []
    used: set[int] = set()
    for i, v in enumerate(values):
        pair, key = bounds[i], keys[i]
        if i in used:
            continue
        if pair is None or key is None:
            result.append(v)
            continue
        flipped = (key[1], key[0])
        partner = next(
            (j for j in range(i + 1, len(values)) if j not in used and keys[j] == flipped), None
        )
        if partner is None:
            result.append(v)
            continue
        used.add(partner)
        result.append(_Level(_sub(pair[0], pair[1], col), col))
    return result
