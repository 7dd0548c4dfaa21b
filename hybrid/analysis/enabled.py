"""Where the simulator may find a guard enabled, and where it surely does.

The slope test of the simulator (docs/semantics.md) finds a guard enabled where
it holds, on the boundary of a strict comparison the flow enters, and not on
the boundary of a non-strict one the flow leaves; an equality level counts
where it is *reached*: from the side the state is on while flowing, and on
entry only where the flow keeps the state on it. :func:`enabled_region`
over-approximates the points where a guard may be found enabled (for the
"never" proofs: dead edges, unreachable locations, zero-time cycles);
:func:`surely_enabled_at_entry` under-approximates those where it surely is
(for the proof that a location cannot be entered with nothing enabled).
docs/check.md states both.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

from hybrid.analysis.flows import derivative
from hybrid.analysis.linear import structural_key
from hybrid.analysis.solve import Box, Env, closure, conjoin, dnf, satisfiable
from hybrid.expr import ir

__all__ = [
    "Side",
    "enabled_region",
    "invariant_side",
    "split_levels",
    "surely_enabled_at_entry",
]

_ZERO = ir.Num(0.0)


def _is(node: ir.Expr, value: float) -> bool:
    return isinstance(node, ir.Num) and node.value == value


def _sub(a: ir.Expr, b: ir.Expr) -> ir.Expr:
    if _is(b, 0.0):
        return a
    if _is(a, 0.0):
        return ir.Unary("-", b)
    return ir.Bin("-", a, b)


def _folded(rate: ir.Expr | None) -> ir.Expr | None:
    """``-c`` as the number ``-c``."""
    if isinstance(rate, ir.Unary) and rate.op == "-" and isinstance(rate.operand, ir.Num):
        return ir.Num(-rate.operand.value)
    return rate


Side = Callable[[ir.Expr], int]
"""``side(d)``: ``1`` if the state keeps ``d >= 0`` while flowing, ``-1`` if ``d <= 0``, else 0."""


def split_levels(term: tuple[ir.Cmp, ...]) -> tuple[list[ir.Cmp], list[ir.Cmp]]:
    """The equality atoms of a conjunction, as ``a == b``, and its other comparisons.

    An equality atom is an ``a == b``, or a pair ``a <= b``, ``a >= b`` (in either
    spelling) of the same two sides, as the simulator reads them
    (:func:`hybrid.expr.rho.levels`).

    Examples
    --------
    >>> from hybrid.expr.parse import Scope, parse_expression
    >>> from hybrid.expr.printer import to_source
    >>> from hybrid.analysis.solve import dnf
    >>> g = parse_expression("0 >= x and y > 1 and x >= 0", Scope({"x": "state", "y": "state"}), want="bool")
    >>> levels, others = split_levels(dnf(g)[0])
    >>> [to_source(a, {"x": "x", "y": "y"}) for a in levels + others]
    ['x == 0.0', 'y > 1.0']
    """
    levels: list[ir.Cmp] = []
    others: list[ir.Cmp] = []
    pending: dict[tuple[object, object], int] = {}
    used: set[int] = set()
    for i, atom in enumerate(term):
        op = atom.ops[0]
        if op == "==":
            levels.append(atom)
            used.add(i)
            continue
        if op not in ("<=", ">="):
            continue
        low, high = atom.operands if op == "<=" else reversed(atom.operands)
        key = (structural_key(low), structural_key(high))
        partner = pending.pop((key[1], key[0]), None)
        if partner is not None:
            levels.append(ir.Cmp(("==",), (high, low), atom.col))
            used.update((i, partner))
        else:
            pending.setdefault(key, i)
    others = [atom for i, atom in enumerate(term) if i not in used]
    return levels, others


def _level_rate(
    atom: ir.Cmp,
    flow: Mapping[str, ir.Expr],
    signals: Mapping[str, ir.Expr],
    opaque: frozenset[str],
) -> tuple[ir.Expr, ir.Expr | None]:
    """``(a - b, d(a - b)/dt)`` of an equality atom ``a == b`` (the rate ``None`` if unknown)."""
    lhs, rhs = atom.operands
    difference = _sub(lhs, rhs)
    return difference, _folded(derivative(difference, flow, signals, opaque))


def _atom_regions(
    atom: ir.Cmp,
    flow: Mapping[str, ir.Expr],
    signals: Mapping[str, ir.Expr],
    opaque: frozenset[str],
) -> tuple[ir.Expr, ir.Expr]:
    """Where ``a < b`` / ``a <= b`` (either spelling) may count for the slope test.

    ``(holding, entering)``: *holding* is the comparison itself, except that a
    non-strict one on its boundary counts only where the flow does not leave
    it (``d(a - b)/dt <= 0``: a state that moves away is disarmed); *entering*
    is ``a < b``, or ``a == b`` with the flow entering (``d(a - b)/dt < 0``).
    Where the derivative cannot be formed, the boundary counts whole.
    """
    op = atom.ops[0]
    lhs, rhs = atom.operands
    small, large = (lhs, rhs) if op in ("<", "<=") else (rhs, lhs)
    inside = ir.Cmp(("<",), (small, large), atom.col)
    rate = _folded(derivative(_sub(small, large), flow, signals, opaque))
    face = ir.Cmp(("==",), (lhs, rhs), atom.col)
    strict = op in ("<", ">")
    if rate is None:
        return atom, ir.Cmp(("<=",), (small, large), atom.col)
    if isinstance(rate, ir.Num):
        entering: ir.Expr = ir.BoolOp("or", (inside, face)) if rate.value < 0 else inside
        holding: ir.Expr = atom if strict or rate.value <= 0 else inside
        return holding, entering
    entering = ir.BoolOp("or", (inside, conjoin(face, ir.Cmp(("<",), (rate, _ZERO)))))
    if strict:
        return atom, entering
    return ir.BoolOp("or", (inside, conjoin(face, ir.Cmp(("<=",), (rate, _ZERO))))), entering


def enabled_region(
    guard: ir.Expr,
    flow: Mapping[str, ir.Expr],
    signals: Mapping[str, ir.Expr] | None = None,
    opaque: frozenset[str] = frozenset(),
    *,
    side: Side | None = None,
    entry: bool = False,
    snapped: bool = False,
) -> ir.Expr:
    """A condition holding at every point where the simulator may find ``guard`` enabled.

    The simulator (docs/semantics.md, the slope test) finds a guard enabled
    where it holds, and also on its boundary when the flow enters it: the
    first instant of ``x > 5`` is ``x == 5`` with ``x' > 0``; and not on the
    boundary of ``x >= 5`` when the flow leaves it. So each conjunction of the
    guard's normal form counts where it holds, its non-strict comparisons ``a <=
    b`` on their boundary only where ``d(a - b)/dt <= 0``; or where each of its
    comparisons holds strictly or sits on its boundary with ``d(a - b)/dt < 0``
    (anywhere on the boundary where the derivative cannot be formed).

    An equality atom (``a == b``, or ``a <= b and a >= b``) counts on its level,
    and where the rate ``d' = d(a - b)/dt`` can be formed, only where:

    - ``entry``: at an entry point (or where a stay starts) the flow keeps the
      state on the level, ``d' == 0``: a state that starts on the level and
      leaves it has not reached it; with ``snapped`` too, anywhere on the level
      (an entry at the instant the last stay stopped, where a level that stay
      reached and no jump has used is snapped: docs/semantics.md);
    - ``side`` given, while flowing: the level is reached from the side the
      state is on. Where the state keeps ``d >= 0`` while flowing (``side(d) ==
      1``: the closure of the invariant implies it), the level is reached with
      ``d' <= 0``; where it keeps ``d <= 0``, with ``d' >= 0``.

    Beyond the normal-form cap the closure of the guard is returned.

    Examples
    --------
    >>> from hybrid.expr.parse import Scope, parse_expression
    >>> from hybrid.expr.printer import to_source
    >>> scope = Scope({"x": "state", "y": "state"})
    >>> names = {"x": "x", "y": "y"}
    >>> g = parse_expression("x > 5", scope, want="bool")
    >>> to_source(enabled_region(g, {"x": ir.Num(1.0)}), names)
    'x > 5.0 or (5.0 < x or x == 5.0)'
    >>> to_source(enabled_region(g, {"x": ir.Num(-1.0)}), names)
    'x > 5.0 or 5.0 < x'
    >>> level = parse_expression("x == 0", scope, want="bool")
    >>> circle = {"x": ir.Var("y", "state"), "y": ir.Unary("-", ir.Var("x", "state"))}
    >>> to_source(enabled_region(level, circle, side=lambda d: 1), names)
    'x == 0.0 and y <= 0.0'
    >>> to_source(enabled_region(level, circle, entry=True), names)
    'x == 0.0 and y == 0.0'
    >>> to_source(enabled_region(level, circle, entry=True, snapped=True), names)
    'x == 0.0'
    """
    signals = signals or {}
    terms = dnf(guard)
    if terms is None:
        return closure(guard)
    parts: list[ir.Expr] = []
    for term in terms:
        if not term:
            return ir.BoolConst(True)
        levels, others = split_levels(term)
        conds: list[ir.Expr] = []
        for atom in levels:
            conds.append(atom)
            difference, rate = _level_rate(atom, flow, signals, opaque)
            if rate is None:
                continue
            if entry:
                if not snapped:
                    conds.append(ir.Cmp(("==",), (rate, _ZERO)))
            elif side is not None and (way := side(difference)) != 0:
                conds.append(ir.Cmp(("<=",) if way > 0 else (">=",), (rate, _ZERO)))
        regions = [_atom_regions(atom, flow, signals, opaque) for atom in others]
        holding = conjoin(*(h for h, _ in regions))
        entering = conjoin(*(e for _, e in regions))
        either: ir.Expr = holding
        if structural_key(holding) != structural_key(entering):
            either = ir.BoolOp("or", (holding, entering))
        parts.append(conjoin(*conds, either))
    if not parts:
        return ir.BoolConst(False)
    return parts[0] if len(parts) == 1 else ir.BoolOp("or", tuple(parts))


def surely_enabled_at_entry(
    guard: ir.Expr,
    flow: Mapping[str, ir.Expr],
    signals: Mapping[str, ir.Expr] | None = None,
    opaque: frozenset[str] = frozenset(),
    *,
    snapped: bool = False,
) -> ir.Expr:
    """A condition under which the simulator surely finds ``guard`` enabled at an entry point.

    By the slope test, a conjunction of the guard's normal form is enabled where
    each comparison holds strictly or sits on its boundary with the flow
    entering (``d(a - b)/dt < 0``); or where its strict comparisons hold
    strictly and its non-strict ones and its equality atoms sit on their
    boundary with the flow entering or keeping them there (``d(a - b)/dt ==
    0``, trusted only for a difference affine in the state: a zero first
    derivative of ``x**2 - y`` may hide a state that leaves at once). Its
    negation holds wherever the guard may *not* be enabled on entry.

    ``snapped``: at a point where the search stopped instead (an exit of the
    invariant while flowing), where the equality atoms of an armed guard hold
    on their level whatever the flow does there.

    Examples
    --------
    >>> from hybrid.expr.parse import Scope, parse_expression
    >>> from hybrid.expr.printer import to_source
    >>> scope = Scope({"x": "state", "y": "state"})
    >>> names = {"x": "x", "y": "y"}
    >>> circle = {"x": ir.Var("y", "state"), "y": ir.Unary("-", ir.Var("x", "state"))}
    >>> level = parse_expression("x == 0", scope, want="bool")
    >>> to_source(surely_enabled_at_entry(level, circle), names)
    'x == 0.0 and y == 0.0'
    >>> to_source(surely_enabled_at_entry(level, circle, snapped=True), names)
    'x == 0.0'
    >>> to_source(surely_enabled_at_entry(parse_expression("y < 1", scope, want="bool"), circle), names)
    '(y < 1.0 or y == 1.0 and -x < 0.0) or y < 1.0'
    """
    signals = signals or {}
    terms = dnf(guard)
    if terms is None:
        return ir.BoolConst(False)
    parts: list[ir.Expr] = []
    for term in terms:
        levels, others = split_levels(term)
        on_level: list[ir.Expr] = []
        for atom in levels:
            on_level.append(atom)
            if snapped:
                continue
            difference, rate = _level_rate(atom, flow, signals, opaque)
            if rate is None or not _affine(difference):
                break
            on_level.append(ir.Cmp(("==",), (rate, _ZERO)))
        else:
            regions = [_surely(atom, flow, signals, opaque) for atom in others]
            entering = conjoin(*on_level, *(into for into, _ in regions))
            sitting = conjoin(*on_level, *(still for _, still in regions))
            # a level sitting still (rate 0) makes the slope 0: then only the boolean form
            # decides, and a strict comparison on its boundary does not hold
            if (snapped or not levels) and structural_key(entering) != structural_key(sitting):
                parts.append(entering)
            parts.append(sitting)
    if not parts:
        return ir.BoolConst(False)
    return parts[0] if len(parts) == 1 else ir.BoolOp("or", tuple(parts))


def _surely(
    atom: ir.Cmp,
    flow: Mapping[str, ir.Expr],
    signals: Mapping[str, ir.Expr],
    opaque: frozenset[str],
) -> tuple[ir.Expr, ir.Expr]:
    """Where ``a < b`` / ``a <= b`` surely counts: ``(entering, sitting)``.

    *entering*: it holds strictly, or sits on its boundary with ``d(a - b)/dt < 0``;
    *sitting*: a strict one holds strictly, a non-strict one holds strictly or sits
    on its boundary with ``d(a - b)/dt <= 0`` (a zero rate trusted only for an
    affine ``a - b``). A rate that is a number is decided here.
    """
    op = atom.ops[0]
    lhs, rhs = atom.operands
    small, large = (lhs, rhs) if op in ("<", "<=") else (rhs, lhs)
    difference = _sub(small, large)
    inside = ir.Cmp(("<",), (small, large), atom.col)
    at_most = ir.Cmp(("<=",), (small, large), atom.col)
    strict = op in ("<", ">")
    rate = _folded(derivative(difference, flow, signals, opaque))
    if rate is None:
        return inside, inside
    if isinstance(rate, ir.Num):
        into = at_most if rate.value < 0 else inside
        keeps = rate.value < 0 or (rate.value == 0 and _affine(difference))
        return into, inside if strict or not keeps else at_most
    face = ir.Cmp(("==",), (small, large), atom.col)
    entering: ir.Expr = ir.BoolOp("or", (inside, conjoin(face, ir.Cmp(("<",), (rate, _ZERO)))))
    if strict:
        return entering, inside
    if not _affine(difference):
        return entering, entering
    return entering, ir.BoolOp("or", (inside, conjoin(face, ir.Cmp(("<=",), (rate, _ZERO)))))


def _affine(node: ir.Expr) -> bool:
    """Whether ``node`` is affine in the state: sums, differences and constant multiples."""
    if isinstance(node, ir.Num):
        return True
    if isinstance(node, ir.Var):
        return node.kind in (ir.STATE, ir.TIME, ir.PARAM, ir.CONST)
    if isinstance(node, ir.Unary):
        return _affine(node.operand)
    if isinstance(node, ir.Bin):
        if node.op in ("+", "-"):
            return _affine(node.left) and _affine(node.right)
        if node.op == "*":
            return (isinstance(node.left, ir.Num) and _affine(node.right)) or (
                isinstance(node.right, ir.Num) and _affine(node.left)
            )
        if node.op == "/":
            return isinstance(node.right, ir.Num) and _affine(node.left)
    return False


def invariant_side(closed: ir.Expr, env: Env, region: Box | None) -> Side:
    """Which side of ``d == 0`` the state keeps while flowing in a location.

    ``closed`` is the closure of the location's invariant and ``region`` the box
    it leaves of the bounds. ``side(d)`` is ``1`` when ``closed and d < 0``
    cannot hold in ``region`` (a proof), ``-1`` when ``closed and d > 0`` cannot,
    else 0.

    Examples
    --------
    >>> from hybrid.expr.parse import Scope, parse_expression
    >>> from hybrid.expr.interval import Interval
    >>> scope = Scope({"x": "state"})
    >>> side = invariant_side(parse_expression("x >= 0", scope, want="bool"), Env(), {"x": Interval(0.0, 5.0)})
    >>> x = ir.Var("x", "state")
    >>> side(x), side(ir.Unary("-", x)), side(ir.Bin("-", x, ir.Num(1.0)))
    (1, -1, 0)
    """

    def side(difference: ir.Expr) -> int:
        if region is None:
            return 0
        for way, op in ((1, "<"), (-1, ">")):
            beyond = ir.Cmp((op,), (difference, _ZERO))
            if not satisfiable(conjoin(closed, beyond), env, region):
                return way
        return 0

    return side
