"""Guards as real-valued functions: ``rho < 0`` exactly where the guard holds (off rho = 0).

The property: compile the boolean guard (``holds``) and its rho expression
(``hybrid.expr.rho.guard_to_rho``); wherever rho is not zero, ``rho < 0`` is
``holds``. On ``rho == 0`` the boolean form decides, and strict and non-strict
comparisons differ there (docs/spec-language.md, "Guards and rho").
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from hybrid.expr import ir
from hybrid.expr.codegen import CodeContext, compile_function
from hybrid.expr.parse import Scope, parse_expression
from hybrid.expr.rho import guard_to_rho, is_strict

NAMES = ("x", "y", "z")
SCOPE = Scope(variables={"x": "state", "y": "state", "z": "state", "k": "param"})
CTX = CodeContext(states=NAMES, params={"k": 2.0})

TERMS = [
    "x",
    "y",
    "z",
    "0",
    "1",
    "-2.5",
    "k",
    "2*x - y + 0.5",
    "x + y + z",
    "x - z",
    "x*y",
    "x**2",
    "y**3 - z",
    "x*y - z**2",
    "sin(x)",
    "abs(y) - 1",
    "max(x, z)",
    "k*x - y/4",
]
OPS = ["<", "<=", ">", ">=", "==", "!="]


def _comparison() -> st.SearchStrategy[str]:
    pair = st.tuples(st.sampled_from(TERMS), st.sampled_from(OPS), st.sampled_from(TERMS)).map(
        lambda p: f"{p[0]} {p[1]} {p[2]}"
    )
    chain = st.tuples(
        st.sampled_from(TERMS),
        st.sampled_from(OPS),
        st.sampled_from(TERMS),
        st.sampled_from(OPS),
        st.sampled_from(TERMS),
    ).map(lambda p: " ".join(p))
    return st.one_of(pair, pair, chain, st.sampled_from(["true", "false"]))


def _combine(children: st.SearchStrategy[str]) -> st.SearchStrategy[str]:
    return st.one_of(
        st.tuples(children, st.sampled_from(["and", "or"]), children).map(
            lambda p: f"({p[0]}) {p[1]} ({p[2]})"
        ),
        children.map(lambda c: f"not ({c})"),
    )


GUARDS = st.recursive(_comparison(), _combine, max_leaves=6)
# Small integers and halves hit boundaries (x == y, x*y == z, ...); floats cover the rest.
COORD = st.one_of(
    st.integers(-3, 3).map(float),
    st.sampled_from([-0.5, 0.5, 1.5, -0.0]),
    st.floats(-10, 10, allow_nan=False, allow_infinity=False),
)
POINT = st.tuples(COORD, COORD, COORD)


def _compiled(source: str) -> tuple[Callable[..., object], Callable[..., object]]:
    guard = parse_expression(source, SCOPE, want="bool")
    holds = compile_function("holds", [guard], CTX, shape="scalar")
    rho = compile_function("rho", [guard_to_rho(guard)], CTX, shape="scalar")
    return holds, rho


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(source=GUARDS, points=st.lists(POINT, min_size=1, max_size=8))
@example(source="x <= 0 and y < 0", points=[(0.0, -1.0, 0.0), (-1.0, 0.0, 0.0)])
@example(source="not (x < y < z)", points=[(1.0, 1.0, 2.0), (0.0, 1.0, 2.0)])
@example(source="x == y or not (z != 1)", points=[(1.0, 1.0, 1.0), (0.5, 1.0, 1.0)])
def test_rho_sign_decides_the_guard_off_the_boundary(
    source: str, points: list[tuple[float, float, float]]
) -> None:
    holds, rho = _compiled(source)
    for point in points:
        h = holds(0.0, np.array(point))
        r = rho(0.0, np.array(point))
        assert isinstance(h, bool | np.bool_)
        h = bool(h)
        assert isinstance(r, float) and not math.isnan(r), (source, point, r)
        r = float(r)
        if r != 0.0:
            assert (r < 0.0) is h, f"{source} at {point}: rho={r!r}, holds={h}"


@pytest.mark.parametrize(
    "source, holds_at_zero",
    [
        ("x <= 0", True),  # non-strict: holds on its boundary
        ("x >= 0", True),
        ("x < 0", False),  # strict: does not hold on its boundary
        ("x > 0", False),
        ("not (x < 0)", True),  # the negation of a strict comparison is non-strict
        ("not (x <= 0)", False),
        ("x == 0", True),
        ("x != 0", False),
        ("0 <= x", True),
        ("0 < x", False),
    ],
)
def test_on_the_boundary_the_boolean_form_decides(source: str, holds_at_zero: bool) -> None:
    """rho is 0 on the boundary for strict and non-strict alike; ``holds`` tells them apart."""
    holds, rho = _compiled(source)
    assert rho(0.0, np.array([0.0, 0.0, 0.0])) == 0.0
    assert bool(holds(0.0, np.array([0.0, 0.0, 0.0]))) is holds_at_zero
    # just off the boundary, rho's sign agrees with the guard
    for x in (-1e-300, 1e-300, -1.0, 1.0):
        r = float(rho(0.0, np.array([x, 0.0, 0.0])))
        h = bool(holds(0.0, np.array([x, 0.0, 0.0])))
        assert r != 0.0 and (r < 0.0) is h, (source, x, r, h)


@pytest.mark.parametrize(
    "source, rho_source",
    [
        ("x <= y", "x - y"),
        ("x < y", "x - y"),
        ("x >= y", "y - x"),
        ("x > y", "y - x"),
        ("x <= 0", "x"),
        ("0 < x", "-x"),
        ("x == y", "abs(x - y)"),
        ("x != y", "-abs(x - y)"),
        ("x <= 0 and y <= 0", "max(x, y)"),
        ("x <= 0 or y <= 0", "min(x, y)"),
        ("not (x <= 0)", "-x"),
        ("x < y < z", "max(x - y, y - z)"),
    ],
)
def test_rho_rewrite_table(source: str, rho_source: str) -> None:
    """The rewrite of DESIGN.md: <= to a - b, and to max, or to min, not to negation."""
    guard = parse_expression(source, SCOPE, want="bool")
    expected = parse_expression(rho_source, SCOPE)
    assert _strip_cols(guard_to_rho(guard)) == _strip_cols(expected)


def test_true_and_false_have_constant_rho() -> None:
    true = parse_expression("true", SCOPE, want="bool")
    false = parse_expression("false", SCOPE, want="bool")
    assert guard_to_rho(true) == ir.Num(-1.0, 0)
    assert guard_to_rho(false) == ir.Num(1.0, 0)


@pytest.mark.parametrize(
    "source, strict",
    [("x < 0", True), ("x > y", True), ("x != 1", True), ("x <= 0", False), ("x == 1", False)],
)
def test_is_strict(source: str, strict: bool) -> None:
    assert is_strict(parse_expression(source, SCOPE, want="bool")) is strict


def _strip_cols(node: ir.Expr) -> ir.Expr:
    """The same tree with every column set to 0 (columns differ between sources)."""
    from dataclasses import replace

    if isinstance(node, ir.Call):
        return replace(node, col=0, args=tuple(_strip_cols(a) for a in node.args))
    if isinstance(node, ir.Unary | ir.Not):
        return replace(node, col=0, operand=_strip_cols(node.operand))
    if isinstance(node, ir.Bin):
        return replace(node, col=0, left=_strip_cols(node.left), right=_strip_cols(node.right))
    if isinstance(node, ir.Cmp):
        return replace(node, col=0, operands=tuple(_strip_cols(a) for a in node.operands))
    if isinstance(node, ir.BoolOp):
        return replace(node, col=0, values=tuple(_strip_cols(a) for a in node.values))
    return replace(node, col=0)


@pytest.mark.parametrize(
    "source, value",
    [("0 >= 0", -1.0), ("1 < 0", 1.0), ("x < x", 1.0), ("x <= x", -1.0), ("x*y == x*y", -1.0)],
)
def test_a_comparison_that_cannot_change_has_the_rho_of_a_constant(
    source: str, value: float
) -> None:
    # its a - b would be 0 everywhere: a rho that touches 0 and never crosses it
    guard = parse_expression(source, SCOPE, want="bool")
    assert _strip_cols(guard_to_rho(guard)) == ir.Num(value, 0)
    rho = guard_to_rho(parse_expression(f"x <= 1 and {source}", SCOPE, want="bool"))
    expected = ir.Call("max", (parse_expression("x - 1", SCOPE), ir.Num(value)))
    assert _strip_cols(rho) == _strip_cols(expected)
