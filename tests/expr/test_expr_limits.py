"""The expression limits, exactly at and just over each one."""

from __future__ import annotations

from collections.abc import Callable

import pytest

from hybrid.expr.parse import MAX_DEPTH, MAX_SOURCE_CHARS, ExprError, Scope, parse_expression

SCOPE = Scope(variables={"x": "state"})


def test_limits_are_as_documented() -> None:
    assert (MAX_SOURCE_CHARS, MAX_DEPTH) == (4000, 64)


def test_length_limit() -> None:
    flat = "max(" + ", ".join(["x"] * 999) + ")"
    flat += " " * (MAX_SOURCE_CHARS - len(flat))
    assert len(flat) == MAX_SOURCE_CHARS
    parse_expression(flat, SCOPE)
    with pytest.raises(ExprError) as info:
        parse_expression(flat + " ", SCOPE)
    assert info.value.message == (
        f"expression is {MAX_SOURCE_CHARS + 1} characters long, over the limit of 4000"
    )
    assert info.value.col == 0


@pytest.mark.parametrize(
    "build, width",
    [
        (lambda n: "-" * (n - 1) + "x", 1),  # n levels: n - 1 negations and x
        (lambda n: "sin(" * (n - 1) + "x" + ")" * (n - 1), 4),
        (lambda n: "2**" * (n - 1) + "x", 3),
    ],
    ids=["negation", "calls", "powers"],
)
def test_depth_limit(build: Callable[[int], str], width: int) -> None:
    parse_expression(build(MAX_DEPTH), SCOPE)
    with pytest.raises(ExprError) as info:
        parse_expression(build(MAX_DEPTH + 1), SCOPE)
    assert info.value.message == "expression is nested more than 64 levels deep"
    assert info.value.col == width * MAX_DEPTH  # the first node over the limit


def test_depth_column_counts_leading_spaces() -> None:
    with pytest.raises(ExprError) as info:
        parse_expression("   " + "-" * MAX_DEPTH + "x", SCOPE)
    assert info.value.col == 3 + MAX_DEPTH


def test_python_parser_limits_are_refused_too() -> None:
    with pytest.raises(ExprError, match="too many nested parentheses"):
        parse_expression("(" * 201 + "x" + ")" * 201, SCOPE)
    with pytest.raises(ExprError, match="nested too deeply to be parsed"):
        parse_expression("-" * 3999 + "x", SCOPE)


def test_parentheses_are_not_levels() -> None:
    node = parse_expression("(" * 150 + "x" + ")" * 150, SCOPE)
    assert (node.name, node.kind) == ("x", "state")  # type: ignore[union-attr]


@pytest.mark.parametrize("source", ["1e400", "x + 1e309", "x <= 2e308", str(10**400)])
def test_a_number_too_large_for_a_float_is_refused_where_it_is_written(source: str) -> None:
    # 1e400 read as inf: validate said ok and the run ended nonfinite at t = 0
    with pytest.raises(ExprError) as info:
        parse_expression(source, Scope({"x": "state"}), want="bool" if "<=" in source else "number")
    assert info.value.message == "number literal is too large for a 64-bit float (at most about 1.8e308)"
    assert info.value.col == source.index(source.split()[-1])


def test_the_largest_float_is_still_a_number() -> None:
    parse_expression("x <= 1.7e308", Scope({"x": "state"}), want="bool")
