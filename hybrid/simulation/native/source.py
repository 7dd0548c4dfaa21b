"""Generated source: one module per model (the kernel's is :mod:`~hybrid.simulation.native.kernel_text`'s).

**A model** (:func:`generate`): its function ``model(op, index, t, x*, p*,
out*)`` (see ``kernel_types``) generated from the expression IR by
:mod:`~hybrid.simulation.native.printer` as one numba ``cfunc``, with
:mod:`~hybrid.simulation.native.mathlib` inlined into it and the
per-operation functions (``model_rhs``...) written into its dispatch, or
compiled apart when the model is large (:data:`INLINE_LINES`); the slots an operation reads
are loaded and the lines all its cases run alike are computed before its
dispatch (:func:`_hoisted`, :func:`_shared`), and cases alike are written once
(:func:`_alike`). And the table
``tab`` (which transitions, levels and invariants each mode has, and the form
numbers of their expressions). One module per model *structure*: parameters
are slots, so their values are not in it. The source is built from checked
IR and fixed templates only (no user text but numbers and accepted names),
like :mod:`hybrid.expr.codegen`'s.

Examples
--------
>>> import hybrid
>>> from hybrid.simulation.native.structure import NativeModel
>>> from hybrid.compose import as_system
>>> generated = generate(NativeModel(as_system(hybrid.load("specs/bouncing_ball.yaml"))))
>>> "out[1] = -p_0" in generated.source, generated.tab[:6].tolist()
(True, [2, 1, 1, 1, 1, 2])
"""

from __future__ import annotations

import re
from collections.abc import Sequence

import numpy as np
from numpy.typing import NDArray

from hybrid.compose import System
from hybrid.expr import ir
from hybrid.expr.rho import guard_to_rho, level_key, within_band
from hybrid.held import HeldCache
from hybrid.simulation.native.buffers import T_MODE_TR, TAB_HEADER, TABLES
from hybrid.simulation.native.kernel_text import JIT, Generated, kernel_source
from hybrid.simulation.native.library import importable
from hybrid.simulation.native.printer import body_lines
from hybrid.simulation.native.structure import (
    BAND_NAME,
    COMPILED_FORM,
    NativeMode,
    NativeModel,
    sign_name,
    slot_name,
    snap_name,
    structure_key,
)

__all__ = ["generate", "native_source"]

MODEL_BASE_S, MODEL_SECONDS_PER_LINE = 0.4, 0.006
"""A model's compile time, about (measured: thermostat, 100 lines of operations, 0.5 s; the
4th-order filtered oscillator, 300 lines, 1.8 s; UVMS mission 2, 5,800 lines, 34 s, and
2,500 lines, 15.6 s, with what its cases share written once: :func:`_hoisted`,
:func:`_shared`, :func:`_alike`)."""
INLINE_LINES = 600
"""Models whose operations take fewer generated lines are compiled as one function (measured,
apart and as one: thermostat, 100 lines, 1.1 s and 0.5 s; the 16th-order filtered oscillator,
550 lines, 3.7 s and 3.0 s; the 32nd-order, 870 lines, 5.0 s and 6.2 s). The operations are
written into ``model``'s branches (:func:`_inlined`), not inlined by numba, which copied and
typed their IR again: the thermostat 0.79 -> 0.67 s, the bouncing ball 0.98 -> 0.74 s, the
4th-order oscillator 2.05 -> 1.66 s (medians of three, the kernel loaded)."""


class _Forms:
    """Scalar and boolean forms, numbered as the generated dispatchers see them."""

    def __init__(self) -> None:
        self.values: list[tuple[NativeMode, ir.Expr]] = []
        self.truths: list[tuple[NativeMode, ir.Expr]] = []

    def value(self, mode: NativeMode, expr: ir.Expr) -> int:
        self.values.append((mode, expr))
        return len(self.values) - 1

    def truth(self, mode: NativeMode, expr: ir.Expr) -> int:
        self.truths.append((mode, expr))
        return len(self.truths) - 1


def _dispatch(var: str, cases: Sequence[list[str]], indent: str) -> list[str]:
    """A binary tree of ``if`` on ``var`` selecting ``cases[k]`` for ``var == k``."""
    return _dispatch_at(var, [case or ["pass"] for case in cases], list(range(len(cases))), indent)


def _dispatch_at(var: str, cases: list[list[str]], starts: list[int], indent: str) -> list[str]:
    """:func:`_dispatch` where ``cases[k]`` covers ``var`` from ``starts[k]`` to the next start."""
    if len(cases) == 1:
        return [f"{indent}{line}" for line in cases[0]]
    mid = len(cases) // 2
    return [
        f"{indent}if {var} < {starts[mid]}:",
        *_dispatch_at(var, cases[:mid], starts[:mid], indent + "    "),
        f"{indent}else:",
        *_dispatch_at(var, cases[mid:], starts[mid:], indent + "    "),
    ]


_READ = re.compile(r"\b([xp])\[(\d+)\]")


def _hoisted(cases: Sequence[list[str]]) -> tuple[list[str], list[list[str]]]:
    """Each state and parameter slot the cases read, loaded once into a local before the
    dispatch, and the cases reading the locals (numba types each ``x[i]`` apart, trying every
    ``getitem`` it knows: UVMS, thousands; a fifth of its compile, and loaded in each case
    apart, a third of its lines).

    >>> _hoisted([["out[0] = x[1] * p[0]"], ["out[0] = x[0]"]])
    (['p_0 = p[0]', 'x_0 = x[0]', 'x_1 = x[1]'], [['out[0] = x_1 * p_0'], ['out[0] = x_0']])
    """
    used = sorted({(m[1], int(m[2])) for case in cases for line in case for m in _READ.finditer(line)})
    loads = [f"{v}_{i} = {v}[{i}]" for v, i in used]
    return loads, [[_READ.sub(r"\1_\2", line) for line in case] for case in cases]


_TARGET = re.compile(r"^(\S+) = ")
_NAME = re.compile(r"\b[A-Za-z_]\w*\b")


def _shared(cases: list[list[str]]) -> tuple[list[str], list[list[str]]]:
    """The lines every case runs alike, moved before the dispatch, and what is left of each case.

    A line is shared when it is in every case, is no ``return``, and reads no name that a
    case defines otherwise (the lines are assignments of pure expressions, each name once
    per case, so a shared line computes the same value wherever it runs). The modes of a
    product repeat many of their signals and flows: UVMS's ``model_outputs`` has 9 cases of
    146 lines (its loads apart: :func:`_hoisted`), 64 of them shared.

    >>> _shared([["a = x[0]", "b = a + 1.0", "out[0] = b"], ["a = x[0]", "b = a - 1.0", "out[0] = b"]])
    (['a = x[0]'], [['b = a + 1.0', 'out[0] = b'], ['b = a - 1.0', 'out[0] = b']])
    """
    if len(cases) < 2:
        return [], cases
    in_all = set(cases[0]).intersection(*cases[1:])
    shared: list[str] = []
    defined: set[str] = set()  # names the shared lines define
    apart: set[str] = set()  # names case 0 defines by a line that is not shared
    for line in cases[0]:
        if not (target := _TARGET.match(line)):
            continue
        if line in in_all and not apart.intersection(_NAME.findall(line[target.end() :])):
            shared.append(line)
            defined.add(target[1])
        else:
            apart.add(target[1])
    chosen = set(shared)
    rest = [[line for line in case if line not in chosen] for case in cases]
    for case, left in zip(cases, rest, strict=True):
        again = {m[1] for line in left if (m := _TARGET.match(line))}
        if len(case) - len(left) != len(shared) or defined & again:
            return [], cases  # a line twice in a case, or a name defined twice: keep as it was
    return shared, rest


def _alike(var: str, cases: list[list[str]], indent: str) -> list[str]:
    """:func:`_dispatch` with each distinct case written once, chosen by its number ``case_``.

    Many transitions of a product reset alike, and many modes flow alike: UVMS's 24
    resets are 9 distinct cases, its 33 guard values 13.

    >>> print("\\n".join(_alike("m", [["a"], ["b"], ["a"]], "")))
    if m < 1:
        case_ = 0
    else:
        if m < 2:
            case_ = 1
        else:
            case_ = 0
    if case_ < 1:
        a
    else:
        b
    """
    bodies = list(dict.fromkeys(map(tuple, cases)))
    if len(bodies) == len(cases):
        return _dispatch(var, cases, indent)
    number = {body: k for k, body in enumerate(bodies)}
    numbers = [number[tuple(case)] for case in cases]
    starts = [i for i, k in enumerate(numbers) if i == 0 or k != numbers[i - 1]]  # runs alike
    choose = _dispatch_at(var, [[f"case_ = {numbers[i]}"] for i in starts], starts, indent)
    return choose + _dispatch("case_", [list(body) for body in bodies], indent)


def _body(var: str, cases: Sequence[list[str]], fallback: str, indent: str) -> list[str]:
    """The lines that run ``cases[var]`` (``fallback`` past the last), each slot loaded once."""
    loads, read = _hoisted(cases)
    shared, rest = _shared(read)
    lines = [f"{indent}{line}" for line in loads + shared]
    lines += _alike(var, rest, indent) if any(rest) else []
    return [*lines, f"{indent}{fallback}"]


def _function(name: str, args: str, cases: Sequence[list[str]], fallback: str) -> list[str]:
    return [f"def {name}({args}):", *_body(args.split(",")[0], cases, fallback, "    "), ""]


_OPERATIONS = (
    # (function, its index, its code, what it returns past its last case)
    ("model_watch", "m", "OP_WATCH", "return"),
    ("model_value", "f", "OP_VALUE", "return _NAN"),
    ("model_truth", "f", "OP_TRUTH", "return False"),
    ("model_rhs", "m", "OP_RHS", "return"),
    ("model_arm", "m", "OP_ARM", "return"),
    ("model_outputs", "m", "OP_OUTPUTS", "return"),
    ("model_reset", "tr", "OP_RESET", "return"),
)
"""The operations of ``model``, in the order its dispatch tests their codes."""


def _inlined(body: dict[str, list[list[str]]]) -> list[str]:
    """``model``'s dispatch with each operation's cases written in it (for a small model).

    What each branch returns is what ``model`` returns for the operation: a value, a
    truth as 1.0 or 0.0, else 0.0. Numba's own inlining of seven functions into one
    copied and retyped their IR: a quarter of a small model's compile.
    """
    lines: list[str] = []
    for k, (name, _, code, fallback) in enumerate(_OPERATIONS):
        cases = body[name]
        if name == "model_truth":
            cases = [[*case[:-1], f"return 1.0 if ({case[-1][len('return ') :]}) else 0.0"]
                     for case in cases]  # fmt: skip
            fallback = "return 0.0"
        elif fallback == "return":
            fallback = "return 0.0"
        lines.append(f"    {'if' if k == 0 else 'elif'} op == {code}:")
        lines += _body("i", cases, fallback, "        ")
    return [*lines, "    return 0.0", ""]


def _calls() -> list[str]:
    """``model``'s dispatch calling each operation's function (for a large model)."""
    lines: list[str] = []
    for k, (name, _, code, _) in enumerate(_OPERATIONS):
        call = f"{name}(i, t, x, p, out)"
        if name == "model_value":
            call = f"return {call}"
        elif name == "model_truth":
            call = f"return 1.0 if {call} else 0.0"
        lines += [f"    {'if' if k == 0 else 'elif'} op == {code}:", f"        {call}"]
    return [*lines, "    return 0.0", ""]


def generate(model: NativeModel) -> Generated:
    """The source of the module that runs ``model`` compiled."""
    states = model.state_names
    modes = model.modes
    n_params = model.n_slots
    max_lv = max(1, *(sum(len(t.levels) for t in m.transitions) for m in modes))
    names = {s: f"x[{i}]" for i, s in enumerate(states)}
    names.update({slot_name(k): f"p[{k}]" for k in range(n_params)})
    names.update({sign_name(a): f"p[{n_params + a}]" for a in range(max_lv)})
    names.update({snap_name(a): f"p[{n_params + max_lv + a}]" for a in range(max_lv)})
    names[BAND_NAME] = f"p[{n_params + 2 * max_lv}]"
    band = ir.Var(BAND_NAME, ir.PARAM)
    for mode in modes:
        names.update({s: f"s_{s}" for s in mode.signals})
    forms = _Forms()
    tables: dict[str, list[int]] = {k: [] for k in TABLES}
    rhs_cases, out_cases, reset_cases, watch_cases, arm_cases = [], [], [], [], []
    watch_sizes: list[int] = []  # each mode's watch terms, and what its arming reads
    arm_sizes: list[int] = []
    outputs_ir = _output_exprs(model)
    levels = 0
    keys: dict[str, int] = {}  # a level's key (hybrid.expr.rho.level_key) -> its number
    for mode in modes:
        flows = [mode.flow.get(s, ir.Num(0.0)) for s in states]
        pre, items = body_lines(flows, mode.signals, names)
        rhs_cases.append(pre + [f"out[{i}] = {v}" for i, v in enumerate(items)])
        pre, items = body_lines(outputs_ir, mode.signals, names)
        out_cases.append(pre + [f"out[{c}] = {v}" for c, v in enumerate(items)])
        tables["MODE_TR"].append(len(tables["TR_TARGET"]))
        tables["MODE_INV"].append(len(tables["INV_RHO"]))
        tables["MODE_URGENT"].append(1 if mode.urgent else 0)
        oriented: list[ir.Expr] = []
        raw: list[ir.Expr] = []
        differences: list[ir.Expr] = []
        for tr in mode.transitions:
            first = len(differences)
            rho = guard_to_rho(tr.guard)
            tables["TR_TARGET"].append(model.index[tr.view.target])
            tables["TR_PRIORITY"].append(tr.view.priority)
            tables["TR_RHO"].append(forms.value(mode, rho))
            tables["TR_BOOL"].append(forms.truth(mode, within_band(tr.guard, band)))
            if tr.levels:
                snapped = tr.snapped(first)
                tables["TR_SRHO"].append(forms.value(mode, guard_to_rho(snapped)))
                tables["TR_SBOOL"].append(forms.truth(mode, within_band(snapped, band)))
            else:
                tables["TR_SRHO"].append(tables["TR_RHO"][-1])
                tables["TR_SBOOL"].append(tables["TR_BOOL"][-1])
            tables["TR_LV"].append(levels + first)
            oriented.append(tr.oriented_rho(first))
            raw.append(rho)
            differences.extend(tr.levels)
            owners = [i for i, _ in tr.view.edges]
            tables["LV_KEY"] += [keys.setdefault(level_key(d, owners), len(keys)) for d in tr.levels]
            resets = [tr.reset.get(s) for s in states]
            pre, items = body_lines([e for e in resets if e is not None], mode.signals, names)
            it = iter(items)
            reset_cases.append(
                pre
                + [
                    f"out[{i}] = {next(it) if e is not None else f'x[{i}]'}"
                    for i, e in enumerate(resets)
                ]
            )
        levels += len(differences)
        for _, expr in mode.invariants:
            tables["INV_RHO"].append(forms.value(mode, guard_to_rho(expr)))
            tables["INV_BOOL"].append(forms.truth(mode, within_band(expr, band)))
        terms = oriented + [guard_to_rho(expr) for _, expr in mode.invariants]
        pre, items = body_lines(terms, mode.signals, names)
        watch_cases.append(pre + [f"out[{k}] = {v}" for k, v in enumerate(items)])
        watch_sizes.append(len(items))
        pre, items = body_lines(raw + differences, mode.signals, names)
        arm_cases.append(pre + [f"out[{k}] = {v}" for k, v in enumerate(items)])
        arm_sizes.append(len(items))
    tables["MODE_TR"].append(len(tables["TR_TARGET"]))
    tables["MODE_INV"].append(len(tables["INV_RHO"]))
    tables["TR_LV"].append(levels)

    def form_cases(chosen: list[tuple[NativeMode, ir.Expr]]) -> list[list[str]]:
        cases = []
        for mode, expr in chosen:
            pre, (item,) = body_lines([expr], mode.signals, names)
            cases.append([*pre, f"return {item}"])
        return cases

    max_tr = max(1, *(len(m.transitions) for m in modes))
    max_inv = max(1, *(len(m.invariants) for m in modes))
    sizes = [len(states), len(model.columns), max_tr, max_lv, max_inv, n_params]
    header, library_modules = _header(model)
    mathlib, helpers = kernel_source(("mathlib",))
    n_pe = n_params + 2 * max_lv + 1  # parameters, level signs, snaps, the band
    out_size = max(1, len(states), len(model.columns), max_tr + max_inv, max_tr + max_lv)
    body = {
        "model_rhs": rhs_cases,
        "model_outputs": out_cases,
        "model_value": form_cases(forms.values),
        "model_truth": form_cases(forms.truths),
        "model_reset": reset_cases,
        "model_watch": watch_cases,
        "model_arm": arm_cases,
    }
    functions: list[str] = []
    for name, index, _, fallback in _OPERATIONS:
        functions += _function(name, f"{index}, t, x, p, out", body[name], fallback)
    op_lines = len(functions)
    # a small model's operations are written into `model`, compiled as one function (less
    # than half the time: numba's cost per function dominates); a large model's apart: numba's
    # typing of one huge function costs more than that of its parts (UVMS mission 2: half its
    # compile)
    inline = op_lines < INLINE_LINES
    pointers = [
        "def model(op, i, t, xp, pp, outp):",
        f"    x = carray(xp, ({max(1, len(states))},))",
        f"    p = carray(pp, ({n_pe},))",
        f"    out = carray(outp, ({out_size},))",
    ]
    if inline:
        functions, dispatch, body = [], _inlined(body), {}
    else:
        dispatch = _calls()
    if model.functions:  # a library's compiled form may raise: an evaluation failure, as NaN
        body["model_ops"], body["model_failed"] = [], []
        functions += [
            "def model_ops(op, i, t, x, p, out):",
            *dispatch,
            "def model_failed(op, i, out):",
            '    """What an operation gives where a library function raised: NaN, a failure."""',
            "    if op == OP_VALUE:",
            "        return _NAN",
            "    if op == OP_TRUTH:",
            "        return 0.0  # its rho, evaluated first, has failed already",
            "    n = 0",
            "    if op == OP_RHS or op == OP_RESET:",
            f"        n = {len(states)}",
            "    elif op == OP_OUTPUTS:",
            f"        n = {len(model.columns)}",
            "    elif op == OP_WATCH:",
            f"        n = {tuple(watch_sizes)!r}[i]",
            "    elif op == OP_ARM:",
            f"        n = {tuple(arm_sizes)!r}[i]",
            "    for k in range(n):",
            "        out[k] = _NAN",
            "    return 0.0",
            "",
            *pointers,
            "    try:",
            "        return model_ops(op, i, t, x, p, out)",
            "    except Exception:",
            "        return model_failed(op, i, out)",
            "",
        ]
    else:
        functions += [*pointers, *dispatch]
    footer = [
        "",
        "# ---- compiled with numba (cached on disk beside this file) ----",
        "def build():",
        '    """Compile or load the model: importing this module does no work, this does."""',
        "    global model",
        f"    for _name in {tuple(helpers)!r}:",
        f"        globals()[_name] = njit({JIT})(globals()[_name])",  # LLVM inlines them
        *(
            [f"    for _name in {tuple(body)!r}:", f"        globals()[_name] = njit({JIT})(globals()[_name])"]
            if body
            else []
        ),
        "    with warnings.catch_warnings():",
        "        warnings.simplefilter('ignore', NumbaExperimentalFeatureWarning)",
        "        model = cfunc(model_signature(), cache=True, error_model='numpy')(model)",
        "",
    ]
    source = "\n".join([*header, mathlib, "", *functions, *footer])
    tab = _table(sizes, tables)
    estimate = MODEL_BASE_S + MODEL_SECONDS_PER_LINE * op_lines
    return Generated(source, library_modules, tab, estimate)


_SOURCES = HeldCache[tuple[NativeModel, Generated]](16)


def native_source(model: System) -> tuple[NativeModel, Generated]:
    """``model``'s :class:`NativeModel` and generated source, made once per structure in a
    process (:func:`~hybrid.simulation.native.structure.structure_key`): the backend's
    choice, the compile notice and the compile itself each need the source (UVMS:
    0.37 s to generate), and the points of a sweep share it.
    """

    def make() -> tuple[NativeModel, Generated]:
        native = NativeModel(model)
        return native, generate(native)

    key, objects = structure_key(model)
    return _SOURCES.get(key, objects, make)


def _table(sizes: list[int], tables: dict[str, list[int]]) -> NDArray[np.int64]:
    """The model's ``tab``: the sizes, where each table starts, then the tables."""
    header = list(sizes) + [0] * len(TABLES)
    assert len(header) == TAB_HEADER
    data: list[int] = []
    for k, name in enumerate(TABLES):
        header[T_MODE_TR + k] = TAB_HEADER + len(data)
        data += tables[name]
    return np.array(header + data, dtype=np.int64)


def _output_exprs(model: NativeModel) -> list[ir.Expr]:
    """Every signal column, as :class:`hybrid.simulation.compiled.CompiledModel` lists them."""
    exprs: list[ir.Expr] = []
    for c in model.system.components:
        sizes = c.automaton.vector_sizes
        for name in c.automaton.signal_names:
            if name in sizes:
                exprs.extend(ir.Index(name, k) for k in range(sizes[name]))
            else:
                exprs.append(ir.Var(name, ir.SIGNAL))
    return exprs


def _header(model: NativeModel) -> tuple[list[str], tuple[str, ...]]:
    lines = [
        # no name: systems of one structure share the compiled module (and numba's cache)
        '"""Generated by hybrid: do not edit (see docs/backends.md)."""',
        "from __future__ import annotations",
        "import math",
        "import numpy as np",
        "import warnings",
        "from numba import carray, cfunc, njit",
        "from numba.core.errors import NumbaExperimentalFeatureWarning",
        "from hybrid.simulation.native.buffers import OP_ARM, OP_OUTPUTS, OP_RESET, OP_RHS",
        "from hybrid.simulation.native.buffers import OP_TRUTH, OP_VALUE, OP_WATCH",
        "from hybrid.simulation.native.kernel_types import model_signature",
        "_NAN = math.nan",
        "_INF = math.inf",
    ]
    modules = []
    for name, function in model.functions.items():
        module, qualname = importable(name, getattr(function.fn, COMPILED_FORM))
        modules.append(module)
        lines += [
            f"from {module} import {qualname} as _imp_{name}",
            f"_lib_{name} = _imp_{name} if hasattr(_imp_{name}, 'py_func') "
            f"else njit({JIT})(_imp_{name})",
        ]
    return lines, tuple(sorted(set(modules)))
