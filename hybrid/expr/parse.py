"""Parse expression source into checked IR: the allow-list lives here.

Source is parsed by Python's ``ast`` (in ``eval`` mode) and then every node is
checked against a short allow-list; anything else is refused with the column
where it starts. Names must resolve in a :class:`Scope`. Expressions are typed
(number or boolean) and constant sub-expressions are folded in floating point,
so ``9**9**9**9`` is refused at load time as an overflow instead of hanging.

Examples
--------
>>> scope = Scope(variables={"h": "state", "g": "param"})
>>> parse_expression("2*g", scope)
Bin(op='*', left=Num(value=2.0, col=0), right=Var(name='g', kind='param', col=2), col=0)
>>> parse_expression("2**0.5", scope)
Num(value=1.4142135623730951, col=0)
"""

from __future__ import annotations

import ast
import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field

from hybrid.errors import did_you_mean
from hybrid.expr import ir
from hybrid.expr.functions import BUILTINS, Function
from hybrid.expr.habits import function_habit, habit

__all__ = [
    "MAX_DEPTH",
    "MAX_SOURCE_CHARS",
    "ExprError",
    "Scope",
    "parse_expression",
    "vector_call",
]

MAX_SOURCE_CHARS = 4000
"""Longest expression source accepted."""
MAX_DEPTH = 64
"""Deepest expression tree accepted."""

_BIN = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**"}
_CMP = {ast.Lt: "<", ast.LtE: "<=", ast.Gt: ">", ast.GtE: ">=", ast.Eq: "==", ast.NotEq: "!="}
_HINTS = {
    ast.BitXor: "'^' is not a power here: write '**'",
    ast.Mod: "'%' is not supported: there is no modulo; write x - m * floor(x / m)",
    ast.FloorDiv: "'//' is not supported: write floor(a / b)",
    ast.BitAnd: "'&' is not supported: write 'and'",
    ast.BitOr: "'|' is not supported: write 'or'",
    ast.MatMult: "'@' is not supported",
    ast.LShift: "'<<' is not supported",
    ast.RShift: "'>>' is not supported",
}
_NODE_NAMES = {
    ast.Attribute: "attribute access",
    ast.Lambda: "lambda",
    ast.ListComp: "comprehension",
    ast.SetComp: "comprehension",
    ast.DictComp: "comprehension",
    ast.GeneratorExp: "comprehension",
    ast.IfExp: "conditional expression (a if c else b)",
    ast.NamedExpr: "assignment expression (:=)",
    ast.Starred: "starred expression",
    ast.List: "list",
    ast.Tuple: "tuple",
    ast.Dict: "dict",
    ast.Set: "set",
    ast.JoinedStr: "f-string",
    ast.Await: "await",
    ast.Yield: "yield",
    ast.YieldFrom: "yield",
    ast.Slice: "slice",
}
_CONSTANTS = {"pi": math.pi}
_BOOLS = {"true": True, "false": False}
_KIND_WORDS = {
    ir.STATE: "a state variable",
    ir.PARAM: "a parameter",
    ir.SIGNAL: "a signal",
    ir.INPUT: "an input",
    ir.CONST: "a constant",
    "t": "the time",
    "pi": "a constant",
}
"""How a message names each kind of variable, the time and the constants."""
_NUM, _BOOL = "number", "boolean"


class ExprError(Exception):
    """A refused expression; ``col`` is the 0-based column in the source."""

    def __init__(self, message: str, col: int = 0) -> None:
        super().__init__(message)
        self.message = message
        self.col = col


@dataclass
class Scope:
    """What names an expression may use.

    ``variables`` maps a name to its kind (``state``, ``param``, ``signal``,
    ``input``); ``t`` is always the time. ``functions`` adds registered library
    functions to the built-ins; ``vectors`` gives the length of vector signals.
    """

    variables: Mapping[str, str]
    functions: Mapping[str, Function] = field(default_factory=dict)
    vectors: Mapping[str, int] = field(default_factory=dict)

    def function(self, name: str) -> Function | None:
        return self.functions.get(name) or BUILTINS.get(name)

    def known_names(self) -> list[str]:
        return [*self.variables, "t", "pi", "true", "false", *BUILTINS, *self.functions]


def parse_expression(source: str, scope: Scope, *, want: str = "number") -> ir.Expr:
    """Parse, check and fold ``source``; ``want`` is ``"number"`` or ``"bool"``.

    Raises :class:`ExprError` with a column for anything outside the language.
    """
    if len(source) > MAX_SOURCE_CHARS:
        raise ExprError(
            f"expression is {len(source)} characters long, over the limit of {MAX_SOURCE_CHARS}"
        )
    text = source.strip()
    if not text:
        raise ExprError("empty expression")
    lead = len(source) - len(source.lstrip())
    try:
        tree = _ast_parse(text)
    except SyntaxError as exc:
        found = habit(text)
        if found is not None:
            raise ExprError(found[0], lead + found[1]) from None
        col = (exc.offset or 1) - 1 if (exc.lineno or 1) == 1 else 0
        if "\n" in text:  # a YAML literal block (|) keeps its line breaks
            raise ExprError(
                "an expression is one line: a YAML literal block (|) keeps its line breaks; "
                "write it on one line or as a folded block (>)",
                lead,
            ) from None
        raise ExprError(f"syntax error: {exc.msg}", lead + col) from None
    except (MemoryError, RecursionError):
        raise ExprError(
            f"expression is nested too deeply to be parsed (limit: {MAX_DEPTH} levels)", lead
        ) from None
    except ValueError as exc:
        raise ExprError(f"expression cannot be parsed: {exc}", lead) from None
    _check_depth(tree.body, lead)
    node, kind = _Converter(scope, lead).convert(tree.body)
    expected = _BOOL if want == "bool" else _NUM
    if kind != expected:
        if expected == _BOOL:
            raise ExprError(
                "expected a condition (true/false), got a number: compare it, e.g. x > 0", lead
            )
        raise ExprError("expected a number, got a condition", lead)
    return node


def _ast_parse(text: str) -> ast.Expression:
    """``ast.parse`` in eval mode, without the warnings Python prints for odd source.

    (``x>1and y`` parses but warns "invalid decimal literal" on stderr.)
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", SyntaxWarning)
        warnings.simplefilter("ignore", DeprecationWarning)
        return ast.parse(text, mode="eval")


def _check_depth(root: ast.AST, lead: int = 0) -> None:
    """Refuse trees deeper than :data:`MAX_DEPTH` expression nodes (``x`` is 1, ``-x`` is 2).

    Operator and context nodes (``+``, ``Load``) are not levels of their own.
    """
    stack: list[tuple[ast.AST, int]] = [(root, 1)]
    while stack:
        node, depth = stack.pop()
        if depth > MAX_DEPTH:
            raise ExprError(
                f"expression is nested more than {MAX_DEPTH} levels deep",
                lead + int(getattr(node, "col_offset", 0)),
            )
        stack.extend(
            (child, depth + 1 if isinstance(child, ast.expr) else depth)
            for child in ast.iter_child_nodes(node)
        )


class _Converter:
    def __init__(self, scope: Scope, lead: int) -> None:
        self.scope = scope
        self.lead = lead

    def col(self, node: ast.AST) -> int:
        return self.lead + int(getattr(node, "col_offset", 0))

    def convert(self, node: ast.AST) -> tuple[ir.Expr, str]:
        col = self.col(node)
        if isinstance(node, ast.Constant):
            return self._constant(node, col)
        if isinstance(node, ast.Name):
            return self._name(node.id, col)
        if isinstance(node, ast.BinOp):
            op = _BIN.get(type(node.op))
            if op is None:
                raise ExprError(_HINTS.get(type(node.op), "operator not supported"), col)
            left = self.number(node.left)
            right = self.number(node.right)
            return _fold(ir.Bin(op, left, right, col)), _NUM
        if isinstance(node, ast.UnaryOp):
            if isinstance(node.op, ast.Not):
                return ir.Not(self.boolean(node.operand), col), _BOOL
            if isinstance(node.op, ast.USub):
                return _fold(ir.Unary("-", self.number(node.operand), col)), _NUM
            if isinstance(node.op, ast.UAdd):
                return self.number(node.operand), _NUM
            raise ExprError("'~' is not negation here: write 'not'", col)
        if isinstance(node, ast.BoolOp):
            op = "and" if isinstance(node.op, ast.And) else "or"
            return ir.BoolOp(op, tuple(self.boolean(v) for v in node.values), col), _BOOL
        if isinstance(node, ast.Compare):
            ops = []
            for op_node in node.ops:
                op = _CMP.get(type(op_node))
                if op is None:
                    raise ExprError("only < <= > >= == != comparisons are allowed", col)
                ops.append(op)
            operands = (self.number(node.left), *(self.number(c) for c in node.comparators))
            return ir.Cmp(tuple(ops), operands, col), _BOOL
        if isinstance(node, ast.Call):
            return self._call(node, col)
        if isinstance(node, ast.Subscript):
            return self._subscript(node, col)
        name = _NODE_NAMES.get(type(node), type(node).__name__)
        raise ExprError(f"{name} is not allowed in expressions", col)

    def number(self, node: ast.AST) -> ir.Expr:
        converted, kind = self.convert(node)
        if kind != _NUM:
            raise ExprError(
                "expected a number here, got a condition (conditions join with 'and' and "
                "'or'; a value that depends on a condition is a location's signal)",
                self.col(node),
            )
        return converted

    def boolean(self, node: ast.AST) -> ir.Expr:
        converted, kind = self.convert(node)
        if kind != _BOOL:
            raise ExprError(
                "expected a condition here, got a number: compare it, e.g. x > 0", self.col(node)
            )
        return converted

    def _constant(self, node: ast.Constant, col: int) -> tuple[ir.Expr, str]:
        value = node.value
        if isinstance(value, bool):
            raise ExprError(f"write '{str(value).lower()}', not '{value}'", col)
        if isinstance(value, int | float):
            try:
                number = float(value)
            except OverflowError:
                number = math.inf
            if not math.isfinite(number):  # 1e400 reads as inf
                raise ExprError(
                    "number literal is too large for a 64-bit float (at most about 1.8e308)", col
                )
            return ir.Num(number, col), _NUM
        raise ExprError(f"{type(value).__name__} literals are not allowed in expressions", col)

    def _name(self, name: str, col: int) -> tuple[ir.Expr, str]:
        if name == "t":
            return ir.Var("t", ir.TIME, col), _NUM
        if name in _BOOLS:
            return ir.BoolConst(_BOOLS[name], col), _BOOL
        if name in _CONSTANTS:
            return ir.Num(_CONSTANTS[name], col), _NUM
        kind = self.scope.variables.get(name)
        if kind is not None:
            if name in self.scope.vectors:
                raise ExprError(
                    f"'{name}' is a vector of {self.scope.vectors[name]} values: "
                    f"pick one with {name}[k]",
                    col,
                )
            return ir.Var(name, kind, col), _NUM
        if self.scope.function(name) is not None:
            raise ExprError(f"'{name}' is a function: call it, e.g. {name}(x)", col)
        raise ExprError(f"unknown name '{name}'{did_you_mean(name, self.scope.known_names())}", col)

    def _call(self, node: ast.Call, col: int) -> tuple[ir.Expr, str]:
        if not isinstance(node.func, ast.Name):
            if isinstance(node.func, ast.Attribute):
                raise ExprError("attribute access is not allowed in expressions", col)
            raise ExprError("only named functions can be called", col)
        fname = node.func.id
        func = self.scope.function(fname)
        if func is None:
            if fname in self.scope.vectors:
                raise ExprError(
                    f"'{fname}' is a vector of {self.scope.vectors[fname]} values, not a "
                    f"function: pick one with {fname}[k], from 0 (MATLAB's {fname}(1) is "
                    f"{fname}[0])",
                    col,
                )
            kind = self.scope.variables.get(fname)
            if kind is not None or fname in ("t", *_CONSTANTS):
                what = _KIND_WORDS.get(kind or fname, "a value")
                raise ExprError(f"'{fname}' is {what}, not a function: write {fname}", col)
            instead = function_habit(fname)
            if instead is not None:
                raise ExprError(f"unknown function '{fname}': {instead}", col)
            names = [*BUILTINS, *self.scope.functions]
            raise ExprError(f"unknown function '{fname}'{did_you_mean(fname, names)}", col)
        if node.keywords:
            raise ExprError(f"{fname}() takes positional arguments only", col)
        n = len(node.args)
        if n < func.min_args or (func.max_args is not None and n > func.max_args):
            raise ExprError(f"{fname}() takes {_arity(func)}, got {n}", col)
        args = tuple(self.number(arg) for arg in node.args)
        if func.outputs != 1:
            raise ExprError(
                f"{fname}() returns {func.outputs} values: define a signal with it and "
                f"index that signal, e.g. s: {fname}(...) then s[0]",
                col,
            )
        return _fold(ir.Call(fname, args, col), func), _NUM

    def _subscript(self, node: ast.Subscript, col: int) -> tuple[ir.Expr, str]:
        if not isinstance(node.value, ast.Name):
            raise ExprError("only a vector signal can be indexed, as name[k]", col)
        name = node.value.id
        index = node.slice
        if not (
            isinstance(index, ast.Constant)
            and isinstance(index.value, int)
            and not isinstance(index.value, bool)
        ):
            raise ExprError("an index must be a whole-number literal, as name[0]", col)
        size = self.scope.vectors.get(name)
        if size is None:
            if self.scope.function(name) is not None and name not in self.scope.variables:
                raise ExprError(f"'{name}' is a function: call it, e.g. {name}(x)", col)
            if name in self.scope.variables:
                raise ExprError(f"'{name}' is a single value and cannot be indexed", col)
            raise ExprError(
                f"unknown name '{name}'{did_you_mean(name, self.scope.known_names())}", col
            )
        if not 0 <= index.value < size:
            raise ExprError(
                f"index {index.value} is out of range for '{name}' ({size} values)", col
            )
        return ir.Index(name, index.value, col), _NUM


def vector_call(source: str, scope: Scope) -> tuple[ir.Call, int] | None:
    """If ``source`` is a single call of a multi-output function, return it and its size."""
    if len(source) > MAX_SOURCE_CHARS:
        return None  # parse_expression refuses it with the limit in the message
    try:
        tree = _ast_parse(source.strip())
    except (SyntaxError, ValueError, MemoryError, RecursionError):
        return None
    body = tree.body
    if not (isinstance(body, ast.Call) and isinstance(body.func, ast.Name)):
        return None
    func = scope.function(body.func.id)
    if func is None or func.outputs == 1:
        return None
    lead = len(source) - len(source.lstrip())
    _check_depth(body, lead)
    converter = _Converter(scope, lead)
    n = len(body.args)
    if body.keywords:
        raise ExprError(f"{func.name}() takes positional arguments only", lead)
    if n < func.min_args or (func.max_args is not None and n > func.max_args):
        raise ExprError(f"{func.name}() takes {_arity(func)}, got {n}", lead)
    args = tuple(converter.number(arg) for arg in body.args)
    return ir.Call(func.name, args, lead), func.outputs


def _arity(func: Function) -> str:
    if func.max_args is None:
        return f"at least {func.min_args} arguments"
    if func.min_args == func.max_args:
        return f"{func.min_args} argument{'s' if func.min_args != 1 else ''}"
    return f"{func.min_args} to {func.max_args} arguments"


def _fold(node: ir.Expr, func: Function | None = None) -> ir.Expr:
    """Evaluate ``node`` now if all its operands are numbers (in floating point)."""
    if not all(isinstance(c, ir.Num) for c in ir.children(node)):
        return node
    values = [c.value for c in ir.children(node) if isinstance(c, ir.Num)]
    col = node.col
    try:
        if isinstance(node, ir.Unary):
            return ir.Num(-values[0], col)
        if isinstance(node, ir.Bin):
            a, b = values
            result = {
                "+": lambda: a + b,
                "-": lambda: a - b,
                "*": lambda: a * b,
                "/": lambda: a / b,
                "**": lambda: math.pow(a, b),
            }[node.op]()
        elif isinstance(node, ir.Call) and func is not None and func.builtin:
            result = func.fn(*values)
        else:
            return node
    except OverflowError:
        raise ExprError("constant expression overflows a 64-bit float", col) from None
    except ZeroDivisionError:
        raise ExprError("division by zero in a constant expression", col) from None
    except ValueError:
        raise ExprError("math domain error in a constant expression", col) from None
    result = float(result)
    if not math.isfinite(result):
        raise ExprError("constant expression is not finite", col)
    return ir.Num(result, col)
