"""Affine forms of SpaceEx expression trees: ``a * x + b`` in one variable.

The importer reads several constructs as affine in one variable: the bounds of
an initial set (``2 <= x + 1``), a rate bounded by numbers (``x' >= a``). What
counts as the variable and what as a constant differs (an unprimed name, or a
primed one; numbers only, or named constants too), and is said by a ``leaf``
function; the algebra is one.

Examples
--------
>>> from hybrid.interchange.safexml import SourceText
>>> from hybrid.interchange.sxexpr import parse
>>> def leaf(n):
...     if isinstance(n, sx.Num):
...         return None, 0.0, n.value
...     if isinstance(n, sx.Name):
...         return n.name, 1.0, 0.0
...     return None
>>> affine_form(parse(SourceText("m.xml", "2*(x - 1)/4")), leaf)
('x', 0.5, -0.5)
"""

from __future__ import annotations

from collections.abc import Callable

from hybrid.interchange import sxexpr as sx
from hybrid.interchange.translate import constant_value

__all__ = ["Affine", "affine_form"]

Affine = tuple[str | None, float, float]
"""``(x, a, b)``: ``a * x + b``, with ``x`` ``None`` (and ``a`` 0) for a number."""


def affine_form(node: sx.Node, leaf: Callable[[sx.Node], Affine | None]) -> Affine | None:
    """``(x, a, b)`` for ``a * x + b`` in one variable (``x`` ``None`` for a number), else ``None``.

    ``leaf(node)`` says what a node is on its own (the variable, a constant) or
    ``None``; sums, differences, negation, products and quotients by a constant,
    and powers of constants are combined here.
    """
    found = leaf(node)
    if found is not None:
        return found
    if isinstance(node, sx.Neg):
        inner = affine_form(node.operand, leaf)
        return None if inner is None else (inner[0], -inner[1], -inner[2])
    if isinstance(node, sx.BinOp):
        left, right = affine_form(node.left, leaf), affine_form(node.right, leaf)
        if left is None or right is None:
            return None
        if node.op in "+-":
            sign = 1.0 if node.op == "+" else -1.0
            if left[0] and right[0] and left[0] != right[0]:
                return None
            return left[0] or right[0], left[1] + sign * right[1], left[2] + sign * right[2]
        if node.op == "*" and (left[0] is None or right[0] is None):
            k, other = (left[2], right) if left[0] is None else (right[2], left)
            return other[0], k * other[1], k * other[2]
        if node.op == "/" and right[0] is None and right[2] != 0:
            return left[0], left[1] / right[2], left[2] / right[2]
        if node.op == "^" and left[0] is None and right[0] is None:
            value = constant_value(node, {})
            return None if value is None else (None, 0.0, value)
    return None
