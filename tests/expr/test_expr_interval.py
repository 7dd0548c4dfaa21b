"""Interval arithmetic is sound: every value at a point of the box lies in the interval."""

from __future__ import annotations

import math
from fractions import Fraction

import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from hybrid.expr import ir
from hybrid.expr.functions import BUILTINS
from hybrid.expr.interval import ENTIRE, Interval
from hybrid.expr.parse import ExprError, Scope, parse_expression
from hybrid.expr.ranges import IntervalEvaluator, can_fail, can_hold, evaluate

SCOPE = Scope({"x": "state", "y": "state", "u": "input", "s": "signal"})


def parse(text: str, want: str = "number") -> ir.Expr:
    return parse_expression(text, SCOPE, want=want)


def parse_or_skip(text: str, want: str = "number") -> ir.Expr:
    """Parse a generated expression; constant parts the parser refuses skip the example."""
    try:
        return parse(text, want)
    except ExprError:
        assume(False)
        raise


def value_at(node: ir.Expr, point: dict[str, float]) -> float | bool:
    """A plain reference evaluator of the IR."""
    if isinstance(node, ir.Num):
        return node.value
    if isinstance(node, ir.BoolConst):
        return node.value
    if isinstance(node, ir.Var):
        return point["t"] if node.kind == ir.TIME else point[node.name]
    if isinstance(node, ir.Unary):
        return -value_at(node.operand, point)
    if isinstance(node, ir.Bin):
        a, b = value_at(node.left, point), value_at(node.right, point)
        return (
            {"+": a + b, "-": a - b, "*": a * b}[node.op]
            if node.op in "+-*"
            else (a / b if node.op == "/" else a**b)
        )
    if isinstance(node, ir.Call):
        return BUILTINS[node.func].fn(*(value_at(a, point) for a in node.args))
    if isinstance(node, ir.Cmp):
        vals = [value_at(o, point) for o in node.operands]
        ops = {
            "<": lambda a, b: a < b,
            "<=": lambda a, b: a <= b,
            ">": lambda a, b: a > b,
            ">=": lambda a, b: a >= b,
            "==": lambda a, b: a == b,
            "!=": lambda a, b: a != b,
        }
        return all(ops[op](vals[i], vals[i + 1]) for i, op in enumerate(node.ops))
    if isinstance(node, ir.BoolOp):
        parts = [value_at(v, point) for v in node.values]
        return all(parts) if node.op == "and" else any(parts)
    if isinstance(node, ir.Not):
        return not value_at(node.operand, point)
    raise TypeError(node)


ATOMS = ["x", "y", "0.1", "2", "-3.5", "1e-3", "7"]
UNARY = [
    "sin",
    "cos",
    "tan",
    "exp",
    "sqrt",
    "log",
    "abs",
    "atan",
    "tanh",
    "sinh",
    "cosh",
    "floor",
    "ceil",
    "sign",
    "asin",
    "acos",
    "log10",
]
BINARY = ["+", "-", "*", "/"]


def expressions() -> st.SearchStrategy[str]:
    return st.recursive(
        st.sampled_from(ATOMS),
        lambda inner: st.one_of(
            st.tuples(inner, st.sampled_from(BINARY), inner).map(
                lambda t: f"({t[0]} {t[1]} {t[2]})"
            ),
            st.tuples(st.sampled_from(UNARY), inner).map(lambda t: f"{t[0]}({t[1]})"),
            st.tuples(inner, st.sampled_from(["2", "3", "0.5", "-1"])).map(
                lambda t: f"({t[0]}) ** {t[1]}"
            ),
            st.tuples(st.sampled_from(["min", "max", "hypot", "atan2"]), inner, inner).map(
                lambda t: f"{t[0]}({t[1]}, {t[2]})"
            ),
            st.tuples(inner, inner, inner).map(lambda t: f"clip({t[0]}, {t[1]}, {t[2]})"),
        ),
        max_leaves=6,
    )


boxes = st.tuples(st.floats(-50, 50), st.floats(0, 20), st.floats(-50, 50), st.floats(0, 20)).map(
    lambda t: {"x": Interval(t[0], t[0] + t[1]), "y": Interval(t[2], t[2] + t[3])}
)


@settings(max_examples=300, deadline=None)
@given(
    expressions(),
    boxes,
    st.lists(st.tuples(st.floats(0, 1), st.floats(0, 1)), min_size=1, max_size=8),
)
def test_interval_contains_every_point_value(text, box, fractions):
    node = parse_or_skip(text)
    result = evaluate(node, box)
    assert result.lo <= result.hi
    corners = [(0.0, 0.0), (1.0, 1.0), (0.0, 1.0), (1.0, 0.0), *fractions]
    for fx, fy in corners:
        point = {
            "x": box["x"].lo + fx * (box["x"].hi - box["x"].lo),
            "y": box["y"].lo + fy * (box["y"].hi - box["y"].lo),
        }
        point = {k: min(max(v, box[k].lo), box[k].hi) for k, v in point.items()}
        try:
            value = value_at(node, point)
        except (ArithmeticError, ValueError, TypeError):
            continue
        if isinstance(value, complex) or not math.isfinite(value):
            continue
        assert result.lo <= value <= result.hi, (text, point, value, result)


@settings(max_examples=200, deadline=None)
@given(
    expressions(),
    st.sampled_from(["<", "<=", ">", ">=", "==", "!="]),
    boxes,
    st.lists(st.tuples(st.floats(0, 1), st.floats(0, 1)), min_size=1, max_size=8),
)
def test_truth_is_sound(text, op, box, fractions):
    cond = parse_or_skip(f"{text} {op} 1", want="bool")
    may_hold, may_fail = IntervalEvaluator(box).truth(cond)
    for fx, fy in [(0.0, 0.0), (1.0, 1.0), *fractions]:
        point = {
            "x": box["x"].lo + fx * (box["x"].hi - box["x"].lo),
            "y": box["y"].lo + fy * (box["y"].hi - box["y"].lo),
        }
        point = {k: min(max(v, box[k].lo), box[k].hi) for k, v in point.items()}
        try:
            holds = value_at(cond, point)
        except (ArithmeticError, ValueError, TypeError):
            continue
        if holds:
            assert may_hold, (text, op, point)
        else:
            assert may_fail, (text, op, point)


def test_strict_comparisons_keep_their_strictness():
    box = {"x": Interval(0.0, 5.0)}
    assert not can_hold(parse("x < 0", "bool"), box)
    assert can_hold(parse("x <= 0", "bool"), box)
    assert not can_hold(parse("x > 5", "bool"), box)
    assert not can_fail(parse("x >= 0", "bool"), box)
    assert can_hold(parse("x == 5", "bool"), box) and can_fail(parse("x == 5", "bool"), box)
    assert not can_hold(parse("x != 3", "bool"), {"x": Interval(3.0, 3.0)})


def test_bouncing_ball_reset_keeps_zero_exact():
    v = Interval(-20.0, 0.0)
    after = evaluate(parse("-0.8 * x"), {"x": v})
    assert after.lo == 0.0  # exact: 0 * anything is 0, no outward widening below 0
    assert not can_hold(parse("x < 0", "bool"), {"x": after})


@pytest.mark.parametrize(
    ("text", "box", "expected"),
    [
        ("1 / x", {"x": Interval(-1.0, 1.0)}, ENTIRE),
        ("sqrt(x)", {"x": Interval(-4.0, 9.0)}, Interval(0.0, 3.0)),
        ("sqrt(x)", {"x": Interval(-4.0, -1.0)}, ENTIRE),
        ("log(x)", {"x": Interval(0.0, 1.0)}, Interval(-math.inf, 0.0)),
        ("sin(x)", {"x": Interval(-100.0, 100.0)}, Interval(-1.0, 1.0)),
        ("x ** 2", {"x": Interval(-3.0, 2.0)}, Interval(0.0, 9.0)),
        ("abs(x)", {"x": Interval(-3.0, 2.0)}, Interval(0.0, 3.0)),
        ("x * y", {"x": Interval(-math.inf, 0.0), "y": Interval(0.0, 0.0)}, Interval(0.0, 0.0)),
        ("exp(x)", {"x": Interval(1000.0, 1001.0)}, Interval(1.7976931348623157e308, math.inf)),
        ("u + 1", {}, ENTIRE),
    ],
)
def test_special_cases(text, box, expected):
    assert evaluate(parse(text), box) == expected


def test_signals_are_evaluated_from_their_definitions_and_vectors_are_unknown():
    ev = IntervalEvaluator({"x": Interval(1.0, 2.0)}, {"s": parse("2 * x")})
    assert ev.number(ir.Var("s", "signal")) == Interval(2.0, 4.0)
    assert ev.number(ir.Index("w", 0)) == ENTIRE
    assert ev.number(ir.Var("t", "time")) == Interval(0.0, math.inf)
    opaque = IntervalEvaluator({"x": Interval(0.0, 1.0)}, opaque=frozenset({"sin"}))
    assert opaque.number(parse("sin(x)")) == ENTIRE


def test_rounding_is_outward_only_when_inexact():
    total = evaluate(parse("x + 0.2"), {"x": Interval(0.1, 0.1)})
    assert total.lo < total.hi
    assert Fraction(total.lo) <= Fraction(0.1) + Fraction(0.2) <= Fraction(total.hi)
    third = evaluate(parse("x / 3"), {"x": Interval(1.0, 1.0)})
    assert third.lo < third.hi and third.lo <= 1 / 3 <= third.hi
    assert evaluate(parse("x / 4"), {"x": Interval(1.0, 1.0)}) == Interval(0.25, 0.25)
    tiny = evaluate(parse("x * x"), {"x": Interval(1e-200, 1e-200)})
    assert tiny.lo == 0.0 and tiny.hi > 0.0  # underflow: the true value is above zero
