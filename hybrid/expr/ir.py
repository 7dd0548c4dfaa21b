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
    """Names of variables (and indexed signals) used in ``node``, optionally of one kind.

    >>> sum_ = Bin("+", Var("x", STATE), Bin("*", Var("k", PARAM), Index("v", 1)))
    >>> sorted(names_in(sum_)), sorted(names_in(sum_, SIGNAL)), sorted(names_in(sum_, PARAM))
    (['k', 'v', 'x'], ['v'], ['k'])
    """
    uses = _uses(node)
    if kind is None:
        return {name for name, _ in uses}
    if kind == SIGNAL:
        return {name for name, k in uses if k in (SIGNAL, _INDEXED)}
    return {name for name, k in uses if k == kind}


_INDEXED = "indexed"
"""The kind :func:`_uses` gives an indexed signal (``names_in`` counts it as a signal)."""
_NO_USES: frozenset[tuple[str, str]] = frozenset()
_USES: dict[int, tuple[Expr, frozenset[tuple[str, str]]]] = {}
"""The names (with kinds) each composite node uses, by the node's identity (the node held)."""
_USES_MAX = 1 << 16
"""Composite nodes remembered at most, then all forgotten (65,536 entries of small sums and
products took 26 MB, measured; the nodes are kept alive with them)."""


def _uses(root: Expr) -> frozenset[tuple[str, str]]:
    """Every ``(name, kind)`` in ``root``, remembered per composite node.

    Code generation asks again for the same definitions in every function and mode
    it compiles, and a model whose parameters change keeps its sub-expressions that
    read none (:func:`~hybrid.expr.transform.bind_parameters` shares them): their
    names are found once. Iterative, as :func:`walk` is.
    """
    found = _USES.get(id(root))
    if found is not None and found[0] is root:
        return found[1]
    done: dict[int, frozenset[tuple[str, str]]] = {}
    stack: list[tuple[Expr, bool]] = [(root, False)]
    while stack:
        node, expanded = stack.pop()
        if isinstance(node, Var):
            done[id(node)] = frozenset(((node.name, node.kind),))
            continue
        if isinstance(node, Index):
            done[id(node)] = frozenset(((node.name, _INDEXED),))
            continue
        below = children(node)
        if not below:
            done[id(node)] = _NO_USES
        elif expanded:
            parts = [done[id(b)] for b in below]
            uses = frozenset().union(*parts)
            # a child that reads every name gives its set: one set object for many nodes
            uses = next((part for part in parts if len(part) == len(uses)), uses)
            done[id(node)] = uses
            if len(_USES) >= _USES_MAX:
                _USES.clear()
            _USES[id(node)] = (node, uses)
        else:
            found = _USES.get(id(node))
            if found is not None and found[0] is node:
                done[id(node)] = found[1]
                continue
            stack.append((node, True))
            stack.extend((b, False) for b in below)
    return done[id(root)]
