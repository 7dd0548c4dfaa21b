"""A function sharing a stash reads its signals only at the very point they were kept.

The stepped flow keeps the signals it computed (``codegen.Stash``); the
outputs and conditions of the same mode read them when called at the same
``t`` and the same state bytes, and must then give exactly what they give
computing alone; anywhere else (another time, a state that differs only in
the sign of a zero, another flow's stash) they compute.
"""

from __future__ import annotations

import math

import numpy as np

from hybrid.expr.codegen import CodeContext, Stash, compile_function
from hybrid.expr.functions import Function
from hybrid.expr.parse import Scope, parse_expression

CALLS: list[tuple[float, float]] = []


def _polar(x: float, y: float) -> float:
    CALLS.append((x, y))
    return math.atan2(y, x)  # sign-sensitive at zeros: atan2(0, -0.0) = pi, atan2(0, 0.0) = 0


POLAR = Function("polar", _polar, 2, 2, builtin=False)
SCOPE = Scope({"x": "state", "y": "state", "p": "signal", "q": "signal"}, {"polar": POLAR})
SIGNALS = {
    "p": parse_expression("polar(x, y)", SCOPE),
    "q": parse_expression("p * t + polar(y, x)", SCOPE),
}
CTX = CodeContext(states=("x", "y"), signals=SIGNALS, functions={"polar": POLAR})


def _pair(slot: list[object]) -> tuple[object, object, object]:
    stash = Stash(slot)
    flow = compile_function("flow", [parse_expression("-p", SCOPE)], CTX, stash=stash)
    out = compile_function("out", [parse_expression("q + 1", SCOPE)], CTX, share=stash)
    alone = compile_function("alone", [parse_expression("q + 1", SCOPE)], CTX)
    return flow, out, alone


def test_the_shared_value_is_the_value_computed_alone_at_the_stash_point() -> None:
    flow, out, alone = _pair([None])
    for t, x, y in [(0.5, 1.0, 2.0), (np.float64(1.25), -3.0, 0.5), (2.0, 0.0, -1.0)]:
        state = np.array([x, y])
        assert flow(t, state) == [-math.atan2(y, x)]
        CALLS.clear()
        shared = out(float(t), state)
        assert [(y, x)] == CALLS  # p was read from the stash, only polar(y, x) computed
        assert shared == alone(float(t), state) == [math.atan2(y, x) * t + math.atan2(x, y) + 1]


def test_another_point_is_computed() -> None:
    flow, out, alone = _pair([None])
    flow(0.5, np.array([1.0, 2.0]))
    for t, state in [(0.75, np.array([1.0, 2.0])), (0.5, np.array([1.0, 2.5]))]:
        CALLS.clear()
        assert out(t, state) == alone(t, state)
        assert len(CALLS) == 4  # both polar calls, in out and in alone


def test_a_zero_of_the_other_sign_is_another_point() -> None:
    flow, out, alone = _pair([None])
    flow(1.0, np.array([0.0, 0.0]))  # p = atan2(0, 0.0) = 0
    state = np.array([-0.0, 0.0])  # equal as numbers, p = atan2(0, -0.0) = pi
    assert out(1.0, state) == alone(1.0, state) == [math.pi + math.atan2(-0.0, 0.0) + 1]
    # a time of -0.0 is not the stash's 0.0 either: atan2(t, -1) is pi there, -pi here
    signals = {"p": parse_expression("polar(-1, t)", SCOPE)}
    ctx = CodeContext(states=("x", "y"), signals=signals, functions={"polar": POLAR})
    stash = Stash([None])
    flow = compile_function("flow", [parse_expression("p", SCOPE)], ctx, stash=stash)
    out = compile_function("out", [parse_expression("p", SCOPE)], ctx, share=stash)
    state = np.array([1.0, 1.0])
    assert flow(0.0, state) == [math.pi]
    assert out(-0.0, state) == [-math.pi]
    assert out(0.0, state) == [math.pi]


def test_another_flows_stash_is_not_read() -> None:
    slot: list[object] = [None]
    flow_a, _, _ = _pair(slot)
    _, out_b, alone = _pair(slot)
    flow_a(0.5, np.array([1.0, 2.0]))
    CALLS.clear()
    assert out_b(0.5, np.array([1.0, 2.0])) == alone(0.5, np.array([1.0, 2.0]))
    assert len(CALLS) == 4


def test_the_stepped_flow_takes_t_as_a_float() -> None:
    seen: list[type] = []
    clock = Function("clock", lambda t: seen.append(type(t)) or t, 1, 1, builtin=False)
    scope = Scope({"x": "state", "c": "signal"}, {"clock": clock})
    ctx = CodeContext(
        states=("x",), signals={"c": parse_expression("clock(t)", scope)}, functions={"clock": clock}
    )
    flow = compile_function("flow", [parse_expression("c", scope)], ctx, stash=Stash([None]))
    plain = compile_function("plain", [parse_expression("c", scope)], ctx)
    flow(np.float64(2.0), np.array([0.0]))
    plain(np.float64(2.0), np.array([0.0]))
    assert seen == [float, np.float64]
