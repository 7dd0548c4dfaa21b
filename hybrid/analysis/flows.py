"""Where the flow can leave a location: time derivatives and exit conditions.

Where a guard may be (or surely is) found enabled is
:mod:`hybrid.analysis.enabled`'s.

The invariant of a location is a closed set (up to strictness); a continuous
flow leaves it only through its boundary, and only where it points outward.
For an invariant in disjunctive normal form, every comparison ``a <= b`` of
every disjunct gives a *face*: ``a == b``, the other comparisons of the
disjunct (closed), and ``d(a - b)/dt > 0`` along the flow. Where the time
derivative cannot be formed (inputs, library functions) the face counts whole.
Points where the flow is tangent (derivative exactly 0) are not exits.

Examples
--------
>>> from hybrid.expr.parse import Scope, parse_expression
>>> from hybrid.expr.printer import to_source
>>> scope = Scope({"h": "state", "v": "state"})
>>> inv = parse_expression("h >= 0", scope, want="bool")
>>> [to_source(c, {"h": "h", "v": "v"}) for c in exit_conditions(inv, {"h": ir.Var("v", "state")})]
['h == 0.0 and v < 0.0']
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

from hybrid.analysis.solve import closure, conjoin, dnf
from hybrid.expr import ir
from hybrid.expr.dependencies import evaluation_order

__all__ = ["MAX_DERIVATIVE_DEPTH", "derivative", "exit_conditions"]

_ZERO = ir.Num(0.0)
_ONE = ir.Num(1.0)


def _is(node: ir.Expr, value: float) -> bool:
    return isinstance(node, ir.Num) and node.value == value


def _add(a: ir.Expr, b: ir.Expr) -> ir.Expr:
    if _is(a, 0.0):
        return b
    if _is(b, 0.0):
        return a
    return ir.Bin("+", a, b)


def _sub(a: ir.Expr, b: ir.Expr) -> ir.Expr:
    if _is(b, 0.0):
        return a
    if _is(a, 0.0):
        return ir.Unary("-", b)
    return ir.Bin("-", a, b)


def _mul(a: ir.Expr, b: ir.Expr) -> ir.Expr:
    if _is(a, 0.0) or _is(b, 0.0):
        return _ZERO
    if _is(a, 1.0):
        return b
    if _is(b, 1.0):
        return a
    return ir.Bin("*", a, b)


def _div(a: ir.Expr, b: ir.Expr) -> ir.Expr:
    return _ZERO if _is(a, 0.0) else ir.Bin("/", a, b)


def _call(name: str, *args: ir.Expr) -> ir.Expr:
    return ir.Call(name, args)


# d f(u) / du for the built-ins with a simple derivative
_CHAIN: dict[str, Callable[[ir.Expr], ir.Expr]] = {
    "sin": lambda u: _call("cos", u),
    "cos": lambda u: ir.Unary("-", _call("sin", u)),
    "exp": lambda u: _call("exp", u),
    "sinh": lambda u: _call("cosh", u),
    "cosh": lambda u: _call("sinh", u),
    "tanh": lambda u: _sub(_ONE, ir.Bin("**", _call("tanh", u), ir.Num(2.0))),
    "sqrt": lambda u: _div(_ONE, _mul(ir.Num(2.0), _call("sqrt", u))),
    "log": lambda u: _div(_ONE, u),
    "atan": lambda u: _div(_ONE, _add(_ONE, _mul(u, u))),
    "abs": lambda u: _call("sign", u),
}


MAX_DERIVATIVE_DEPTH = 256
"""Deepest derivative expression formed (deeper, it is not formed). A derivative through
signals defined through each other can be as deep as their chain is long; what reads it
(the interval evaluator) recurses over it."""


def derivative(
    node: ir.Expr,
    flow: Mapping[str, ir.Expr],
    signals: Mapping[str, ir.Expr],
    opaque: frozenset[str] = frozenset(),
) -> ir.Expr | None:
    """The time derivative of ``node`` along ``flow`` (``None`` if it cannot be formed).

    A signal's derivative is formed once, after those of the signals it reads
    (so a long chain of definitions is followed in order, not recursively); a
    result deeper than :data:`MAX_DERIVATIVE_DEPTH` is not formed.

    Examples
    --------
    >>> from hybrid.expr.printer import to_source
    >>> x = ir.Var("x", "state")
    >>> d = derivative(ir.Bin("*", x, x), {"x": ir.Num(2.0)}, {})
    >>> to_source(d, {"x": "x"})
    '2.0 * x + x * 2.0'
    """
    formed: dict[str, ir.Expr | None] = {}  # each signal's derivative, once

    def d(n: ir.Expr) -> ir.Expr | None:
        if isinstance(n, ir.Num):
            return _ZERO
        if isinstance(n, ir.Var):
            if n.kind == ir.STATE:
                return flow.get(n.name, _ZERO)
            if n.kind == ir.TIME:
                return _ONE
            if n.kind == ir.SIGNAL and n.name in signals:
                if n.name not in formed:
                    for name in evaluation_order((n.name,), signals, formed):
                        formed[name] = d(signals[name])
                return formed[n.name]
            return None
        if isinstance(n, ir.Unary):
            inner = d(n.operand)
            return None if inner is None else (_ZERO if _is(inner, 0.0) else ir.Unary("-", inner))
        if isinstance(n, ir.Bin):
            return _bin(n)
        if isinstance(n, ir.Call) and len(n.args) == 1 and n.func in _CHAIN:
            if n.func in opaque:
                return None
            inner = d(n.args[0])
            return None if inner is None else _mul(_CHAIN[n.func](n.args[0]), inner)
        return None

    def _bin(n: ir.Bin) -> ir.Expr | None:
        dl, dr = d(n.left), d(n.right)
        if n.op == "**":
            if isinstance(n.right, ir.Num) and dl is not None:
                k = n.right.value
                power = ir.Bin("**", n.left, ir.Num(k - 1.0)) if k != 2.0 else n.left
                return _mul(_mul(ir.Num(k), power), dl)
            return None
        if dl is None or dr is None:
            return None
        if n.op == "+":
            return _add(dl, dr)
        if n.op == "-":
            return _sub(dl, dr)
        if n.op == "*":
            return _add(_mul(dl, n.right), _mul(n.left, dr))
        if n.op == "/":
            return _div(_sub(_mul(dl, n.right), _mul(n.left, dr)), _mul(n.right, n.right))
        return None

    found = d(node)
    return None if found is None or _deeper_than(found, MAX_DERIVATIVE_DEPTH) else found


def _deeper_than(node: ir.Expr, limit: int) -> bool:
    """Whether ``node`` nests more than ``limit`` levels (walked without recursion)."""
    stack = [(node, 1)]
    while stack:
        current, depth = stack.pop()
        if depth > limit:
            return True
        stack.extend((child, depth + 1) for child in ir.children(current))
    return False


def _folded(rate: ir.Expr | None) -> ir.Expr | None:
    """``-c`` as the number ``-c``."""
    if isinstance(rate, ir.Unary) and rate.op == "-" and isinstance(rate.operand, ir.Num):
        return ir.Num(-rate.operand.value)
    return rate


def exit_conditions(
    invariant: ir.Expr,
    flow: Mapping[str, ir.Expr],
    signals: Mapping[str, ir.Expr] | None = None,
    opaque: frozenset[str] = frozenset(),
) -> list[ir.Expr]:
    """Conditions whose union holds every point where the flow may leave ``invariant``.

    ``[]`` when the invariant can never be left (``true``). Beyond the normal-form
    cap the whole closed invariant is returned (any point may be an exit).
    """
    signals = signals or {}
    terms = dnf(invariant)
    if terms is None:
        return [closure(invariant)]
    result: list[ir.Expr] = []
    for term in terms:
        for k, atom in enumerate(term):
            rest = [closure(a) for j, a in enumerate(term) if j != k]
            lhs, rhs = atom.operands
            op = atom.ops[0]
            face = ir.Cmp(("==",), (lhs, rhs), atom.col)
            rate = derivative(_sub(lhs, rhs), flow, signals, opaque)
            outward: ir.Expr
            if rate is None:
                outward = ir.BoolConst(True)
            elif op in ("<", "<="):
                outward = ir.Cmp((">",), (rate, _ZERO))
            elif op in (">", ">="):
                outward = ir.Cmp(("<",), (rate, _ZERO))
            else:
                outward = ir.Cmp(("!=",), (rate, _ZERO))
            if isinstance(rate, ir.Num):  # constant rate: decide now
                holds = {"<": rate.value > 0, "<=": rate.value > 0, ">": rate.value < 0}
                holds[">="] = rate.value < 0
                holds["=="] = rate.value != 0
                if not holds[op]:
                    continue
                outward = ir.BoolConst(True)
            result.append(conjoin(*rest, face, outward))
    return result
