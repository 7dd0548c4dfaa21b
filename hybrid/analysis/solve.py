"""Deciding conditions over boxes: can a guard hold, can two guards hold at once?

A condition is first put in negation normal form (:func:`nnf`), then in
disjunctive normal form (:func:`dnf`, capped at :data:`DNF_CAP` conjunctions).
Each conjunction of comparisons is decided in three steps, each a proof when
it says "no":

1. interval evaluation of every comparison over the box;
2. contraction of the box by every comparison (linear ones narrow each of
   their variables; strictness is kept when the narrowed box is re-checked);
3. when some comparison links two or more variables, the linear program of
   :mod:`hybrid.analysis.linear` (non-affine terms become bounded unknowns).

Beyond the cap, or for anything not understood, the answer leans to
"may hold": a finding built on "cannot hold" is never a false alarm because of
an approximation here.

Examples
--------
>>> from hybrid.expr.parse import Scope, parse_expression
>>> from hybrid.expr.interval import Interval
>>> scope = Scope({"x": "state", "y": "state"})
>>> cond = lambda s: parse_expression(s, scope, want="bool")
>>> box = {"x": Interval(0.0, 10.0), "y": Interval(0.0, 10.0)}
>>> env = Env()
>>> satisfiable(cond("x + y >= 12 and x - y > 9"), env, box)
False
>>> contract(cond("x <= 3 or x >= 8"), env, box)["x"]
Interval(lo=0.0, hi=10.0)
>>> contract(cond("x <= 3 and y > 4"), env, box)
{'x': Interval(lo=0.0, hi=3.0), 'y': Interval(lo=4.0, hi=10.0)}
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field

from hybrid.analysis.linear import Linearizer, structural_key
from hybrid.analysis.lp import lp_feasible
from hybrid.expr import ir
from hybrid.expr.interval import ENTIRE, Interval
from hybrid.expr.ranges import IntervalEvaluator

__all__ = [
    "DNF_CAP",
    "Box",
    "Env",
    "closure",
    "conjoin",
    "contract",
    "dnf",
    "negate",
    "nnf",
    "satisfiable",
]

DNF_CAP = 64
Box = Mapping[str, Interval]
_TIME = Interval(0.0, math.inf)
_FLIP = {"<": ">=", "<=": ">", ">": "<=", ">=": "<", "==": "!=", "!=": "=="}
_TRUE = ir.BoolConst(True)
_FALSE = ir.BoolConst(False)


@dataclass(frozen=True)
class Env:
    """What names mean in one location: scalar signal definitions in force, opaque functions."""

    signals: Mapping[str, ir.Expr] = field(default_factory=dict)
    opaque: frozenset[str] = frozenset()
    cache: dict[tuple[object, ...], bool] = field(
        default_factory=dict, compare=False, hash=False, repr=False
    )
    boxes: dict[tuple[object, ...], dict[str, Interval] | None] = field(
        default_factory=dict, compare=False, hash=False, repr=False
    )

    def evaluator(self, box: Box) -> IntervalEvaluator:
        return IntervalEvaluator(box, self.signals, opaque=self.opaque)


def conjoin(*conds: ir.Expr) -> ir.Expr:
    """``a and b and ...`` (dropping ``true``; one operand is returned as is)."""
    parts = [c for c in conds if not (isinstance(c, ir.BoolConst) and c.value)]
    if not parts:
        return _TRUE
    return parts[0] if len(parts) == 1 else ir.BoolOp("and", tuple(parts))


def negate(node: ir.Expr) -> ir.Expr:
    """The negation of a condition, in negation normal form."""
    return nnf(node, negated=True)


def nnf(node: ir.Expr, *, negated: bool = False) -> ir.Expr:
    """Negation normal form: no ``not``; comparison chains split into single comparisons.

    Examples
    --------
    >>> from hybrid.expr.parse import Scope, parse_expression
    >>> from hybrid.expr.printer import to_source
    >>> g = parse_expression("not (x < 1 and 0 <= x <= 2)", Scope({"x": "state"}), want="bool")
    >>> to_source(nnf(g), {"x": "x"})
    'x >= 1.0 or 0.0 > x or x > 2.0'
    """
    if isinstance(node, ir.BoolConst):
        return ir.BoolConst(node.value != negated, node.col)
    if isinstance(node, ir.Not):
        return nnf(node.operand, negated=not negated)
    if isinstance(node, ir.BoolOp):
        op = node.op if not negated else ("or" if node.op == "and" else "and")
        values: list[ir.Expr] = []
        for v in node.values:
            part = nnf(v, negated=negated)
            if isinstance(part, ir.BoolOp) and part.op == op:
                values.extend(part.values)
            else:
                values.append(part)
        return ir.BoolOp(op, tuple(values), node.col)
    if isinstance(node, ir.Cmp):
        pairs: list[ir.Expr] = [
            ir.Cmp(
                (_FLIP[op] if negated else op,),
                (node.operands[i], node.operands[i + 1]),
                node.col,
            )
            for i, op in enumerate(node.ops)
        ]
        if len(pairs) == 1:
            return pairs[0]
        return ir.BoolOp("or" if negated else "and", tuple(pairs), node.col)
    raise TypeError(f"not a condition: {node!r}")


def closure(node: ir.Expr) -> ir.Expr:
    """The topological closure of a condition's set, approximately: strict becomes non-strict.

    ``a != b`` becomes ``true``. Used for invariants: a jump may happen on the
    boundary of a location's invariant.
    """
    node = nnf(node)
    if isinstance(node, ir.Cmp):
        op = node.ops[0]
        if op == "!=":
            return _TRUE
        return ir.Cmp(({"<": "<=", ">": ">="}.get(op, op),), node.operands, node.col)
    if isinstance(node, ir.BoolOp):
        return ir.BoolOp(node.op, tuple(closure(v) for v in node.values), node.col)
    return node


def dnf(node: ir.Expr, cap: int = DNF_CAP) -> list[tuple[ir.Cmp, ...]] | None:
    """Disjunctive normal form: a list of conjunctions of single comparisons.

    ``[]`` is *false*, ``[()]`` is *true*; ``None`` when more than ``cap``
    conjunctions would be needed. ``a != b`` splits into ``a < b`` or ``a > b``.
    """
    return _dnf(nnf(node), cap)


def _dnf(node: ir.Expr, cap: int) -> list[tuple[ir.Cmp, ...]] | None:
    if isinstance(node, ir.BoolConst):
        return [()] if node.value else []
    if isinstance(node, ir.Cmp):
        if node.ops[0] == "!=":
            a, b = node.operands
            return [(ir.Cmp(("<",), (a, b), node.col),), (ir.Cmp((">",), (a, b), node.col),)]
        return [(node,)]
    if isinstance(node, ir.BoolOp):
        parts = []
        for v in node.values:
            part = _dnf(v, cap)
            if part is None:
                return None
            parts.append(part)
        if node.op == "or":
            result = [c for p in parts for c in p]
            return result if len(result) <= cap else None
        size = math.prod(len(p) for p in parts)
        if size > cap:
            return None
        return [tuple(a for c in combo for a in c) for combo in itertools.product(*parts)]
    raise TypeError(f"not a condition in normal form: {node!r}")


def satisfiable(cond: ir.Expr, env: Env, box: Box) -> bool:
    """Whether ``cond`` may hold somewhere in ``box`` (``False`` is a proof that it never does).

    Answers are cached in ``env`` (by the structure of ``cond`` and the box).
    """
    key = (structural_key(cond), tuple(sorted(box.items())))
    found = env.cache.get(key)
    if found is None:
        terms = dnf(cond)
        if terms is None:
            found = env.evaluator(box).truth(cond)[0]
        else:
            found = any(_conjunction_feasible(term, env, box) for term in terms)
        env.cache[key] = found
    return found


def contract(cond: ir.Expr, env: Env, box: Box) -> dict[str, Interval] | None:
    """A box inside ``box`` holding every point of ``box`` where ``cond`` may hold.

    ``None`` when there is no such point. Disjunctions give the hull of their parts.
    Answers are cached in ``env``.
    """
    key = (structural_key(cond), tuple(sorted(box.items())))
    if key not in env.boxes:
        env.boxes[key] = _contract(cond, env, box)
    found = env.boxes[key]
    return None if found is None else dict(found)


def _contract(cond: ir.Expr, env: Env, box: Box) -> dict[str, Interval] | None:
    terms = dnf(cond)
    if terms is None:
        return dict(box) if env.evaluator(box).truth(cond)[0] else None
    result: dict[str, Interval] | None = None
    for term in terms:
        part = _contract_term(term, env, box)
        if part is None or not _atoms_can_hold(term, env, part):
            continue
        result = part if result is None else _hull(result, part)
    return result


def _hull(a: Mapping[str, Interval], b: Mapping[str, Interval]) -> dict[str, Interval]:
    result: dict[str, Interval] = {}
    for name in set(a) | set(b):
        if name in a and name in b:
            result[name] = a[name].hull(b[name])
        elif name == "t":
            result[name] = _TIME
    # a name bounded on one side only is unbounded in the hull (absent means "anything")
    return result


def _atoms_can_hold(term: tuple[ir.Cmp, ...], env: Env, box: Box) -> bool:
    ev = env.evaluator(box)
    return all(ev.truth(atom)[0] for atom in term)


def _contract_term(
    term: tuple[ir.Cmp, ...], env: Env, box: Box, rounds: int = 2
) -> dict[str, Interval] | None:
    current = dict(box)
    for _ in range(rounds):
        ev = env.evaluator(current)
        lin = Linearizer(ev)
        changed = False
        for atom in term:
            for row in lin.atom(atom):
                for var, coeff in row.form.coeffs.items():
                    if var.startswith("#"):
                        continue
                    old = current.get(var, _TIME if var == "t" else ENTIRE)
                    rest = Interval.point(row.form.const)
                    for other, c in row.form.coeffs.items():
                        if other != var:
                            rest = rest + Interval.point(c) * _value(other, current, lin)
                    if coeff == 1.0:
                        bound = -rest
                    elif coeff == -1.0:
                        bound = rest
                    else:
                        bound = (-rest) / Interval.point(coeff)
                    if row.op == "==":
                        new = old.intersect(bound)
                    elif coeff > 0:  # var <= bound
                        new = old.intersect(Interval(-math.inf, bound.hi))
                    else:  # var >= bound
                        new = old.intersect(Interval(bound.lo, math.inf))
                    if new is None:
                        return None
                    if new != old:
                        current[var] = new
                        changed = True
        if not changed:
            break
    return current


def _value(name: str, box: Box, lin: Linearizer) -> Interval:
    if name.startswith("#"):
        for aux_name, interval in lin.aux.values():
            if aux_name == name:
                return interval
        return ENTIRE
    return box.get(name, _TIME if name == "t" else ENTIRE)


def _conjunction_feasible(term: tuple[ir.Cmp, ...], env: Env, box: Box) -> bool:
    if not _atoms_can_hold(term, env, box):
        return False
    narrowed = _contract_term(term, env, box)
    if narrowed is None or not _atoms_can_hold(term, env, narrowed):
        return False
    lin = Linearizer(env.evaluator(narrowed))
    rows = [row for atom in term for row in lin.atom(atom)]
    coupled = any(
        len(row.form.coeffs) > 1 or any(v.startswith("#") for v in row.form.coeffs) for row in rows
    )
    if not coupled:
        return True  # one variable per comparison: the narrowed box decides exactly
    return lp_feasible(rows, lin.bounds(narrowed))
