"""The SpaceEx expression translator against a table written by hand, and its refusals.

Each accepted row also compiles in our expression language, and means the
same: both sides are evaluated at sample points, the SpaceEx side by an
independent little evaluator written here over Python's operator module.
"""

from __future__ import annotations

import math
import operator
import re

import pytest

from hybrid.errors import SpecError
from hybrid.expr import ir
from hybrid.expr.interval import Interval
from hybrid.expr.parse import Scope, parse_expression
from hybrid.expr.ranges import IntervalEvaluator, can_hold
from hybrid.interchange import sxexpr as sx
from hybrid.interchange.safexml import SourceText
from hybrid.interchange.translate import condition_text, flows, number_text, resets

CONDITIONS = [
    ("x <= eps & v < 0", "x <= eps and v < 0"),
    ("x >= 0 && y <= 1", "x >= 0 and y <= 1"),
    ("x < 0 | x > 1", "x < 0 or x > 1"),
    ("x < 0 || x > 1", "x < 0 or x > 1"),
    ("x < 0 & (y > 1 | y < -1)", "x < 0 and (y > 1 or y < -1)"),
    ("-0.1 <= w <= 0.1", "-0.1 <= w <= 0.1"),
    ("x^2 + y^2 > 10", "x ** 2 + y ** 2 > 10"),
    ("y + 0.714285*x == 0", "y + 0.714285 * x == 0"),
    ("x = 1", "x == 1"),
    ("x != 1", "x != 1"),
    ("true", "true"),
    ("", "true"),
]
NUMBERS = [
    ("-x^2", "-x ** 2"),
    ("(-x)^2", "(-x) ** 2"),
    ("2^-1", "2 ** (-1)"),
    ("x^y^2", "x ** y ** 2"),
    ("(x^y)^2", "(x ** y) ** 2"),
    ("x - (y - w)", "x - (y - w)"),
    ("x/(y*w)", "x / (y * w)"),
    ("1.0e-3*x", "0.001 * x"),
    (".5*x", "0.5 * x"),
    ("- 2592.1*x - 21.119*y", "-2592.1 * x - 21.119 * y"),
    ("sin(x) + pow(x, 3)", "sin(x) + x ** 3"),
    ("exp(-x) * sqrt(y)", "exp(-x) * sqrt(y)"),
    ("ln(y)", "log(y)"),
    ("-((1-x)*y)", "-((1 - x) * y)"),
    ("+x", "x"),
]
SCOPE = Scope({n: "state" for n in ("x", "y", "v", "w", "eps")})


def _text(source: str) -> SourceText:
    return SourceText("m.xml", source, [(0, 1, 1)])


def _evaluate(node: sx.Node, env: dict[str, float]) -> float | bool:
    """An evaluator of the SpaceEx tree, independent of our expression package."""
    ops = {"+": operator.add, "-": operator.sub, "*": operator.mul, "/": operator.truediv}
    cmps = {"<": operator.lt, "<=": operator.le, ">": operator.gt, ">=": operator.ge}
    cmps |= {"==": operator.eq, "!=": operator.ne}
    if isinstance(node, sx.Num):
        return node.value
    if isinstance(node, sx.Bool):
        return node.value
    if isinstance(node, sx.Name):
        return env[node.name]
    if isinstance(node, sx.Neg):
        return -_evaluate(node.operand, env)
    if isinstance(node, sx.BinOp):
        a, b = _evaluate(node.left, env), _evaluate(node.right, env)
        return math.pow(a, b) if node.op == "^" else ops[node.op](a, b)
    if isinstance(node, sx.Call):
        args = [_evaluate(a, env) for a in node.args]
        fn = {"pow": math.pow, "ln": math.log}.get(node.func) or getattr(math, node.func)
        return float(fn(*args))
    if isinstance(node, sx.Cmp):
        values = [_evaluate(o, env) for o in node.operands]
        return all(cmps[op](a, b) for op, a, b in zip(node.ops, values, values[1:], strict=False))
    if isinstance(node, sx.And):
        return all(_evaluate(i, env) for i in node.items)
    if isinstance(node, sx.Or):
        return any(_evaluate(i, env) for i in node.items)
    raise AssertionError(node)


POINTS = [
    {"x": 0.5, "y": 1.5, "v": -1.0, "w": 0.05, "eps": 0.0},
    {"x": 1.25, "y": 0.75, "v": 2.0, "w": -0.2, "eps": 1.0},
    {"x": 1.0, "y": 2.0, "v": 0.0, "w": 0.1, "eps": 0.5},
]


@pytest.mark.parametrize(("spaceex", "ours"), CONDITIONS, ids=[c[0] or "empty" for c in CONDITIONS])
def test_conditions_translate_as_the_table_says(spaceex: str, ours: str) -> None:
    tree = sx.parse(_text(spaceex))
    assert condition_text(tree, str) == ours
    compiled = parse_expression(ours, SCOPE, want="bool")
    for point in POINTS:
        assert _ours(compiled, point) == bool(_evaluate(tree, point)), point


@pytest.mark.parametrize(("spaceex", "ours"), NUMBERS, ids=[n[0] for n in NUMBERS])
def test_numbers_translate_as_the_table_says(spaceex: str, ours: str) -> None:
    tree = sx.parse(_text(spaceex))
    assert number_text(tree, str) == ours
    compiled = parse_expression(ours, SCOPE)
    for point in POINTS:
        assert _ours(compiled, point) == pytest.approx(_evaluate(tree, point), rel=1e-15)


def _ours(node: ir.Expr, point: dict[str, float]) -> float | bool:
    """Our side at a point: the interval evaluator over a box of one point."""
    box = {k: Interval(v, v) for k, v in point.items()}
    if isinstance(node, ir.Cmp | ir.BoolOp | ir.Not | ir.BoolConst):
        return can_hold(node, box)
    value = IntervalEvaluator(box).number(node)
    return (value.lo + value.hi) / 2


def test_flows_and_resets() -> None:
    assert flows(sx.parse(_text("x' == v & v' == -g")), str) == {"x": "v", "v": "-g"}
    assert flows(sx.parse(_text("x'==-y & y'==x")), str) == {"x": "-y", "y": "x"}
    assert flows(sx.parse(_text("-g == v'")), str) == {"v": "-g"}
    assert resets(sx.parse(_text("v := -c*v")), str) == {"v": "-c * v"}
    assert resets(sx.parse(_text("x' == x & v' == -0.75*v")), str) == {"v": "-0.75 * v"}
    assert resets(sx.parse(_text("x := x & y := 0")), str) == {"y": "0"}
    assert resets(sx.parse(_text("")), str) == {}


REFUSED = [
    ("flow", "x' <= 2", 1, "is not an equation x' == f(x)"),
    ("flow", "x' == v & 1 <= x'", 11, "nondeterministic flow"),
    ("flow", "x' == v & x >= 0", 11, "algebraic constraint"),
    ("flow", "x' == y'", 7, "differential-algebraic"),
    ("flow", "x' == 1 & x' == 2", 11, "given twice"),
    ("flow", "x' == 1 | x' == 2", 1, "split the location"),
    ("assignment", "x := [0, 1]", 6, "range assignment x := [lo, hi]"),
    ("assignment", "x' >= 0 & x' <= 1", 1, "a range assignment"),
    ("assignment", "x > 0", 1, "belongs in the <guard>"),
    ("assignment", "x := y'", 6, "right side of an assignment"),
    ("condition", "x := 1", 1, "belongs in <assignment> only"),
    ("condition", "x' > 0", 1, "primed variable"),
    ("condition", "foo(x) > 0", 1, "function 'foo' has no counterpart"),
    ("condition", "x + 1", 1, "expected a condition"),
    ("condition", "(x > 0", 7, "expected ')'"),
    ("condition", "x > 0 # y", 7, "unexpected character '#'"),
    ("condition", "!(x > 0)", 1, "'!' (negation) is not supported"),
    ("condition", "x == 0 with offset support_function(x >= 0)", 8, "flattened form"),
    ("condition", "x >", 4, "ends too early"),
    ("condition", "(" * 70 + "x" + ")" * 70, 65, "nested more than 64 levels"),
]


@pytest.mark.parametrize(
    ("where", "source", "column", "message"), REFUSED, ids=[r[1][:30] for r in REFUSED]
)
def test_what_has_no_counterpart_is_refused_at_its_column(
    where: str, source: str, column: int, message: str
) -> None:
    with pytest.raises(SpecError) as info:
        tree = sx.parse(_text(source))
        if where == "flow":
            flows(tree, str)
        elif where == "assignment":
            resets(tree, str)
        else:
            condition_text(tree, str)
    assert (info.value.line, info.value.column) == (1, column)
    assert re.search(re.escape(message), info.value.message), info.value.message
