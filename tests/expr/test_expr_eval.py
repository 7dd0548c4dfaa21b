"""Compiled expressions give the same numbers as the same formula written in Python.

Each row is an expression of the spec language and a hand-written Python
function of ``(t, x, y, z)`` with parameters ``a, b, c``; both are evaluated at
several points and must agree to 1e-15 relative (most agree exactly: the
compiled code does the same floating-point operations in the same order).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest

from hybrid.expr import ir
from hybrid.expr.codegen import CodeContext, compile_function
from hybrid.expr.functions import BUILTINS
from hybrid.expr.parse import ExprError, Scope, parse_expression
from hybrid.expr.printer import to_source

A, B, C = 1.7, -0.45, 3.2
SCOPE = Scope(
    variables={"x": "state", "y": "state", "z": "state", "a": "param", "b": "param", "c": "param"}
)
CTX = CodeContext(states=("x", "y", "z"), params={"a": A, "b": B, "c": C})
# (t, x, y, z): x in [-3, 3], y > 0, z of either sign (and zero)
POINTS = [
    (0.0, -2.5, 0.4, -1.1),
    (0.25, -0.3, 1.3, 0.0),
    (1.5, 0.7, 2.2, 0.5),
    (3.0, 1.9, 3.7, 2.0),
    (7.25, 2.96, 0.05, -3.5),
]

Row = tuple[str, Callable[[float, float, float, float], float | bool]]

FUNCTIONS: list[Row] = [
    ("sin(x)", lambda t, x, y, z: math.sin(x)),
    ("cos(x + t)", lambda t, x, y, z: math.cos(x + t)),
    ("tan(x / 2)", lambda t, x, y, z: math.tan(x / 2)),
    ("asin(x / 3)", lambda t, x, y, z: math.asin(x / 3)),
    ("acos(x / 3)", lambda t, x, y, z: math.acos(x / 3)),
    ("atan(x * y)", lambda t, x, y, z: math.atan(x * y)),
    ("atan2(x, z)", lambda t, x, y, z: math.atan2(x, z)),
    ("atan2(z, x)", lambda t, x, y, z: math.atan2(z, x)),
    ("sinh(x)", lambda t, x, y, z: math.sinh(x)),
    ("cosh(x)", lambda t, x, y, z: math.cosh(x)),
    ("tanh(x)", lambda t, x, y, z: math.tanh(x)),
    ("exp(x)", lambda t, x, y, z: math.exp(x)),
    ("log(y)", lambda t, x, y, z: math.log(y)),
    ("log10(y)", lambda t, x, y, z: math.log10(y)),
    ("sqrt(y)", lambda t, x, y, z: math.sqrt(y)),
    ("abs(x)", lambda t, x, y, z: abs(x)),
    ("abs(z)", lambda t, x, y, z: abs(z)),
    ("min(x, z)", lambda t, x, y, z: min(x, z)),
    ("min(x, y, z)", lambda t, x, y, z: min(x, y, z)),
    ("max(x, z)", lambda t, x, y, z: max(x, z)),
    ("max(x, y, z, a)", lambda t, x, y, z: max(x, y, z, A)),
    ("floor(x)", lambda t, x, y, z: float(math.floor(x))),
    ("ceil(x)", lambda t, x, y, z: float(math.ceil(x))),
    ("sign(x)", lambda t, x, y, z: math.copysign(1.0, x) if x else 0.0),
    ("sign(z)", lambda t, x, y, z: (z > 0) - (z < 0) + 0.0),
    ("clip(x, -1, 1)", lambda t, x, y, z: max(-1.0, min(1.0, x))),
    ("clip(z, b, a)", lambda t, x, y, z: max(B, min(A, z))),
    ("hypot(x, y)", lambda t, x, y, z: math.hypot(x, y)),
    ("hypot(x, y, z)", lambda t, x, y, z: math.hypot(x, y, z)),
]

OPERATORS: list[Row] = [
    ("pi", lambda t, x, y, z: math.pi),
    ("t", lambda t, x, y, z: t),
    ("2*pi*t", lambda t, x, y, z: 2 * math.pi * t),
    ("1e-3 * x", lambda t, x, y, z: 1e-3 * x),
    ("x + y * z", lambda t, x, y, z: x + y * z),
    ("(x + y) * z", lambda t, x, y, z: (x + y) * z),
    ("-x**2", lambda t, x, y, z: -(x**2)),
    ("(-x)**2", lambda t, x, y, z: (-x) ** 2),
    ("-x**3", lambda t, x, y, z: -(x**3)),
    ("x**-1", lambda t, x, y, z: x**-1),
    ("2**-1", lambda t, x, y, z: 0.5),
    ("2**3**2", lambda t, x, y, z: 512.0),
    ("y**y**0.5", lambda t, x, y, z: y ** (y**0.5)),
    ("(y**2)**0.5", lambda t, x, y, z: (y**2) ** 0.5),
    ("y**1.5", lambda t, x, y, z: y**1.5),
    ("a - b - c", lambda t, x, y, z: A - B - C),
    ("x - y - z", lambda t, x, y, z: (x - y) - z),
    ("x - (y - z)", lambda t, x, y, z: x - (y - z)),
    ("x / y / a", lambda t, x, y, z: (x / y) / A),
    ("x / (y / a)", lambda t, x, y, z: x / (y / A)),
    ("x / y * a", lambda t, x, y, z: (x / y) * A),
    ("x * y / a", lambda t, x, y, z: (x * y) / A),
    ("-a", lambda t, x, y, z: -A),
    ("-b * x", lambda t, x, y, z: -B * x),
    ("x - -y", lambda t, x, y, z: x - -y),
    ("+x", lambda t, x, y, z: x),
    ("-(x - y)", lambda t, x, y, z: -(x - y)),
    ("0.5*y**2 + a*x", lambda t, x, y, z: 0.5 * y**2 + A * x),
    ("a*(b - x)", lambda t, x, y, z: A * (B - x)),
    ("sqrt(x**2 + y**2)", lambda t, x, y, z: math.sqrt(x**2 + y**2)),
    ("sin(x)**2 + cos(x)**2", lambda t, x, y, z: math.sin(x) ** 2 + math.cos(x) ** 2),
    ("exp(-t / a) * cos(2*pi*t)", lambda t, x, y, z: math.exp(-t / A) * math.cos(2 * math.pi * t)),
    ("sqrt(2)", lambda t, x, y, z: math.sqrt(2.0)),
    ("max(a, b) - min(a, c)", lambda t, x, y, z: max(A, B) - min(A, C)),
]

CONDITIONS: list[Row] = [
    ("x < y", lambda t, x, y, z: x < y),
    ("x <= z", lambda t, x, y, z: x <= z),
    ("x > z", lambda t, x, y, z: x > z),
    ("x >= -0.3", lambda t, x, y, z: x >= -0.3),
    ("z == 0", lambda t, x, y, z: z == 0),
    ("z != 0", lambda t, x, y, z: z != 0),
    ("x < y < z", lambda t, x, y, z: x < y < z),
    ("z <= x < y", lambda t, x, y, z: z <= x < y),
    ("-1 < x <= y != z", lambda t, x, y, z: -1 < x <= y != z),
    ("not x < y or z > 0", lambda t, x, y, z: (not (x < y)) or (z > 0)),
    ("not (x < y or z > 0)", lambda t, x, y, z: not (x < y or z > 0)),
    ("x < 0 or y > 1 and z > 0", lambda t, x, y, z: x < 0 or (y > 1 and z > 0)),
    ("(x < 0 or y > 1) and z > 0", lambda t, x, y, z: (x < 0 or y > 1) and z > 0),
    ("not not x > 0", lambda t, x, y, z: x > 0),
    ("x > 0 and not z < 0", lambda t, x, y, z: x > 0 and not z < 0),
    ("true", lambda t, x, y, z: True),
    ("false or x > 0", lambda t, x, y, z: x > 0),
    ("x*x - y >= a*b", lambda t, x, y, z: x * x - y >= A * B),
    ("t >= 1.5", lambda t, x, y, z: t >= 1.5),
]


def _compile(source: str, want: str) -> Callable[[float, list[float]], object]:
    node = parse_expression(source, SCOPE, want=want)
    return compile_function("f", [node], CTX, shape="scalar")


def _agree(got: float, want: float) -> bool:
    return got == want or math.isclose(got, want, rel_tol=1e-15, abs_tol=0.0)


@pytest.mark.parametrize(
    "source, expected", FUNCTIONS + OPERATORS, ids=[s for s, _ in FUNCTIONS + OPERATORS]
)
def test_number_expression_matches_python(
    source: str, expected: Callable[[float, float, float, float], float]
) -> None:
    f = _compile(source, "number")
    for t, x, y, z in POINTS:
        got = f(t, np.array([x, y, z]))
        want = expected(t, x, y, z)
        assert isinstance(got, float), (source, got)
        assert _agree(got, want), f"{source} at {(t, x, y, z)}: {got!r} != {want!r}"


@pytest.mark.parametrize("source, expected", CONDITIONS, ids=[s for s, _ in CONDITIONS])
def test_condition_matches_python(
    source: str, expected: Callable[[float, float, float, float], bool]
) -> None:
    f = _compile(source, "bool")
    for t, x, y, z in POINTS:
        got = f(t, np.array([x, y, z]))
        assert isinstance(got, bool | np.bool_), (source, got)
        assert bool(got) is expected(t, x, y, z), f"{source} at {(t, x, y, z)}"


def test_every_builtin_is_in_the_table() -> None:
    called = set()
    for source, _ in FUNCTIONS:
        node = parse_expression(source, SCOPE)
        called |= {n.func for n in ir.walk(node) if isinstance(n, ir.Call)}
    assert called == set(BUILTINS)


def test_conditions_are_not_constant_over_the_points() -> None:
    """The condition table is only a test if the points make most rows both true and false."""
    varied = 0
    for source, _ in CONDITIONS:
        f = _compile(source, "bool")
        varied += len({bool(f(t, np.array([x, y, z]))) for t, x, y, z in POINTS}) == 2
    assert varied >= len(CONDITIONS) - 3


@pytest.mark.parametrize(
    "source, value",
    [
        ("2**3**2", 512.0),
        ("2**-1", 0.5),
        ("-2**2", -4.0),
        ("(-2)**2", 4.0),
        ("10 - 4 - 3", 3.0),
        ("24 / 4 / 2", 3.0),
        ("sqrt(16) + abs(-2)", 6.0),
        ("pi", math.pi),
        ("hypot(3, 4)", 5.0),
        ("1e3", 1000.0),
        ("7", 7.0),
    ],
)
def test_constants_fold_at_load_time(source: str, value: float) -> None:
    node = parse_expression(source, SCOPE)
    assert node == ir.Num(value, node.col)
    assert isinstance(node.value, float)


@pytest.mark.parametrize(
    "source, says",
    [
        ("9**9**9**9", "overflows"),
        ("1 / 0", "division by zero"),
        ("sqrt(-1)", "math domain error"),
        ("log(0)", "math domain error"),
        ("1e308 * 10", "not finite"),
    ],
)
def test_bad_constants_are_refused_at_load_time(source: str, says: str) -> None:
    with pytest.raises(ExprError) as info:
        parse_expression(source, SCOPE)
    assert says in info.value.message


def test_integers_become_floats() -> None:
    """Every number is a float: integer arithmetic can neither hang nor give an int result."""
    f = _compile("x * 2 + 1", "number")
    assert f(0.0, np.array([3.0, 0.0, 0.0])) == 7.0
    assert isinstance(f(0.0, np.array([3.0, 0.0, 0.0])), float)
    node = parse_expression("2**64", SCOPE)
    assert isinstance(node, ir.Num) and node.value == 2.0**64


def test_compiled_source_reads_as_the_expression() -> None:
    node = parse_expression("-x**2 + a*(y - z)", SCOPE)
    assert to_source(node, {"x": "x", "y": "y", "z": "z", "a": "a"}) == "-x ** 2 + a * (y - z)"


def test_math_error_at_run_time_gives_nan_and_is_recorded() -> None:
    ctx = CodeContext(states=("x", "y", "z"), params={"a": A, "b": B, "c": C})
    f = compile_function("rhs", [parse_expression("sqrt(x)", SCOPE)], ctx, shape="scalar")
    assert math.isnan(f(2.0, np.array([-1.0, 0.0, 0.0])))
    assert isinstance(ctx.failure.error, ValueError)
    assert (ctx.failure.t, ctx.failure.where) == (2.0, "rhs")


@pytest.mark.parametrize("name", sorted(BUILTINS))
def test_builtins_accept_numpy_scalars(name: str) -> None:
    """Compiled code may pass numpy scalars (array items): same result as with floats."""
    func = BUILTINS[name]
    n = max(func.min_args, 1)
    calls = [[0.3, 0.2, 0.9][:n], [-0.3, 0.2, 0.9][:n], [0.0, 0.2, 0.9][:n]]
    if name == "clip":
        calls = [[0.3, -0.5, 0.25], [-0.7, -0.5, 0.25], [0.0, -0.5, 0.25]]
    if name in ("log", "log10", "sqrt"):
        calls = calls[:1]
    for args in calls:
        want = func.fn(*args)
        got = func.fn(*(np.float64(a) for a in args))
        assert float(got) == float(want), (name, args)
