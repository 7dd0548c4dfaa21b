"""Compile IR into Python functions of ``(t, x)``: no ``eval`` of user text.

The generated source is built only from checked IR nodes: numbers become float
literals, names become prefixed local variables, calls go to functions bound in
the generated module's globals. Parameters are inlined as constants. Each
function computes the signals it needs in dependency order, then its outputs.

Examples
--------
>>> from hybrid.expr.parse import Scope, parse_expression
>>> scope = Scope({"h": "state", "v": "state", "g": "param"})
>>> flow = [parse_expression(s, scope) for s in ("v", "-g")]
>>> ctx = CodeContext(states=("h", "v"), params={"g": 9.81})
>>> rhs = compile_function("rhs", flow, ctx, shape="list")
>>> import numpy as np
>>> rhs(0.0, np.array([10.0, 0.0]))
[np.float64(0.0), -9.81]
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from hybrid.expr import ir
from hybrid.expr.dependencies import evaluation_order
from hybrid.expr.functions import BUILTINS, Function
from hybrid.expr.generated import define
from hybrid.expr.matrix_form import MatrixForm, matrix_form
from hybrid.expr.printer import SourcePrinter

__all__ = [
    "EVALUATION_ERRORS",
    "CodeContext",
    "EvalFailure",
    "Stash",
    "compile_function",
    "reads_items",
    "reads_library",
]

EVALUATION_ERRORS: tuple[type[Exception], ...] = (Exception,)
"""What an expression's evaluation may raise and is then a failure of that evaluation (the
run ends ``nonfinite`` naming it): arithmetic and domain errors, and whatever a library
function raises (an IndexError of a table, its own exception class). Not KeyboardInterrupt
or SystemExit."""
_ERRORS = EVALUATION_ERRORS


@dataclass
class EvalFailure:
    """Where evaluation last failed (math domain error, overflow, ...), if anywhere."""

    error: BaseException | None = None
    t: float | None = None
    where: str = ""

    def record(self, error: BaseException, t: float, where: str) -> None:
        if self.error is None:
            self.error, self.t, self.where = error, t, where

    def clear(self) -> None:
        self.error, self.t, self.where = None, None, ""


@dataclass(slots=True)
class CodeContext:
    """Everything names in an expression can refer to when compiled.

    ``signals`` are the signal definitions in force (a vector signal's is a call
    of a multi-output function); ``inputs`` gives each external input's *slot*, a
    list whose item 0 is its callable of ``t``, read at every call: a model compiled
    once is run again with other inputs by putting them in its slots.
    """

    states: Sequence[str]
    params: Mapping[str, float] = field(default_factory=dict)
    signals: Mapping[str, ir.Expr] = field(default_factory=dict)
    inputs: Mapping[str, list[Callable[[float], float]]] = field(default_factory=dict)
    functions: Mapping[str, Function] = field(default_factory=dict)
    failure: EvalFailure = field(default_factory=EvalFailure)


class Stash:
    """The signals one function computed at its last point, for others to read there.

    A function compiled with ``stash=`` (the flow the solver steps) keeps the
    values of the signals it computed, with its point ``(t, x)``, in
    ``slot[0]``; a function compiled with ``share=`` the same stash reads them
    instead of computing them again when it is called at exactly that point
    (the same ``t`` and the same bytes of ``x``), and computes only the signals
    the stash lacks. A Runge-Kutta solver evaluates the flow last at the end of
    the step it accepts, where the simulator then evaluates its watch and
    stores a point. The values are the same either way (the same source
    computes them from the same floats). ``names`` (the signals kept, in
    order) is set when the stashing function is compiled.

    Examples
    --------
    >>> from hybrid.expr.parse import Scope, parse_expression
    >>> from hybrid.expr.functions import Function
    >>> calls = []
    >>> double = Function("double", lambda v: calls.append(v) or 2 * v, 1, 1, builtin=False)
    >>> scope = Scope({"x": "state", "d": "signal"}, functions={"double": double})
    >>> ctx = CodeContext(states=("x",), signals={"d": parse_expression("double(x)", scope)},
    ...                   functions={"double": double})
    >>> stash = Stash([None])
    >>> flow = compile_function("flow", [parse_expression("-d", scope)], ctx, stash=stash)
    >>> signals = compile_function("out", [parse_expression("d + 1", scope)], ctx, share=stash)
    >>> import numpy as np
    >>> flow(0.0, np.array([3.0])), signals(0.0, np.array([3.0])), signals(0.5, np.array([3.0]))
    ([-6.0], [7.0], [7.0])
    >>> calls                           # the second call read the stash; the third computed
    [3.0, 3.0]
    """

    __slots__ = ("names", "slot")

    def __init__(self, slot: list[Any]) -> None:
        self.slot = slot
        self.names: tuple[str, ...] = ()


_SAFE_CALLS = {"min", "max", "abs"}


def _float_safe(exprs: Sequence[ir.Expr]) -> bool:
    """True if numpy scalars give exactly what Python floats give (no /, **, other calls).

    Only then may a function read ``x[i]`` (a numpy scalar) directly: division by
    zero or an overflowing power must raise as they do on floats, not give inf.
    """
    for root in exprs:
        for node in ir.walk(root):
            if isinstance(node, ir.Bin) and node.op in ("/", "**"):
                return False
            if isinstance(node, ir.Call) and node.func not in _SAFE_CALLS:
                return False
    return True


def _calls(definitions: Sequence[ir.Expr], functions: Mapping[str, Function]) -> bool:
    """True if some definition calls a library function."""
    return any(
        isinstance(node, ir.Call) and node.func in functions
        for root in definitions
        for node in ir.walk(root)
    )


def reads_library(outputs: Sequence[ir.Expr], ctx: CodeContext) -> bool:
    """True if the signals ``outputs`` read call a library function (worth a :class:`Stash`)."""
    used: set[str] = set()
    for e in outputs:
        used |= ir.names_in(e)
    order = evaluation_order(used, ctx.signals)
    return _calls([ctx.signals[s] for s in order], ctx.functions)


_GLOBAL_NAME = re.compile(r"\b_[A-Za-z0-9]\w*")
"""A name a generated source may take from its scope (they all start with ``_``)."""

_INDEXES: dict[int, tuple[Sequence[str], int, dict[str, int]]] = {}


def _state_index(states: Sequence[str]) -> dict[str, int]:
    """Each state variable's position in ``states``, made once per sequence: a model's
    many functions share one sequence, and reading it whole for each would cost a
    system of many components the square of their number."""
    found = _INDEXES.get(id(states))
    if found is None or found[0] is not states or found[1] != len(states):
        if len(_INDEXES) >= 64:
            _INDEXES.clear()
        found = (states, len(states), {s: i for i, s in enumerate(states)})
        _INDEXES[id(states)] = found
    return found[2]


class _Names(dict[str, str]):
    """The local name of each variable, made when first looked up: an input's, else a
    signal's, else a state's (as ``CodeContext`` lists them, the later kind first)."""

    def __init__(self, ctx: CodeContext, index: Mapping[str, int]) -> None:
        super().__init__()
        self._ctx, self._index = ctx, index

    def __missing__(self, name: str) -> str:
        if name in self._ctx.inputs:
            local = f"u_{name}"
        elif name in self._ctx.signals:
            local = f"s_{name}"
        elif name in self._index:
            local = f"x_{name}"
        else:
            raise KeyError(name)
        self[name] = local
        return local


MATRIX_MIN_TERMS = 64
"""A flow of at least this many number-times-variable products is compiled as one matrix
product (below it, the interpreter's operations cost about what the product's call does)."""


def _as_matrix(
    exprs: Sequence[ir.Expr],
    ctx: CodeContext,
    shape: str,
    part: bool,
    stash: Stash | None,
    order: Sequence[str],
) -> MatrixForm | None:
    """The matrix form of a list of outputs that read no signal, if it has enough terms."""
    if shape != "list" or part or stash is not None or order or not ctx.states:
        return None
    return _long_form(exprs, ctx)


def _columns_as_matrix(
    exprs: Sequence[ir.Expr], ctx: CodeContext, shape: str, part: bool, share: Stash | None
) -> MatrixForm | None:
    """The matrix form of a tuple of signal columns, each a signal whose definition reads no
    other signal, if their definitions are linear with enough terms (ISS's outputs: three
    sums of 135 products, 76 µs a stored point term by term)."""
    if shape != "tuple" or part or share is not None or not ctx.states or not exprs:
        return None
    if not all(isinstance(e, ir.Var) and e.kind == ir.SIGNAL and e.name in ctx.signals
               for e in exprs):  # fmt: skip
        return None
    definitions = [ctx.signals[e.name] for e in exprs if isinstance(e, ir.Var)]
    if any(ir.names_in(d, ir.SIGNAL) for d in definitions):
        return None
    return _long_form(definitions, ctx)


def _long_form(exprs: Sequence[ir.Expr], ctx: CodeContext) -> MatrixForm | None:
    """The matrix form of ``exprs`` if they are linear with :data:`MATRIX_MIN_TERMS` products."""
    form = matrix_form(exprs, ctx.states, ctx.params, ctx.inputs)
    return form if form is not None and form.terms >= MATRIX_MIN_TERMS else None


def _tiny(exprs: Sequence[ir.Expr], definitions: Sequence[ir.Expr], ctx: CodeContext) -> bool:
    """True if a function of ``exprs`` reads ``x[i]`` directly (numpy scalars, not floats):
    it and the signals it needs read at most three state variables, each once, and no
    operation where numpy scalars differ from floats (:func:`_float_safe`)."""
    wanted = _state_index(ctx.states)
    read: set[str] = set()
    for root in (*exprs, *definitions):
        for node in ir.walk(root):
            if isinstance(node, ir.Var) and node.kind == ir.STATE and node.name in wanted:
                if node.name in read or len(read) == 3:
                    return False  # a large function is known to be none after a few nodes
                read.add(node.name)
    return _float_safe([*exprs, *definitions])


def reads_items(outputs: Sequence[ir.Expr], ctx: CodeContext) -> bool:
    """True if :func:`compile_function` of ``outputs`` (shape ``scalar``, ``list`` or
    ``tuple``) reads the state's items ``x[i]`` directly: its values are then numpy scalars.
    """
    used: set[str] = set()
    for e in outputs:
        used |= ir.names_in(e)
    order = evaluation_order(used, ctx.signals)
    return bool(ctx.states) and _tiny(list(outputs), [ctx.signals[s] for s in order], ctx)


def _memo_deps(
    order: Sequence[str], definitions: Sequence[ir.Expr], ctx: CodeContext, steady: frozenset[str]
) -> dict[str, tuple[str, ...]]:
    """The signals worth a last-arguments memo, each with what its value depends on.

    A signal qualifies if its definition calls a library function and reads,
    directly or through other signals, only ``t``, numbers, parameters and the
    ``steady`` state variables; it depends on ``t`` and those state variables
    (its key, in a fixed order; a signal reading neither is not memoized). A
    library function is a function of its arguments (docs/spec-language.md,
    "Function libraries"): the same arguments give the same value.
    """
    reads: dict[str, frozenset[str] | None] = {}
    memo: dict[str, tuple[str, ...]] = {}
    for s, definition in zip(order, definitions, strict=True):
        key = _key_of(definition, steady, reads)
        reads[s] = key
        if key and _calls([definition], ctx.functions):
            memo[s] = tuple(sorted(key, key=lambda n: (n != "t", n)))
    return memo


def _key_of(
    definition: ir.Expr, steady: frozenset[str], reads: Mapping[str, frozenset[str] | None]
) -> frozenset[str] | None:
    """``t`` and the ``steady`` state variables ``definition`` reads (``reads``: those of
    the signals before it), or None if it reads anything else that varies."""
    key: set[str] = set()
    for node in ir.walk(definition):
        if isinstance(node, ir.Var) and node.kind in (ir.PARAM, ir.CONST):
            continue
        if isinstance(node, ir.Var) and node.kind == ir.TIME:
            key.add("t")
        elif isinstance(node, ir.Var) and node.kind == ir.STATE and node.name in steady:
            key.add(node.name)
        elif isinstance(node, (ir.Var, ir.Index)):
            signal = isinstance(node, ir.Index) or node.kind == ir.SIGNAL
            found = reads.get(node.name) if signal else None  # an input, a moving state
            if found is None:
                return None
            key |= found
    return frozenset(key)


def _memoized(
    emitted: str, target: str, key: tuple[str, ...], names: Mapping[str, str], index: int
) -> list[str]:
    """``emitted`` (``target = ...``) behind memo ``index`` of its last key, compared bit for bit."""
    values = [("t" if k == "t" else names[k]) for k in key]
    same = " and ".join(f"{v} == _k[{i}]" for i, v in enumerate(values))
    # equal floats of different signs are zeros: -0.0 == 0.0, but a function may tell them apart
    signs = " and ".join(
        f"({v} or _copysign(1.0, {v}) == _copysign(1.0, _k[{i}]))" for i, v in enumerate(values)
    )
    return [
        f"_k = _m{index}[0]",
        f"if _k and {same} and {signs}:",
        f"    {target} = _k[-1]",
        "else:",
        f"    {emitted}",
        f"    _m{index}[0] = ({', '.join(values)}, {target})",
    ]


def compile_function(
    name: str,
    outputs: Sequence[ir.Expr],
    ctx: CodeContext,
    *,
    shape: str = "list",
    reset_of: Sequence[ir.Expr | None] | None = None,
    part: bool = False,
    stash: Stash | None = None,
    share: Stash | None = None,
    steady: frozenset[str] = frozenset(),
) -> Callable[..., Any]:
    """Compile ``outputs`` into one function ``f(t, x)`` of a time and a 1-D numpy array.

    ``shape`` is ``"scalar"`` (one value), ``"list"`` or ``"tuple"``; a list of
    outputs compiled as one matrix product (:func:`_as_matrix`) is returned as the
    product's array (the same floats: a solver writes either into its stage row,
    where turning 274 values into a list and back cost as much as the product). With
    ``reset_of``, output ``i`` is ``reset_of[i]`` if given, else ``x[i]``
    unchanged. On a math error the function records it in ``ctx.failure`` and
    returns NaN values (or ``False`` for conditions), so the solver stops and
    the simulator can say what failed and where.

    ``steady`` names the state variables the function's solver keeps unchanged
    (their flow is 0). In a function compiled with ``stash`` (the flow a solver
    steps), a signal that calls a library function and reads only ``t``,
    numbers, parameters and steady state variables (directly or through such
    signals) is reused from the last call where all of those had the same
    values, bit for bit (:func:`_memo_deps`): a Runge-Kutta step evaluates its
    last stage and the step end at the same ``t``, with the same steady state.

    ``part=True`` compiles one component's share of a larger function: ``x``
    is then the state as a list of floats (``x.tolist()``, converted once by
    the caller), only the state variables read are taken from it, and a math
    error propagates to the caller, which records it for the whole.

    ``stash`` keeps the signals computed at each call, and ``t`` is taken as
    a Python float (a solver passes numpy scalars, whose arithmetic is slower
    and does not raise where floats do); ``share`` reads a stash's signals at
    the point it was kept (:class:`Stash`). Neither applies to ``part`` or
    ``reset_of``.
    """
    exprs = list(outputs)
    if reset_of is not None:
        exprs = [e for e in reset_of if e is not None]
    index = _state_index(ctx.states)
    names = _Names(ctx, index)
    consts: list[float] = []
    printer = SourcePrinter(names, consts)
    for pname, value in ctx.params.items():
        names[pname] = printer.literal(float(value))

    used: set[str] = set()
    for e in exprs:
        used |= ir.names_in(e)
    order = evaluation_order(used, ctx.signals)
    all_used = set(used)
    for s in order:
        all_used |= ir.names_in(ctx.signals[s])

    body: list[str] = []
    memos = 0
    definitions = [ctx.signals[s] for s in order]
    if part or reset_of is not None or not ctx.states:
        stash = share = None
    # a long linear list: one product with the state array (hybrid.expr.matrix_form)
    form = None if reset_of is not None else _as_matrix(exprs, ctx, shape, part, stash, order)
    columns = None if reset_of is not None else _columns_as_matrix(exprs, ctx, shape, part, share)
    if columns is not None:  # the signals' definitions are in the product: none computed
        form, order, definitions = columns, [], []
    if stash is not None:
        body.append("t = _float(t)")
    tiny = _tiny(exprs, definitions, ctx)
    if part:
        # the caller converted the state once: take the variables read, as floats
        # (an input bound to another component's state variable reads it too)
        read = sorted((s for s in all_used if s in index), key=index.__getitem__)
        body.extend(f"{names[s]} = x[{index[s]}]" for s in read)
    elif reset_of is None and tiny:
        # a tiny function: index the array directly (faster than converting it)
        for s in all_used:
            if s in index:
                names[s] = f"x[{index[s]}]"
    elif ctx.states and form is None:
        targets = ", ".join(names[s] for s in ctx.states)
        body.append(f"{targets}, = x.tolist()")
    for u in sorted(n for n in all_used if n in ctx.inputs):
        body.append(f"{names[u]} = _in_{u}[0](t)")
    kept = share.names if share is not None else ()
    if kept and set(kept) & set(order) and _calls(definitions, ctx.functions):
        # at the stash's point its signals are read, the others computed from them
        body.append("_s = _slot[0]")
        body.append(
            "if _s is not None and _s[0] is _share and _s[1] == t and _s[2] == x.tobytes() "
            "and (t or _copysign(1.0, t) == _copysign(1.0, _s[1])):"
        )
        body.append(f"    {', '.join(names[s] for s in kept)}, = _s[3]")
        lacking = [(s, d) for s, d in zip(order, definitions, strict=True) if s not in kept]
        body.extend(f"    {names[s]} = {printer.emit(d)[0]}" for s, d in lacking)
        body.append("else:")
        body.extend(
            f"    {names[s]} = {printer.emit(d)[0]}" for s, d in zip(order, definitions, strict=True)
        )
    else:
        share = None
        memo = _memo_deps(order, definitions, ctx, steady) if stash is not None else {}
        for s, definition in zip(order, definitions, strict=True):
            emitted = f"{names[s]} = {printer.emit(definition)[0]}"
            if s in memo:
                body.extend(_memoized(emitted, names[s], memo[s], names, memos))
                memos += 1
            else:
                body.append(emitted)
    if stash is not None and order:
        stash.names = tuple(order)
        body.append(
            f"if _keep: _slot[0] = (_stash, t, x.tobytes(), ({', '.join(names[s] for s in order)},))"
        )

    failed: str
    matrices: dict[str, Any] = {}
    if reset_of is not None:
        items = [
            printer.emit(e)[0] if e is not None else names[ctx.states[i]]
            for i, e in enumerate(reset_of)
        ]
        body.append(f"return [{', '.join(items)}]")
        failed = f"[_nan] * {len(reset_of)}"
    elif shape == "scalar":
        body.append(f"return {printer.emit(exprs[0])[0]}")
        failed = "_nan"
    elif form is not None:  # the inputs read are in the body; the state stays an array
        driven = f" + _N @ ({''.join(f'{names[u]}, ' for u in form.inputs)})" if form.inputs else ""
        if columns is not None:  # a tuple of floats, as the columns' own function gives
            body.append(f"return _tuple((_M @ x{driven} + _c).tolist())")
            failed = f"({'_nan, ' * len(exprs)})"
        else:
            body.append(f"return _M @ x{driven} + _c")
            failed = f"[_nan] * {len(exprs)}"
        matrices = {"_M": form.states, "_N": form.by_input, "_c": form.const}
    else:
        items = [printer.emit(e)[0] for e in exprs]
        open_, close = ("[", "]") if shape == "list" else ("(", ",)" if len(items) == 1 else ")")
        body.append(f"return {open_}{', '.join(items)}{close}")
        failed = f"[_nan] * {len(items)}" if shape == "list" else f"({'_nan, ' * len(items)})"

    # a stashing function keeps its signals only when asked (the solver's last stage)
    header = f"def {name}(t, x, _keep=True):" if stash is not None else f"def {name}(t, x):"
    if part:
        lines = [header, *(f"    {line}" for line in body)]
    else:
        lines = [header, "    try:"]
        lines += [f"        {line}" for line in body]
        lines += [
            "    except _ERRORS as _e:",
            f"        _failure.record(_e, t, {name!r})",
            f"        return {failed}",
        ]
    source = "\n".join(lines) + "\n"

    scope: dict[str, Any] = {
        "_ERRORS": _ERRORS,
        "_failure": ctx.failure,
        "_nan": math.nan,
        "_K": tuple(consts),
        "_pow": math.pow,
        "_copysign": math.copysign,
        "_float": float,
    }
    if stash is not None:
        scope["_slot"], scope["_stash"] = stash.slot, stash
    for k in range(memos):
        scope[f"_m{k}"] = [()]  # the last key and value of memo k (an empty key matches nothing)
    if share is not None:
        scope["_slot"], scope["_share"] = share.slot, share
    for fname, func in BUILTINS.items():
        scope[f"_{fname}"] = func.fn
    scope["_min"], scope["_max"], scope["_tuple"] = min, max, tuple
    for fname, func in ctx.functions.items():
        scope[f"_{fname}"] = func.fn
    for u, slot in ctx.inputs.items():
        scope[f"_in_{u}"] = slot
    scope.update(matrices)
    # only what the source names: a system of many components compiles thousands of
    # small functions, each with its own namespace
    named = set(_GLOBAL_NAME.findall(source))
    compiled = define(name, source, {k: v for k, v in scope.items() if k in named})
    compiled.__doc__ = source
    return compiled
