"""SpaceEx expressions to our expression language, construct by construct.

- ``x' == e`` in a flow gives the flow ``x: e``; ``x := e`` or ``x' == e`` in an
  assignment gives the reset ``x: e`` (an identity ``x := x`` is dropped);
- ``&``, ``&&`` become ``and``; ``|``, ``||`` become ``or``; ``^`` becomes ``**``;
  comparisons and their chains stay as they are;
- what has no counterpart is refused at its position with what to do: a flow
  given as an inequality (``x' <= 2``), a range assignment (``x := [0, 1]``),
  an assignment written as an inequality, a primed variable in a condition,
  an algebraic constraint inside a flow, an unknown function.

Names are mapped by the caller (reserved words, renamings, constants inlined).

Examples
--------
>>> from hybrid.interchange.safexml import SourceText
>>> from hybrid.interchange.sxexpr import parse
>>> text = lambda s: condition_text(parse(SourceText("m.xml", s)), str)
>>> text("x <= eps & v < 0"), text("-0.1 <= w && w <= 0.1"), text("x^2 + y^2 > 10 | y < 0")
('x <= eps and v < 0', '-0.1 <= w and w <= 0.1', 'x ** 2 + y ** 2 > 10 or y < 0')
>>> flows(parse(SourceText("m.xml", "x' == v & v' == -g")), str)
{'x': 'v', 'v': '-g'}
>>> resets(parse(SourceText("m.xml", "x' == x & v' == -0.75*v")), str)
{'v': '-0.75 * v'}
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

from hybrid.errors import Position, SpecError
from hybrid.expr import ir
from hybrid.expr.functions import BUILTINS
from hybrid.expr.printer import expression_text
from hybrid.interchange import sxexpr as sx
from hybrid.interchange.sxvalues import constant_value, substitute

__all__ = [
    "FUNCTIONS",
    "changed_by",
    "condition_ir",
    "condition_text",
    "constant_value",
    "flows",
    "number_text",
    "resets",
    "substitute",
    "to_ir",
]

Rename = Callable[[str], str]
"""SpaceEx name -> our name (or the text of a number, for an inlined constant).

It raises ``KeyError(message)`` for a name it does not know; the message is
reported at the name's position."""

FUNCTIONS = {
    name: name
    for name in (
        [
            "sin",
            "cos",
            "tan",
            "asin",
            "acos",
            "atan",
            "sinh",
            "cosh",
            "tanh",
            "exp",
            "log",
            "sqrt",
            "abs",
            "min",
            "max",
        ]
    )
} | {"ln": "log", "arcsin": "asin", "arccos": "acos", "arctan": "atan"}
"""SpaceEx function names (and common spellings) -> ours; ``pow(a, b)`` becomes ``a ** b``."""

_RANGE_HINT = (
    "nondeterministic values have no counterpart in our language; declare an uncontrolled "
    'variable w (controlled="false") bounded in the invariant, e.g. lo <= w & w <= hi, '
    "and use it instead (it becomes an input with that range), or pick one value"
)


def to_ir(node: sx.Node, rename: Rename) -> ir.Expr:
    """A SpaceEx arithmetic or boolean tree as our IR (names through ``rename``)."""
    if isinstance(node, sx.Num):
        return ir.Num(node.value)
    if isinstance(node, sx.Bool):
        return ir.BoolConst(node.value)
    if isinstance(node, sx.Name):
        if node.primed:
            raise SpecError(
                f"'{node.name}'' (a primed variable) can only be the left side of a flow "
                f"equation or of an assignment",
                node.position,
            )
        try:
            mapped = rename(node.name)
        except KeyError as exc:
            message = exc.args[0] if exc.args else node.name
            raise SpecError(str(message), node.position) from None
        try:
            return ir.Num(float(mapped))
        except ValueError:
            return ir.Var(mapped, ir.STATE)
    if isinstance(node, sx.Neg):
        return ir.Unary("-", to_ir(node.operand, rename))
    if isinstance(node, sx.BinOp) and node.op in "+-":
        return _sum(node, rename)
    if isinstance(node, sx.BinOp):
        op = "**" if node.op == "^" else node.op
        return ir.Bin(op, to_ir(node.left, rename), to_ir(node.right, rename))
    if isinstance(node, sx.Call):
        return _call(node, rename)
    if isinstance(node, sx.Cmp):
        return ir.Cmp(node.ops, tuple(to_ir(o, rename) for o in node.operands))
    if isinstance(node, sx.And):
        items = sx.conjuncts(node)
        if not items:
            return ir.BoolConst(True)
        if len(items) == 1:
            return to_ir(items[0], rename)
        return ir.BoolOp("and", tuple(to_ir(i, rename) for i in items))
    if isinstance(node, sx.Or):
        if not node.items:
            return ir.BoolConst(True)
        return ir.BoolOp("or", tuple(to_ir(i, rename) for i in node.items))
    if isinstance(node, sx.Interval):
        raise SpecError(f"a range [lo, hi] is not a value: {_RANGE_HINT}", node.position)
    if isinstance(node, sx.Assign):
        raise SpecError("an assignment ':=' belongs in <assignment> only", node.position)
    if isinstance(node, sx.Loc):
        raise SpecError("loc(...) belongs in the .cfg file only", node.position)
    raise TypeError(f"unknown SpaceEx node {node!r}")


LONG_SUM = 32
"""Sums of more terms than this are written in parenthesised groups (see :func:`_sum`)."""


def _sum(node: sx.BinOp, rename: Rename) -> ir.Expr:
    """A chain ``t0 ± t1 ± ...`` as IR; a long one in groups of about sqrt(n) terms.

    Our expressions refuse trees deeper than 64 levels, and a sum of n terms
    written flat is n levels deep (the ISS model's outputs have 135 terms):
    ``t0 + ... + t15 + (t16 - ... ) - (...)`` is about 2 sqrt(n) deep.
    """
    terms: list[tuple[str, sx.Node]] = []
    current: sx.Node = node
    while isinstance(current, sx.BinOp) and current.op in "+-":
        terms.append((current.op, current.right))
        current = current.left
    terms.append(("+", current))
    terms.reverse()
    converted = [(sign, to_ir(term, rename)) for sign, term in terms]
    size = len(converted) if len(converted) <= LONG_SUM else math.isqrt(len(converted)) + 1
    result: ir.Expr | None = None
    for start in range(0, len(converted), size):
        chunk = converted[start : start + size]
        outer = chunk[0][0]
        group = chunk[0][1]
        for sign, term in chunk[1:]:
            group = ir.Bin("+" if sign == outer else "-", group, term)
        result = group if result is None else ir.Bin(outer, result, group)
    assert result is not None
    return result


def _call(node: sx.Call, rename: Rename) -> ir.Expr:
    args = tuple(to_ir(a, rename) for a in node.args)
    if node.func == "pow" and len(args) == 2:
        return ir.Bin("**", args[0], args[1])
    ours = FUNCTIONS.get(node.func)
    if ours is None:
        raise SpecError(
            f"function '{node.func}' has no counterpart; known: pow, {', '.join(sorted(FUNCTIONS))}",
            node.position,
        )
    spec = BUILTINS[ours]
    if len(args) < spec.min_args or (spec.max_args is not None and len(args) > spec.max_args):
        raise SpecError(f"{node.func}() takes {spec.min_args} argument(s)", node.position)
    return ir.Call(ours, args)


def condition_ir(node: sx.Node, rename: Rename) -> ir.Expr:
    """A condition (invariant, guard, forbidden set) as IR."""
    if isinstance(node, sx.Num | sx.Name | sx.Neg | sx.BinOp | sx.Call):
        raise SpecError("expected a condition (a comparison), got a number", _where(node))
    return to_ir(node, rename)


def condition_text(node: sx.Node, rename: Rename) -> str:
    """A condition as text of our language (``true`` for an empty one)."""
    return expression_text(condition_ir(node, rename))


def number_text(node: sx.Node, rename: Rename) -> str:
    """An arithmetic expression as text of our language."""
    if isinstance(node, sx.Cmp | sx.And | sx.Or | sx.Bool):
        raise SpecError("expected a number, got a condition", _where(node))
    return expression_text(to_ir(node, rename))


def _where(node: sx.Node) -> Position:
    return node.position


def _primed_target(item: sx.Node) -> tuple[sx.Name, sx.Node] | None:
    """``(x', e)`` for ``x' == e`` or ``e == x'``; ``None`` if the item is not of that form."""
    if isinstance(item, sx.Cmp) and item.ops == ("==",):
        left, right = item.operands
        if isinstance(left, sx.Name) and left.primed:
            return left, right
        if isinstance(right, sx.Name) and right.primed:
            return right, left
    return None


def _has_primed(node: sx.Node) -> sx.Name | None:
    stack: list[sx.Node] = [node]
    while stack:
        current = stack.pop()
        if isinstance(current, sx.Name) and current.primed:
            return current
        stack.extend(_children(current))
    return None


def _children(node: sx.Node) -> tuple[sx.Node, ...]:
    if isinstance(node, sx.Call):
        return node.args
    if isinstance(node, sx.Neg):
        return (node.operand,)
    if isinstance(node, sx.BinOp):
        return (node.left, node.right)
    if isinstance(node, sx.Cmp):
        return node.operands
    if isinstance(node, sx.And | sx.Or):
        return node.items
    if isinstance(node, sx.Assign):
        return (node.target, node.value)
    if isinstance(node, sx.Interval):
        return (node.lo, node.hi)
    return ()


def flows(node: sx.Node, rename: Rename) -> dict[str, str]:
    """``{x: text of f}`` for a flow ``x' == f & ...`` (keys are SpaceEx names).

    Raises
    ------
    SpecError
        For a flow that is not a conjunction of equations ``x' == f(x)``.
    """
    found: dict[str, str] = {}
    for item in sx.conjuncts(node):
        if isinstance(item, sx.Or):
            raise SpecError(
                "a disjunction '|' in a flow has no counterpart: split the location in two",
                item.position,
            )
        pair = _primed_target(item)
        if pair is None:
            primed = _has_primed(item)
            if primed is not None:
                raise SpecError(
                    f"the flow of '{primed.name}' is not an equation {primed.name}' == f(x): a "
                    f"derivative given as an inequality or inside an expression is a "
                    f"nondeterministic flow, which has no counterpart here; for a bounded rate "
                    f'declare an uncontrolled variable w (controlled="false") bounded in the '
                    f"invariant (lo <= w & w <= hi) and write {primed.name}' == w: w becomes an "
                    f"input with that range",
                    _where(item),
                )
            raise SpecError(
                "a constraint without a derivative inside a flow (an algebraic constraint) has "
                "no counterpart: move a bound on the state into the <invariant>, or replace an "
                "algebraic variable by its expression",
                _where(item),
            )
        target, value = pair
        other = _has_primed(value)
        if other is not None:
            raise SpecError(
                f"'{other.name}'' on the right side of a flow equation (a differential-algebraic "
                "equation) has no counterpart: write each derivative as a function of the state",
                other.position,
            )
        if target.name in found:
            raise SpecError(f"the derivative of '{target.name}' is given twice", target.position)
        found[target.name] = number_text(value, rename)
    return found


def _single_equals(item: sx.Node) -> tuple[sx.Name, sx.Node] | None:
    """``(x, e)`` for ``x = e`` written with one ``=`` (the reset ``x := e``), else ``None``."""
    if isinstance(item, sx.Cmp) and item.single:
        left, right = item.operands
        if isinstance(left, sx.Name) and not left.primed and _has_primed(right) is None:
            return left, right
    return None


def resets(node: sx.Node, rename: Rename, single: list[sx.Node] | None = None) -> dict[str, str]:
    """``{x: text of e}`` for an assignment ``x := e & ...`` (or ``x' == e``); identities dropped.

    ``x = e`` (one ``=``) is read as ``x := e``, as SpaceEx, PHAVer and HyST
    read it; each such item is appended to ``single`` (for the note).
    """
    found: dict[str, str] = {}
    for item in sx.conjuncts(node):
        equals = _single_equals(item)
        if isinstance(item, sx.Assign):
            target, value = item.target, item.value
        elif equals is not None:
            target, value = equals
            if single is not None:
                single.append(item)
        else:
            pair = _primed_target(item)
            if pair is None:
                primed = _has_primed(item)
                raise SpecError(
                    "an assignment must be 'x := e' or \"x' == e\"; "
                    + (
                        f"a bound on {primed.name}' (a range assignment): {_RANGE_HINT}"
                        if primed is not None
                        else "a condition here belongs in the <guard>"
                    ),
                    _where(item),
                )
            target, value = pair
        if isinstance(value, sx.Interval):
            raise SpecError(
                f"range assignment {target.name} := [lo, hi]: {_RANGE_HINT}", value.position
            )
        other = _has_primed(value)
        if other is not None:
            raise SpecError(
                f"'{other.name}'' on the right side of an assignment has no counterpart: "
                "the right side reads the values before the jump, written unprimed",
                other.position,
            )
        if target.name in found:
            raise SpecError(f"'{target.name}' is assigned twice", target.position)
        if isinstance(value, sx.Name) and not value.primed and value.name == target.name:
            continue  # identity: x keeps its value, which is our default
        found[target.name] = number_text(value, rename)
    return found


def reset_nodes(node: sx.Node) -> dict[str, sx.Node]:
    """``{x: e}`` as SpaceEx trees (identities included), for substitution; call after :func:`resets`."""
    found: dict[str, sx.Node] = {}
    for item in sx.conjuncts(node):
        equals = _single_equals(item)
        if isinstance(item, sx.Assign):
            found[item.target.name] = item.value
        elif equals is not None:
            found[equals[0].name] = equals[1]
        else:
            pair = _primed_target(item)
            if pair is not None:
                found[pair[0].name] = pair[1]
    return found


def changed_by(values: Mapping[str, sx.Node]) -> set[str]:
    """The variables :func:`reset_nodes`'s ``{x: e}`` changes: every ``x`` but ``x := x``."""
    return {k for k, v in values.items() if not (isinstance(v, sx.Name) and v.name == k)}
