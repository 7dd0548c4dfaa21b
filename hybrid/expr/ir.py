"""The expression IR: a small, typed tree that every later stage reads.

Parsing (:mod:`hybrid.expr.parse`) turns checked Python ``ast`` into these
nodes; code generation, guard-to-rho rewriting and interval evaluation all walk
them. Every node keeps the column where it starts in its source text.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

__all__ = [
    "Bin",
    "BoolConst",
    "BoolOp",
    "Call",
    "Cmp",
    "Expr",
    "Index",
    "Not",
    "Num",
    "Unary",
    "Var",
    "children",
    "names_in",
    "walk",
]

# Variable kinds a name can resolve to.
STATE, PARAM, SIGNAL, INPUT, TIME, CONST = "state", "param", "signal", "input", "time", "const"


@dataclass(frozen=True, slots=True)
class Num:
    value: float
    col: int = 0


@dataclass(frozen=True, slots=True)
class BoolConst:
    value: bool
    col: int = 0


@dataclass(frozen=True, slots=True)
class Var:
    name: str
    kind: str
    col: int = 0


@dataclass(frozen=True, slots=True)
class Index:
    """``name[k]``: component ``k`` of a vector-valued signal."""

    name: str
    index: int
    col: int = 0


@dataclass(frozen=True, slots=True)
class Call:
    func: str
    args: tuple[Expr, ...]
    col: int = 0


@dataclass(frozen=True, slots=True)
class Unary:
    """Arithmetic negation (``op`` is ``"-"``)."""

    op: str
    operand: Expr
    col: int = 0


@dataclass(frozen=True, slots=True)
class Bin:
    """``+ - * / **``."""

    op: str
    left: Expr
    right: Expr
    col: int = 0


@dataclass(frozen=True, slots=True)
class Cmp:
    """A comparison chain ``a < b <= c`` (``ops`` has one fewer item than ``operands``)."""

    ops: tuple[str, ...]
    operands: tuple[Expr, ...]
    col: int = 0


@dataclass(frozen=True, slots=True)
class BoolOp:
    """``and`` / ``or`` of two or more boolean operands."""

    op: str
    values: tuple[Expr, ...]
    col: int = 0


@dataclass(frozen=True, slots=True)
class Not:
    operand: Expr
    col: int = 0


Expr = Num | BoolConst | Var | Index | Call | Unary | Bin | Cmp | BoolOp | Not


def children(node: Expr) -> tuple[Expr, ...]:
    """The direct sub-expressions of ``node``."""
    if isinstance(node, Call):
        return node.args
    if isinstance(node, Unary | Not):
        return (node.operand,)
    if isinstance(node, Bin):
        return (node.left, node.right)
    if isinstance(node, Cmp):
        return node.operands
    if isinstance(node, BoolOp):
        return node.values
    return ()


def walk(node: Expr) -> Iterator[Expr]:
    """Every node of the tree, parents before children (iterative: no recursion limit)."""
    stack = [node]
    while stack:
        current = stack.pop()
        yield current
        stack.extend(reversed(children(current)))


def names_in(node: Expr, kind: str | None = None) -> set[str]:
    """Names of variables (and indexed signals) used in ``node``, optionally of one kind."""
    found: set[str] = set()
    for n in walk(node):
        if (isinstance(n, Var) and (kind is None or n.kind == kind)) or (
            isinstance(n, Index) and kind in (None, SIGNAL)
        ):
            found.add(n.name)
    return found
