"""The engine's Runge-Kutta step (hybrid.simulation.stepper) against scipy's own, bit for bit.

The truth is scipy's RK45 / RK23 stepped side by side on the same problem: every
accepted step (time, state, stages, step size) must be the same doubles, including
steps that scipy rejects and shrinks, steps clipped to ``t_bound`` and ``max_step``.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from scipy.integrate import DOP853, RK23, RK45, Radau

import hybrid
from hybrid.simulation.stepper import SteppedRK23, SteppedRK45, stepped

PAIRS = [(RK45, SteppedRK45), (RK23, SteppedRK23)]


def _van_der_pol(t: float, y: np.ndarray) -> list[float]:
    mu = 8.0
    return [y[1], mu * (1.0 - y[0] ** 2) * y[1] - y[0]]


def _forced(t: Any, y: np.ndarray) -> list[float]:
    return [math.cos(3.0 * float(t)) - 0.5 * y[0] + y[1], -y[0] * y[1] + math.sin(float(t))]


def _side_by_side(
    theirs_class: Any, ours_class: Any, fun: Any, y0: list[float], t_end: float, **kwargs: Any
) -> int:
    theirs = theirs_class(fun, 0.0, np.array(y0), t_end, **kwargs)
    ours = ours_class(fun, 0.0, np.array(y0), t_end, **kwargs)
    steps = 0
    while theirs.status == "running":
        assert ours.status == "running"
        assert ours.step() == theirs.step()
        steps += 1
        assert ours.t == theirs.t and ours.t_old == theirs.t_old
        assert np.array_equal(ours.y, theirs.y)
        assert np.array_equal(ours.y_old, theirs.y_old)
        assert np.array_equal(ours.f, theirs.f)
        assert np.array_equal(ours.K, theirs.K)  # the interpolant is built from K
        assert ours.h_abs == theirs.h_abs and ours.h_previous == theirs.h_previous
    assert ours.status == theirs.status
    return steps


@pytest.mark.parametrize(("theirs_class", "ours_class"), PAIRS)
@pytest.mark.parametrize(
    "kwargs",
    [
        {"rtol": 1e-8, "atol": 1e-10},
        {"rtol": 1e-3, "atol": 1e-6},
        {"rtol": 1e-6, "atol": 1e-9, "max_step": 0.05},
        {"rtol": 1e-6, "atol": np.array([1e-9, 1e-6]), "first_step": 0.7},
    ],
)
def test_steps_are_scipys_bit_for_bit(theirs_class: Any, ours_class: Any, kwargs: Any) -> None:
    # van der Pol with mu = 8: the step size swings over orders of magnitude, with rejections
    steps = _side_by_side(theirs_class, ours_class, _van_der_pol, [2.0, 0.0], 20.0, **kwargs)
    assert steps > 20
    _side_by_side(theirs_class, ours_class, _forced, [1.0, -1.0], 7.3, **kwargs)


def test_rejected_steps_are_taken_as_scipy_does() -> None:
    # a first step far too long: scipy rejects it and shrinks; so must the copy
    calls: list[int] = []

    def fun(t: Any, y: np.ndarray) -> list[float]:
        calls.append(1)
        return _van_der_pol(t, y)

    theirs = RK45(_van_der_pol, 0.0, np.array([2.0, 0.0]), 20.0, first_step=5.0)
    ours = SteppedRK45(fun, 0.0, np.array([2.0, 0.0]), 20.0, first_step=5.0)
    before = len(calls)
    theirs.step(), ours.step()
    assert len(calls) - before > 6  # more than one attempt's six stages
    assert ours.t == theirs.t and np.array_equal(ours.y, theirs.y)


def test_the_plain_right_hand_side_still_gets_numpy_time() -> None:
    seen: list[type] = []

    def fun(t: Any, y: np.ndarray) -> list[float]:
        seen.append(type(t))
        return [-y[0]]

    solver = SteppedRK45(fun, 0.0, np.array([1.0]), 1.0)
    seen.clear()
    solver.step()
    assert seen and set(seen) == {np.float64}  # as scipy passes it (numpy does not raise on 1/0)
    floats = SteppedRK45(fun, 0.0, np.array([1.0]), 1.0, float_time=True)
    seen.clear()
    floats.step()
    assert seen and set(seen) == {float}


def test_only_the_explicit_pairs_are_stepped() -> None:
    assert stepped(RK45) is SteppedRK45 and stepped(RK23) is SteppedRK23
    assert stepped(DOP853) is None and stepped(Radau) is None


@pytest.mark.parametrize("method", ["RK45", "RK23"])
def test_runs_are_unchanged_by_the_stepper(method: str, monkeypatch: pytest.MonkeyPatch) -> None:
    # the whole engine with scipy's own classes (the stepper switched off) is the truth
    from hybrid.simulation import stay

    models = [hybrid.load("specs/bouncing_ball.yaml"), hybrid.load("specs/thermostat.yaml")]
    ours = [hybrid.simulate(model, t_end=12.0, method=method) for model in models]
    monkeypatch.setattr(stay, "stepped", lambda method: None)
    theirs = [hybrid.simulate(model, t_end=12.0, method=method) for model in models]
    for a, b in zip(ours, theirs, strict=True):
        assert len(a.jumps) >= 2
        assert np.array_equal(a.t, b.t) and np.array_equal(a.states, b.states)
        assert np.array_equal(a.signals, b.signals)
        assert [jump.t for jump in a.jumps] == [jump.t for jump in b.jumps]


def _fields(solver: Any) -> dict[str, Any]:
    """What a step reads of a solver (scipy's fields; K is scratch the step overwrites)."""
    names = ("t", "t_old", "t_bound", "y", "y_old", "f", "h_abs", "h_previous", "direction",
             "status", "n", "rtol", "atol", "max_step", "error_exponent")  # fmt: skip
    return {name: getattr(solver, name) for name in names}


def _same(ours: dict[str, Any], theirs: dict[str, Any], types: bool = False) -> None:
    """The same values (and, with ``types``, types: the stepper's times are floats, scipy's
    numpy scalars, after a step)."""
    for name, value in theirs.items():
        if isinstance(value, np.ndarray):
            assert np.array_equal(ours[name], value), name
        else:
            assert ours[name] == value, name
            assert not types or type(ours[name]) is type(value), name


@pytest.mark.parametrize(("theirs_class", "ours_class"), PAIRS)
@pytest.mark.parametrize("first_step", [None, 0.01])
def test_a_restarted_solver_is_the_one_scipy_constructs(
    theirs_class: Any, ours_class: Any, first_step: float | None
) -> None:
    # one stay of van der Pol, then a new stay of another flow from where it ended: the
    # restarted solver against scipy's constructed there, field by field and step by step
    kwargs: dict[str, Any] = {"rtol": 1e-8, "atol": 1e-10, "max_step": 0.5}
    ours = ours_class(_van_der_pol, 0.0, np.array([2.0, 0.0]), 20.0, **kwargs)
    for _ in range(30):
        ours.step()
    t1, y1 = float(ours.t), ours.y.copy()
    ours.restart(_forced, t1, y1, first_step, False)
    theirs = theirs_class(_forced, t1, y1, 20.0, first_step=first_step, **kwargs)
    _same(_fields(ours), _fields(theirs), types=True)
    assert ours.nfev == theirs.nfev  # the start's evaluations (the stepper counts none after)
    # every field scipy's constructor sets, so that a new one in a later scipy is noticed
    wrappers = {"fun", "fun_single", "fun_vectorized", "_fun"}
    assert set(theirs.__dict__) <= set(ours.__dict__)
    _same({k: ours.__dict__[k] for k in theirs.__dict__ if k not in wrappers | {"K"}},
          {k: v for k, v in theirs.__dict__.items() if k not in wrappers | {"K"}}, types=True)  # fmt: skip
    assert ours.K.shape == theirs.K.shape and ours.K.dtype == theirs.K.dtype
    for _ in range(40):
        assert ours.step() == theirs.step()
        _same(_fields(ours), _fields(theirs))
        assert np.array_equal(ours.K, theirs.K)


def test_a_restart_refuses_what_scipy_refuses() -> None:
    ours = SteppedRK45(_van_der_pol, 0.0, np.array([2.0, 0.0]), 1.0)
    for y0, first_step in (([math.nan, 0.0], None), ([1.0, 0.0], 5.0), ([1.0, 0.0], -0.1)):
        with pytest.raises(ValueError) as theirs:
            RK45(_forced, 0.5, np.array(y0), 1.0, first_step=first_step)
        with pytest.raises(ValueError) as refused:
            ours.restart(_forced, 0.5, np.array(y0), first_step, False)
        assert str(refused.value) == str(theirs.value)


def test_a_restart_takes_the_new_flow_and_its_time(monkeypatch: pytest.MonkeyPatch) -> None:
    # a stay of a plain right-hand side after one of a stepped flow (keeps): numpy time again
    seen: list[tuple[type, int]] = []

    def kept(t: Any, y: np.ndarray, at_end: bool = True) -> list[float]:
        seen.append((type(t), 3))
        return [-y[0]]

    def plain(t: Any, y: np.ndarray) -> list[float]:
        seen.append((type(t), 2))
        return [-y[0]]

    solver = SteppedRK45(kept, 0.0, np.array([1.0]), 2.0, keeps=True)
    solver.step()
    solver.restart(plain, float(solver.t), solver.y, None, False)
    seen.clear()
    solver.step()
    assert seen and set(seen) == {(np.float64, 2)}
    solver.restart(kept, float(solver.t), solver.y, None, True)
    seen.clear()
    solver.step()
    assert seen and set(seen) == {(float, 3)}


def test_runs_with_stepped_flows_are_unchanged_by_restarts(monkeypatch: pytest.MonkeyPatch) -> None:
    # UVMS mission 1: flows whose signals call library functions (the stepped flow keeps
    # them), 10 stays; the truth is the engine constructing scipy's solver at every stay
    from hybrid.simulation import stepper
    from hybrid.simulation.stay import StayIntegrator
    from uvms_model.missions import specs_dir

    model = hybrid.load(specs_dir() / "uvms_mission_1.yaml")
    restarts: list[int] = []
    restart = stepper._Stepped.restart

    def counted(self: Any, *args: Any) -> None:
        restarts.append(1)
        restart(self, *args)

    monkeypatch.setattr(stepper._Stepped, "restart", counted)
    ours = hybrid.simulate(model, t_end=30.0, rtol=1e-8, atol=1e-10, handle_sigint=False)
    monkeypatch.setattr(StayIntegrator, "restarts", False)
    count = len(restarts)
    theirs = hybrid.simulate(model, t_end=30.0, rtol=1e-8, atol=1e-10, handle_sigint=False)
    assert count >= 2 and len(restarts) == count  # restarted, then not at all
    assert len(ours.jumps) >= 2
    assert np.array_equal(ours.t, theirs.t) and np.array_equal(ours.j, theirs.j)
    assert np.array_equal(ours.states, theirs.states)
    assert np.array_equal(ours.signals, theirs.signals, equal_nan=True)
    assert [(jump.t, jump.edge) for jump in ours.jumps] == [(jump.t, jump.edge) for jump in theirs.jumps]
    assert ours.termination == theirs.termination
