"""The SpaceEx expression language: tokens and a parser into a small tree with positions.

SpaceEx writes flows as ``x' == e``, assignments as ``x := e`` (or ``x' == e``),
conditions with ``&`` / ``&&`` (and ``|`` / ``||``), powers with ``^``, and
comparison chains such as ``-0.1 <= w <= 0.1``. The ``.cfg`` file adds
``loc(component) == name`` and dotted names (``osc.osci.y``). The parser keeps
the file position of every node so that a refusal points at the user's text.
It never evaluates anything.

Examples
--------
>>> from hybrid.interchange.safexml import SourceText
>>> tree = parse(SourceText("m.xml", "x' == v & v' == -g*x^2"))
>>> [type(n).__name__ for n in tree.items]
['Cmp', 'Cmp']
>>> tree.items[0].operands[0]
Name(name='x', primed=True, position=Position(file='m.xml', line=1, column=1))
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from hybrid.errors import Position, SpecError
from hybrid.interchange.safexml import SourceText

__all__ = [
    "MAX_NODES",
    "And",
    "Assign",
    "BinOp",
    "Bool",
    "Call",
    "Cmp",
    "Interval",
    "Loc",
    "Name",
    "Neg",
    "Node",
    "Num",
    "Or",
    "conjuncts",
    "parse",
]

MAX_NODES = 20_000
"""Most tokens accepted in one expression (a guard of a big model has a few hundred)."""
MAX_NESTING = 64
"""Deepest parenthesis nesting accepted."""


@dataclass(frozen=True)
class Num:
    value: float
    position: Position


@dataclass(frozen=True)
class Bool:
    value: bool
    position: Position


@dataclass(frozen=True)
class Name:
    """A variable; ``primed`` for ``x'`` (the derivative in a flow, the new value in a jump)."""

    name: str
    primed: bool
    position: Position


@dataclass(frozen=True)
class Call:
    func: str
    args: tuple[Node, ...]
    position: Position


@dataclass(frozen=True)
class Neg:
    operand: Node
    position: Position


@dataclass(frozen=True)
class BinOp:
    """``+ - * / ^``."""

    op: str
    left: Node
    right: Node
    position: Position


@dataclass(frozen=True)
class Cmp:
    """A comparison chain; ``ops`` from ``== != <= >= < >``.

    ``single`` marks ``a = b`` written with one ``=`` (read as ``==``, except in an
    ``<assignment>``, where ``x = e`` is the reset ``x := e``).
    """

    ops: tuple[str, ...]
    operands: tuple[Node, ...]
    position: Position
    single: bool = False


@dataclass(frozen=True)
class And:
    items: tuple[Node, ...]
    position: Position


@dataclass(frozen=True)
class Or:
    items: tuple[Node, ...]
    position: Position


@dataclass(frozen=True)
class Assign:
    """``x := e``."""

    target: Name
    value: Node
    position: Position


@dataclass(frozen=True)
class Interval:
    """``[lo, hi]``: a range, as in ``x := [0, 1]`` (refused where it has no counterpart)."""

    lo: Node
    hi: Node
    position: Position


@dataclass(frozen=True)
class Loc:
    """``loc(component)`` (``loc()`` for the only component) in a ``.cfg`` condition."""

    component: str
    position: Position


Node = Num | Bool | Name | Call | Neg | BinOp | Cmp | And | Or | Assign | Interval | Loc

_TOKEN = re.compile(
    r"""
    (?P<space>\s+)
  | (?P<num>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)
  | (?P<name>[A-Za-z_][A-Za-z0-9_]*(?:\.[A-Za-z_][A-Za-z0-9_]*)*'?)
  | (?P<op>:=|==|!=|<=|>=|&&|\|\||[-+*/^()<>&|,\[\]=!'])
    """,
    re.VERBOSE,
)
_RELOPS = {"==", "!=", "<=", ">=", "<", ">", "="}


@dataclass(frozen=True)
class _Token:
    kind: str
    text: str
    offset: int


def _tokens(source: SourceText) -> list[_Token]:
    text = source.text
    found: list[_Token] = []
    at = 0
    while at < len(text):
        match = _TOKEN.match(text, at)
        if match is None:
            raise SpecError(
                f"unexpected character {text[at]!r} in a SpaceEx expression", source.where(at)
            )
        kind = match.lastgroup or "op"
        if kind != "space":
            found.append(_Token(kind, match.group(), at))
            if len(found) > MAX_NODES:
                raise SpecError(
                    f"expression has more than {MAX_NODES} tokens: refused", source.where(at)
                )
        at = match.end()
    return found


class _Parser:
    def __init__(self, source: SourceText) -> None:
        self.source = source
        self.tokens = _tokens(source)
        self.i = 0
        self.depth = 0

    # --- helpers -------------------------------------------------------------------------

    def peek(self) -> _Token | None:
        return self.tokens[self.i] if self.i < len(self.tokens) else None

    def at(self, token: _Token | None) -> Position:
        if token is None:
            return self.source.where(len(self.source.text))
        return self.source.where(token.offset)

    def take(self, *texts: str) -> _Token | None:
        token = self.peek()
        if token is not None and token.kind == "op" and token.text in texts:
            self.i += 1
            return token
        return None

    def expect(self, text: str, what: str) -> _Token:
        token = self.take(text)
        if token is None:
            found = self.peek()
            shown = f"'{found.text}'" if found else "the end"
            raise SpecError(f"expected {what}, found {shown}", self.at(found))
        return token

    # --- grammar -------------------------------------------------------------------------

    def whole(self) -> Node:
        if not self.tokens:
            return And((), self.source.where(0))
        node = self.disjunction()
        extra = self.peek()
        if extra is not None:
            hint = ""
            if extra.kind == "name" and extra.text == "with":
                hint = (
                    ": 'with offset support_function(...)' is SpaceEx's flattened form of a "
                    "nondeterministic input and has no counterpart; import the model before "
                    "flattening (the file with the original components)"
                )
            raise SpecError(f"unexpected '{extra.text}'{hint}", self.at(extra))
        return node

    def disjunction(self) -> Node:
        first = self.peek()
        items = [self.conjunction()]
        while self.take("|", "||"):
            items.append(self.conjunction())
        return items[0] if len(items) == 1 else Or(tuple(items), self.at(first))

    def conjunction(self) -> Node:
        first = self.peek()
        items = [self.comparison()]
        while self.take("&", "&&"):
            items.append(self.comparison())
        return items[0] if len(items) == 1 else And(tuple(items), self.at(first))

    def comparison(self) -> Node:
        first = self.peek()
        left = self.sum()
        if self.take(":="):
            if not isinstance(left, Name) or left.primed:
                raise SpecError("the left side of ':=' must be a variable", self.at(first))
            return Assign(left, self.sum(), self.at(first))
        ops: list[str] = []
        written: list[str] = []
        operands = [left]
        while (token := self.peek()) is not None and token.kind == "op" and token.text in _RELOPS:
            self.i += 1
            written.append(token.text)
            ops.append("==" if token.text == "=" else token.text)
            operands.append(self.sum())
        if not ops:
            return left
        return Cmp(tuple(ops), tuple(operands), self.at(first), written == ["="])

    def sum(self) -> Node:
        first = self.peek()
        node = self.product()
        while (token := self.take("+", "-")) is not None:
            node = BinOp(token.text, node, self.product(), self.at(first))
        return node

    def product(self) -> Node:
        first = self.peek()
        node = self.unary()
        while (token := self.take("*", "/")) is not None:
            node = BinOp(token.text, node, self.unary(), self.at(first))
        return node

    def unary(self) -> Node:
        token = self.peek()
        if self.take("-"):
            return Neg(self.unary(), self.at(token))
        if self.take("+"):
            return self.unary()
        if self.take("!"):
            raise SpecError("'!' (negation) is not supported in SpaceEx conditions", self.at(token))
        return self.power()

    def power(self) -> Node:
        first = self.peek()
        base = self.primary()
        if self.take("^"):
            return BinOp("^", base, self.unary(), self.at(first))
        return base

    def primary(self) -> Node:
        token = self.peek()
        if token is None:
            raise SpecError("expression ends too early", self.at(None))
        where = self.at(token)
        if token.kind == "num":
            self.i += 1
            return Num(float(token.text), where)
        if token.kind == "name":
            self.i += 1
            return self.named(token, where)
        if self.take("("):
            self.nest(token)
            node = self.disjunction()
            self.expect(")", "')'")
            self.depth -= 1
            return node
        if self.take("["):
            self.nest(token)
            lo = self.sum()
            self.expect(",", "',' between the ends of a range [lo, hi]")
            hi = self.sum()
            self.expect("]", "']'")
            self.depth -= 1
            return Interval(lo, hi, where)
        raise SpecError(f"unexpected '{token.text}'", where)

    def named(self, token: _Token, where: Position) -> Node:
        text = token.text
        primed = text.endswith("'")
        name = text.rstrip("'")
        if primed:
            return Name(name, True, where)
        if name in ("true", "false"):
            return Bool(name == "true", where)
        if self.peek() is not None and self.take("("):
            self.nest(token)
            if name == "loc":
                inner = self.peek()
                component = ""
                if inner is not None and inner.kind == "name":
                    self.i += 1
                    component = inner.text
                self.expect(")", "')' after loc(component")
                self.depth -= 1
                return Loc(component, where)
            args: list[Node] = []
            if not self.take(")"):
                args.append(self.disjunction())
                while self.take(","):
                    args.append(self.disjunction())
                self.expect(")", f"')' closing the call of {name}")
            self.depth -= 1
            return Call(name, tuple(args), where)
        return Name(name, False, where)

    def nest(self, token: _Token) -> None:
        self.depth += 1
        if self.depth > MAX_NESTING:
            raise SpecError(
                f"expression nested more than {MAX_NESTING} levels deep: refused", self.at(token)
            )


def parse(source: SourceText) -> Node:
    """Parse SpaceEx text (a flow, invariant, guard, assignment or ``.cfg`` condition).

    An empty text is an empty conjunction (``true``).

    Raises
    ------
    SpecError
        At the position of the first character that does not fit the grammar.
    """
    return _Parser(source).whole()


def conjuncts(node: Node) -> list[Node]:
    """The items of a top-level conjunction (``[node]`` for anything else).

    A ``true`` item is dropped (``true && x' <= 2`` is ``x' <= 2``), so what
    follows is read, and refused, for what it is.
    """
    if isinstance(node, And):
        found: list[Node] = []
        for item in node.items:
            found.extend(conjuncts(item))
        return found
    if isinstance(node, Bool) and node.value:
        return []
    return [node]
