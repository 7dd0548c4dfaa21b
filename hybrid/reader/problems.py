"""Problems found while building a model, each at its place in the file.

Building collects every problem it finds (a name used twice, an unknown
location, a bad expression) with its position, and raises them all together
as one :class:`~hybrid.errors.SpecError`.
"""

from __future__ import annotations

from typing import Any

from hybrid.errors import Position
from hybrid.expr import ir
from hybrid.expr.parse import ExprError, Scope, parse_expression
from hybrid.reader.characters import ascii_only
from hybrid.reader.yamlpos import PositionMap

__all__ = ["Problems"]


class Problems:
    """The problems found so far, with the positions of the document being built."""

    def __init__(self, positions: PositionMap) -> None:
        self.positions = positions
        self.items: list[tuple[Position, str]] = []

    def at_key(self, path: tuple[Any, ...], message: str) -> None:
        self.items.append((self.positions.key(path), message))

    def at_value(self, path: tuple[Any, ...], message: str) -> None:
        self.items.append((self.positions.value(path), message))

    def expression(self, path: tuple[Any, ...], source: str, scope: Scope, want: str) -> ir.Expr:
        """``source`` parsed in ``scope``; a problem at its place (and a stand-in) if it fails."""
        try:
            ascii_only(source)
            return parse_expression(source, scope, want=want)
        except ExprError as exc:
            self.items.append((self.positions.value(path).shifted(exc.col), exc.message))
            return ir.BoolConst(True) if want == "bool" else ir.Num(0.0)
