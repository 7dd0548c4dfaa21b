"""The stepped flow reuses a library call's value only at the very same arguments.

The flow a solver steps (compiled with ``stash=``) memoizes a signal that calls a
library function and reads only ``t``, numbers and the state variables the mode
keeps (flow 0): a Runge-Kutta step evaluates its last stage and its end at the
same ``t``. Arguments equal as numbers but not the same value (``0.0`` and
``-0.0``; ``NaN``, equal to nothing) must never stand for each other; a signal
that reads a moving state variable or an input is never memoized; and a
simulation gives exactly what it gives without the memo.
"""

from __future__ import annotations

import math

import numpy as np
from support import SPECS

import hybrid
from hybrid.expr.codegen import CodeContext, Stash, compile_function
from hybrid.expr.functions import Function
from hybrid.expr.parse import Scope, parse_expression
from hybrid.simulation.stepper import SteppedRK45

CALLS: list[tuple[float, ...]] = []


def _polar(y: float, x: float) -> float:
    CALLS.append((y, x))
    return math.atan2(y, x)  # tells zeros apart: atan2(0.0, -1) = pi, atan2(-0.0, -1) = -pi


POLAR = Function("polar", _polar, 2, 2, builtin=False)
SCOPE = Scope(
    {"a": "state", "b": "state", "p": "signal", "q": "signal", "u": "input"}, {"polar": POLAR}
)


def _flow(definition: str, steady: frozenset[str] = frozenset({"a"}), **inputs: object) -> object:
    signals = {"p": parse_expression(definition, SCOPE)}
    ctx = CodeContext(
        states=("a", "b"),
        signals=signals,
        functions={"polar": POLAR},
        inputs={name: [fn] for name, fn in inputs.items()},  # type: ignore[misc]
    )
    exprs = [parse_expression("0", SCOPE), parse_expression("p", SCOPE)]
    return compile_function("flow", exprs, ctx, stash=Stash([None]), steady=steady)


def test_the_same_time_and_kept_state_reuse_the_value() -> None:
    flow = _flow("polar(t, a)")
    CALLS.clear()
    assert flow(0.5, np.array([-1.0, 3.0]), False) == [0.0, math.atan2(0.5, -1.0)]
    assert flow(0.5, np.array([-1.0, 7.0])) == [0.0, math.atan2(0.5, -1.0)]  # b is not read
    assert CALLS == [(0.5, -1.0)]
    assert flow(0.25, np.array([-1.0, 7.0])) == [0.0, math.atan2(0.25, -1.0)]
    assert flow(0.25, np.array([-2.0, 7.0])) == [0.0, math.atan2(0.25, -2.0)]
    assert CALLS == [(0.5, -1.0), (0.25, -1.0), (0.25, -2.0)]


def test_signed_zeros_and_nan_are_never_one_anothers_arguments() -> None:
    flow = _flow("polar(t, a)")
    for _ in range(2):  # the second round meets each value right after its twin
        CALLS.clear()
        assert flow(0.0, np.array([-1.0, 0.0]))[1] == math.pi
        assert flow(-0.0, np.array([-1.0, 0.0]))[1] == -math.pi
        assert flow(-0.0, np.array([-1.0, 0.0]))[1] == -math.pi  # memo
        assert CALLS == [(0.0, -1.0), (-0.0, -1.0)]
        assert [math.copysign(1.0, t) for t, _ in CALLS] == [1.0, -1.0]
    flow = _flow("polar(a, -1.0) + 0.0 * t")  # a kept state variable of either sign
    CALLS.clear()
    assert flow(1.0, np.array([0.0, 0.0]))[1] == math.pi
    assert flow(1.0, np.array([0.0, 0.0]))[1] == math.pi  # memo
    assert flow(1.0, np.array([-0.0, 0.0]))[1] == -math.pi
    assert [math.copysign(1.0, a) for a, _ in CALLS] == [1.0, -1.0]
    flow = _flow("polar(t, a)")
    CALLS.clear()
    for _ in range(2):
        assert math.isnan(flow(math.nan, np.array([-1.0, 0.0]))[1])
    assert len(CALLS) == 2  # NaN equals nothing, not even itself: computed each time


def test_number_types_of_t_reach_the_function_as_the_same_float() -> None:
    flow = _flow("polar(t, a)")
    CALLS.clear()
    values = [flow(t, np.array([-1.0, 0.0]))[1] for t in (1, 1.0, True, np.float64(1.0))]
    assert values == [math.atan2(1.0, -1.0)] * 4 == [3 * math.pi / 4] * 4
    assert CALLS == [(1.0, -1.0)] and type(CALLS[0][0]) is float


def test_moving_state_and_inputs_are_never_memoized() -> None:
    moving = _flow("polar(t, b)")
    CALLS.clear()
    moving(0.5, np.array([0.0, -1.0]))
    moving(0.5, np.array([0.0, -1.0]))
    assert len(CALLS) == 2  # b moves: no memo at all
    gains = iter([1.0, 2.0])
    read = _flow("polar(u, a)", u=lambda t: next(gains))
    CALLS.clear()
    assert read(0.5, np.array([-1.0, 0.0]))[1] == math.atan2(1.0, -1.0)
    assert read(0.5, np.array([-1.0, 0.0]))[1] == math.atan2(2.0, -1.0)
    assert CALLS == [(1.0, -1.0), (2.0, -1.0)]


def test_a_stage_is_not_kept_the_step_end_is() -> None:
    stash = Stash([None])
    signals = {"p": parse_expression("polar(t, b)", SCOPE)}
    ctx = CodeContext(states=("a", "b"), signals=signals, functions={"polar": POLAR})
    exprs = [parse_expression("0", SCOPE), parse_expression("p", SCOPE)]
    flow = compile_function("flow", exprs, ctx, stash=stash)
    solver = SteppedRK45(flow, 0.0, np.array([1.0, -1.0]), 1.0, keeps=True, first_step=0.125)
    solver.step()
    kept = stash.slot[0]
    assert kept is not None and kept[1] == solver.t == 0.125
    assert kept[2] == solver.y.tobytes()
    plain = compile_function("rhs", exprs, ctx)
    again = SteppedRK45(plain, 0.0, np.array([1.0, -1.0]), 1.0, float_time=True, first_step=0.125)
    again.step()
    assert again.t == solver.t and again.y.tobytes() == solver.y.tobytes()


def test_a_mission_runs_as_without_the_memo(monkeypatch: object) -> None:
    import hybrid.simulation.compiled as compiled_module

    model = hybrid.load(SPECS / "uvms_mission_2.yaml")
    kwargs = dict(t_end=12.0, rtol=1e-6, atol=1e-9, handle_sigint=False)
    memo = hybrid.simulate(model, **kwargs)
    original = compiled_module.compile_function

    stepped: list[object] = []

    def without(*args: object, **kw: object) -> object:
        if kw.pop("steady", None):
            stepped.append(args[0])
        return original(*args, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(compiled_module, "compile_function", without)  # type: ignore[attr-defined]
    plain = hybrid.simulate(hybrid.load(SPECS / "uvms_mission_2.yaml"), **kwargs)
    assert stepped and len(memo.jumps) >= 1  # the stepped flows compiled again, without it
    assert memo.t.tobytes() == plain.t.tobytes()
    assert memo.states.tobytes() == plain.states.tobytes()
    assert memo.signals.tobytes() == plain.signals.tobytes()
    assert [j.t for j in memo.jumps] == [j.t for j in plain.jumps]
