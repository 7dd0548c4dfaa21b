"""What failed, and where: user messages for evaluation errors of compiled functions.

A compiled function that fails (a math domain error, an overflow) records the
error in an :class:`~hybrid.expr.codegen.EvalFailure` and returns NaN. Here the
failure becomes ``<what> failed: <call(args)>: <error>``: the role of the
function ("the flow of A", "the guard of e"), and the innermost call or
operation that fails at the failing point, shown with its argument values
(found by re-evaluating, so only on this rare path).

Examples
--------
>>> import hybrid
>>> from hybrid.simulation.compiled import CompiledModel
>>> m = hybrid.load_text("automaton: a\\nstate: {x: {initial: -1}}\\nlocations: {l: {flow: {x: sqrt(x)}}}\\n")
>>> from hybrid.compose import as_system
>>> compiled = CompiledModel(as_system(m))
>>> import numpy as np
>>> _ = compiled.mode(compiled.initial_key).rhs(0.0, np.array([-1.0]))
>>> describe_failure(compiled, compiled.flow_failure)
'the flow of l failed: sqrt(-1): math domain error'
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from typing import Any

from hybrid.expr import ir
from hybrid.expr.codegen import CodeContext, EvalFailure, compile_function
from hybrid.expr.dependencies import evaluation_order
from hybrid.expr.generated import FRAME_PREFIX
from hybrid.modes import Mode
from hybrid.simulation.compiled import CompiledModel

__all__ = ["describe_failure"]


def describe_failure(
    compiled: CompiledModel, failure: EvalFailure, mode: Mode | None = None
) -> str:
    """``<what> failed: <call(args)>: <error>`` for a failure recorded in ``mode``.

    A function compiled once and reused in several modes records its failures
    under one name; ``mode`` (where the failure happened) says which mode's
    description to use.
    """
    source = compiled.source(failure.where, mode)
    error = failure.error
    culprit = None
    from_input = isinstance(error, ValueError) and str(error).startswith("input ")
    if source is not None and error is not None and not from_input:
        point = _failure_point(error, compiled.state_names)
        if point is not None:
            culprit = _culprit(list(source.exprs), source.context, *point)
    what = source.what if source is not None else failure.where
    detail = f"{culprit}: {error}" if culprit else f"{error}"
    return f"{what} failed: {detail}"


def _failure_point(error: BaseException, states: Sequence[str]) -> tuple[float, list[float]] | None:
    """``(t, x)`` at which a compiled function failed, read from its frame."""
    tb = error.__traceback__
    while tb is not None:
        local = tb.tb_frame.f_locals
        if tb.tb_frame.f_code.co_filename.startswith(FRAME_PREFIX) and "t" in local:
            try:
                if all(f"x_{s}" in local for s in states):
                    return float(local["t"]), [float(local[f"x_{s}"]) for s in states]
                return float(local["t"]), [float(v) for v in local["x"]]
            except (KeyError, TypeError, ValueError):
                return None
        tb = tb.tb_next
    return None


def _post_order(node: ir.Expr) -> list[ir.Expr]:
    """Every node, children before parents, left to right."""
    out: list[ir.Expr] = []
    stack: list[tuple[ir.Expr, bool]] = [(node, False)]
    while stack:
        current, expanded = stack.pop()
        if expanded:
            out.append(current)
            continue
        stack.append((current, True))
        stack.extend((c, False) for c in reversed(ir.children(current)))
    return out


def _culprit(exprs: list[ir.Expr], ctx: CodeContext, t: float, x: list[float]) -> str | None:
    """The innermost call or operation of ``exprs`` that fails at ``(t, x)``, shown with values."""
    point = _Point(float(v) for v in x)
    probe = replace(ctx, failure=EvalFailure())
    used: set[str] = set()
    for e in exprs:
        used |= ir.names_in(e)
    roots = [ctx.signals[s] for s in evaluation_order(used, ctx.signals)] + list(exprs)

    def value(node: ir.Expr) -> Any:
        probe.failure.clear()
        result = compile_function("probe", [node], probe, shape="scalar")(t, point)
        return None if probe.failure.error is not None else result

    for root in roots:
        for node in _post_order(root):
            if not isinstance(node, ir.Call | ir.Bin):
                continue
            if value(node) is not None:
                continue
            args = node.args if isinstance(node, ir.Call) else (node.left, node.right)
            shown = [_show(value(a)) for a in args]
            if isinstance(node, ir.Call):
                return f"{node.func}({', '.join(shown)})"
            return f"{shown[0]} {node.op} {shown[1]}"
    return None


class _Point(list[float]):
    """A state as plain floats that compiled functions can read like an array.

    Plain floats keep Python's arithmetic, which raises on a division by zero or
    an overflow where numpy scalars would only warn, so the probe finds the culprit.
    """

    def tolist(self) -> list[float]:
        return list(self)


def _show(value: Any) -> str:
    if isinstance(value, float | int):
        return f"{float(value):.6g}"
    return "?"
