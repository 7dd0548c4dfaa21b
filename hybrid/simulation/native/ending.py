"""How a compiled run ended, worded as the reference engine words it.

The counterpart of the messages :class:`hybrid.simulation.loop.EventLoop`
writes into a :class:`~hybrid.simulation.result.Termination`: the texts are
the same, so a user reads the same thing from either backend. An evaluation
failure is described by running the reference engine's compiled function at
the failing point (:func:`hybrid.simulation.failures.describe_failure`), so
the message names the expression and its arguments exactly as it does there.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any

import numpy as np

from hybrid.compose import System
from hybrid.model import Automaton
from hybrid.simulation.native import buffers as b
from hybrid.simulation.native.names import Layout
from hybrid.simulation.native.structure import NativeModel
from hybrid.simulation.result import Termination
from hybrid.simulation.settings import Settings

__all__ = ["Inputs", "describe_native_failure", "termination_of"]

Inputs = Mapping[str, Callable[[float], float]] | None
"""The reference engine's inputs of a model (to word a failure as the reference does)."""


def termination_of(
    native: NativeModel,
    layout: Layout,
    model: Automaton | System,
    settings: Settings,
    buf: b.RunArrays,
    inputs: Inputs = None,
) -> Termination:
    """How the run in ``buf`` ended, worded as the reference engine words it.

    A plain end (``t_end``, ``max_jumps``, ``interrupted``) where the last run
    of the same model ended is that run's record again (it is frozen): a
    repeated run builds none.
    """
    oi, of = buf.oi.tolist(), buf.of.tolist()  # Python numbers, read at once
    detail = oi[b.I_DETAIL]
    if detail == b.D_NONE:
        t = of[b.F_T]
        key = (oi[b.I_CAUSE], t, math.copysign(1.0, t), oi[b.I_J], oi[b.I_MODE],
               settings.max_jumps)  # fmt: skip
        last = _LAST_END[0]
        if last is not None and last[0] is native and last[1] == key:
            return last[2]
        plain = _termination(native, layout, model, settings, buf, inputs, oi, of)
        _LAST_END[0] = (native, key, plain)  # one tuple, replaced at once
        return plain
    return _termination(native, layout, model, settings, buf, inputs, oi, of)


_LAST_END: list[tuple[NativeModel, tuple[Any, ...], Termination] | None] = [None]
"""The last plain end: its model structure, key (cause, t and its sign, j, mode, max_jumps) and
record."""


def _termination(native: NativeModel, layout: Layout, model: Automaton | System,
                 settings: Settings, buf: b.RunArrays, inputs: Inputs, oi: list[int],
                 of: list[float]) -> Termination:  # fmt: skip
    """:func:`termination_of` from ``buf``'s counts and numbers read as ``oi`` and ``of``."""
    cause = b.CAUSE_CODES[oi[b.I_CAUSE]]
    t, j, m = of[b.F_T], oi[b.I_J], oi[b.I_MODE]
    detail, index = oi[b.I_DETAIL], oi[b.I_DETAIL_INDEX]
    mode = native.modes[m]
    zeno_time = of[b.F_ZENO_TIME] if cause == "zeno" else None
    if detail == b.D_INITIAL:
        message = "initial state is not finite"
    elif detail in (b.D_BLOCKED_ENTRY, b.D_BLOCKED_FLOW):
        how = "does not hold" if detail == b.D_BLOCKED_ENTRY else "is about to be left"
        message = f"invariant of {mode.invariants[index][0]} {how} and no transition is enabled"
    elif detail == b.D_URGENT:
        message = (
            f"urgent location {', '.join(mode.urgent)}: no time may pass there and no "
            "transition is enabled"
        )
    elif detail == b.D_STALL:
        message = (
            "events keep firing at the same instant without any transition "
            "becoming enabled (a guard touching its boundary?)"
        )
    elif detail == b.D_ZENO_INSTANT:
        name = layout.transitions[index][2].view.name
        message = (
            f"{settings.max_jumps_per_instant} jumps at the same instant: a cycle of "
            f"transitions takes no time (last: {name})"
        )
    elif detail == b.D_ZENO_GEOMETRIC:
        message = (
            "jumps accumulate (gaps shrink geometrically); estimated Zeno time "
            f"{zeno_time:.12g}"
        )
    elif detail == b.D_RESET_NONFINITE:
        message = f"reset of {layout.transitions[index][2].view.name} gave a non-finite state"
    elif detail in (b.D_EVAL, b.D_FLOW):
        fail_t = float(buf.of[b.F_FAIL_T])
        described = describe_native_failure(native, layout, model, buf, inputs)
        if described is None:
            what = _reference_function(int(buf.oi[b.I_FAIL_KIND]), int(buf.oi[b.I_FAIL_INDEX]),
                                       int(buf.oi[b.I_FAIL_MODE]), None, layout, native)[0]  # fmt: skip
            described = f"{what} gave a non-finite value"
        message = f"{described} (at t={fail_t:.9g})"
        if detail == b.D_FLOW:
            message += f"; the solution leaves the domain of the flow after t={t:.9g}"
        if detail == b.D_EVAL:
            t = fail_t
    elif detail in (b.D_STEP_TOO_SMALL, b.D_STATE_NONFINITE):
        why = (
            "solver stopped: Required step size is less than spacing between numbers."
            if detail == b.D_STEP_TOO_SMALL
            else "the state became non-finite"
        )
        message = (
            f"{why} (largest |state| {float(buf.of[b.F_PEAK]):.3g}; the solution may blow up "
            "here, or try another --method or tighter tolerances)"
        )
    elif detail == b.D_NOT_ADVANCING:
        message = (
            "solver stopped advancing: its step size fell below the spacing of floating-point "
            f"numbers at t={t:.9g} (largest |state| {float(buf.of[b.F_PEAK]):.3g}; the solution "
            "may blow up here, or try another --method)"
        )
    elif detail == b.D_CRAWL:
        message = _crawl_message(settings, t, buf)
    elif detail == b.D_FLOW_START:
        message = _flow_at_start(native, layout, model, buf, index, inputs)
    elif cause == "t_end":
        message = "reached t_end"
    elif cause == "max_jumps":
        message = f"reached max_jumps={settings.max_jumps}"
    else:
        message = "interrupted by the user"
    return Termination(cause, t, j, message, zeno_time=zeno_time, location=mode.name)


def _crawl_message(settings: Settings, t: float, buf: b.RunArrays) -> str:
    """``StayIntegrator._crawled``'s words."""
    from hybrid.simulation.stay import CRAWL_STEPS

    pace, longest = float(buf.of[b.F_AUX0]), float(buf.of[b.F_AUX1])
    remaining = (settings.t_end - t) / pace
    return (
        f"solver crawls: its last {CRAWL_STEPS} steps averaged {pace:.3g} (it took steps of "
        f"{longest:.3g} before), so t_end is still {remaining:.2g} steps away (largest "
        f"|state| {float(buf.of[b.F_PEAK]):.3g}); the solution may near a singularity here (a "
        "derivative without bound) and chatter across it"
    )


def _flow_at_start(native: NativeModel, layout: Layout, model: Automaton | System,
                   buf: b.RunArrays, index: int, inputs: Inputs) -> str:  # fmt: skip
    """``StayIntegrator._start``'s words for a flow that fails or is not finite at the start."""
    t = float(buf.of[b.F_FAIL_T])
    described = describe_native_failure(native, layout, model, buf, inputs)
    if described is not None:
        return f"{described} (at t={t:.9g})"
    x = np.array(buf.of[b.N_OUT_F : b.N_OUT_F + len(native.state_names)], dtype=float)
    mode = native.modes[int(buf.oi[b.I_FAIL_MODE])]
    derivative = _reference_mode(native, model, int(buf.oi[b.I_FAIL_MODE]), inputs)[1].rhs(t, x)
    names = native.state_names
    bad = next((k for k, v in enumerate(derivative) if not math.isfinite(v)), index)
    return f"the flow of {mode.name} gives {names[bad]}' = {derivative[bad]} (at t={t:.9g})"


def _reference_mode(native: NativeModel, model: Automaton | System, m: int,
                    inputs: Inputs) -> tuple[Any, Any]:  # fmt: skip
    """The reference engine's compiled model and its mode ``m`` (for the words of a failure)."""
    from hybrid.simulation.compiled import CompiledModel
    from hybrid.simulation.start import run_inputs

    compiled = CompiledModel(model, run_inputs(model, inputs))
    return compiled, compiled.mode(native.modes[m].key)


def describe_native_failure(native: NativeModel, layout: Layout, model: Automaton | System,
                            buf: b.RunArrays, inputs: Inputs = None) -> str | None:  # fmt: skip
    """``<what> failed: <call(args)>: <error>``, found by the reference engine's functions.

    None if the reference's function does not fail at that point (a value that
    is not finite without an error).
    """
    from hybrid.simulation.failures import describe_failure

    kind, index = int(buf.oi[b.I_FAIL_KIND]), int(buf.oi[b.I_FAIL_INDEX])
    m = int(buf.oi[b.I_FAIL_MODE])
    t = float(buf.of[b.F_FAIL_T])
    x = np.array(buf.of[b.N_OUT_F : b.N_OUT_F + len(native.state_names)], dtype=float)
    compiled, mode = _reference_mode(native, model, m, inputs)
    _, call = _reference_function(kind, index, m, mode, layout)
    call(t, x)
    for failure in (compiled.failure, compiled.flow_failure):
        if failure.error is not None:
            return str(describe_failure(compiled, failure))
    return None


def _reference_function(kind: int, index: int, m: int, mode: Any, layout: Layout,
                        native: NativeModel | None = None) -> Sequence[Any]:  # fmt: skip
    """``(what, the reference's function)`` that failed (``mode`` None: the words only)."""
    names = native.modes[m] if native is not None else mode
    if kind in (b.F_GUARD, b.F_RESET):
        k = layout.transitions[index][1]
        name = names.transitions[k].view.name if native is not None else mode.transitions[k].name
        what = f"the {'guard' if kind == b.F_GUARD else 'reset'} of {name}"
        if mode is None:
            return what, None
        tr = mode.transitions[k]
        return what, tr.rho if kind == b.F_GUARD else tr.reset
    if kind == b.F_INVARIANT:
        inv = index - layout.invariant_first[m]
        name = names.invariants[inv][0] if native is not None else mode.invariants[inv].name
        return f"the invariant of {name}", None if mode is None else mode.invariants[inv].rho
    if kind == b.F_SIGNALS:
        return f"the signals of {names.name}", None if mode is None else mode.outputs
    return f"the flow of {names.name}", None if mode is None else mode.rhs
