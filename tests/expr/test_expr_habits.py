"""The reader's names for C and MATLAB habits, where the command-line test cannot reach them.

A vector signal called as MATLAB indexes it, and the scan for a number written
against a name, which must leave every number Python reads (exponents, a
leading or trailing point) alone: a wrong "write '1 * e5'" would be worse than
Python's own message.
"""

from __future__ import annotations

import pytest

from hybrid.expr.habits import habit
from hybrid.expr.parse import ExprError, Scope, parse_expression


def test_a_vector_signal_called_as_in_matlab_is_indexed_from_0() -> None:
    scope = Scope({"x": "state", "s": "signal"}, vectors={"s": 3})
    with pytest.raises(ExprError) as caught:
        parse_expression("x + s(1)", scope)
    assert str(caught.value) == (
        "'s' is a vector of 3 values, not a function: pick one with s[k], from 0 "
        "(MATLAB's s(1) is s[0])"
    )
    assert caught.value.col == 4


@pytest.mark.parametrize(
    ("text", "culprit"),
    [
        ("2x", "'2x' is not a product here: write '2 * x'"),
        ("1e5x", "'1e5x' is not a product here: write '1e5 * x'"),
        ("a + .5b", "'.5b' is not a product here: write '.5 * b'"),
        ("1.e-3y && z", "'1.e-3y' is not a product here: write '1.e-3 * y'"),
        ("1e5 && x", "'&&' is not an operator here: write 'and'"),  # 1e5 is a number
        ("x2y && z", "'&&' is not an operator here: write 'and'"),  # x2y is a name
        ("a.b2c && z", "'&&' is not an operator here: write 'and'"),
    ],
)
def test_a_number_against_a_name_is_found_and_numbers_are_left_alone(
    text: str, culprit: str
) -> None:
    found = habit(text)
    assert found is not None and found[0] == culprit
