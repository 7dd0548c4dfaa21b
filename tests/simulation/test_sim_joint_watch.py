"""The watch from one call of a mode's terms (events.joint_watch_factory) is the watch.

The truth is the watch built from the guards' and invariants' own functions, one
by one (events.watch_factory), as before: at any point the joint watch must be the
same number, and where an evaluation fails it must record the same failure (the
one-by-one functions do it). Where a term's own function reads numpy scalars, or a
guard is read in an oriented form, the joint form must not be used.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import hybrid
from hybrid.compose import as_system
from hybrid.simulation import events
from hybrid.simulation.compiled import CompiledModel
from hybrid.simulation.events import Watch

TWO_GUARDS = """
automaton: ring
state: {x: {initial: 1.0}, y: {initial: 0.0}}
signals: {r: "sqrt(x*x + y*y)", a: "atan2(y, x)"}
locations:
  spin:
    flow: {x: -y, y: x}
    invariant: "r <= 2.0"
initial: {location: spin}
edges:
  - {name: flip, from: spin, to: spin, guard: "a >= 2.5 and r >= 0.5", reset: {x: "-x"}}
  - {name: low, from: spin, to: spin, guard: "log(x + 1.5) <= -3", reset: {x: "1.0"}}
"""


def _mode(text: str) -> tuple[CompiledModel, object]:
    compiled = CompiledModel(as_system(hybrid.load_text(text)))
    return compiled, compiled.mode(compiled.initial_key)


def _one_by_one(mode: object, armed: list[bool], x0: np.ndarray, width: float) -> Watch:
    original = events._joint
    try:
        events._joint = _term_by_term
        return Watch(mode, armed, 0.0, x0, width, {})  # type: ignore[arg-type]
    finally:
        events._joint = original


def _term_by_term(key: object) -> object:
    """In place of the joint watch's factory: the watch of the terms one by one."""
    return lambda values, failure, each, b0: each


@pytest.mark.parametrize("armed", [[True, True], [False, True], [True, False]])
def test_the_joint_watch_is_the_watch_term_by_term(armed: list[bool]) -> None:
    _, mode = _mode(TWO_GUARDS)
    assert mode.terms is not None  # type: ignore[attr-defined]
    x0 = np.array([1.0, 0.0])
    joint = Watch(mode, armed, 0.0, x0, 1e-9, {})  # type: ignore[arg-type]
    alone = _one_by_one(mode, armed, x0, 1e-9)
    assert "_values" in joint.value.__code__.co_freevars  # type: ignore[union-attr]
    assert "_values" not in alone.value.__code__.co_freevars  # type: ignore[union-attr]
    rng = np.random.default_rng(7)
    points = rng.uniform(-2.5, 2.5, size=(400, 2))
    points[:3] = [[0.0, 0.0], [-0.0, 1.0], [-1.4, 1e-300]]  # zeros, a tiny y
    values = []
    for t, x in zip(rng.uniform(0, 9, 400), points, strict=True):
        a, b = joint.value(float(t), x), alone.value(float(t), x)  # type: ignore[misc]
        assert a == b or (math.isnan(a) and math.isnan(b)), (x, a, b)
        values.append(a)
    assert min(values) < 0.0 < max(values)  # both signs seen: the terms take turns


def test_a_failing_term_is_recorded_as_its_own_function_records_it() -> None:
    compiled, mode = _mode(TWO_GUARDS)
    x0 = np.array([1.0, 0.0])
    joint = Watch(mode, [True, True], 0.0, x0, 1e-9, {})  # type: ignore[arg-type]
    alone = _one_by_one(mode, [True, True], x0, 1e-9)
    bad = np.array([-1.75, 0.5])  # log(x + 1.5) of a negative number: the second guard fails
    found = []
    for watch in (joint, alone):
        compiled.failure.clear()
        value = watch.value(0.0, bad)  # type: ignore[misc]
        found.append((value, compiled.failure.where, type(compiled.failure.error)))
        assert compiled.terms_failure.error is None  # the joint function's own record is cleared
    assert found[0] == found[1]
    assert found[0][1].startswith("g_") and found[0][2] is ValueError


def test_runs_are_the_same_with_and_without_the_joint_watch(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    model = hybrid.load_text(TWO_GUARDS)
    ours = hybrid.simulate(model, t_end=20.0)
    monkeypatch.setattr(events, "_joint", _term_by_term)
    theirs = hybrid.simulate(model, t_end=20.0)
    assert len(ours.jumps) >= 3
    assert np.array_equal(ours.t, theirs.t) and np.array_equal(ours.states, theirs.states)
    assert np.array_equal(ours.signals, theirs.signals)
    assert [j.t for j in ours.jumps] == [j.t for j in theirs.jumps]


def test_no_joint_form_where_a_term_reads_numpy_scalars() -> None:
    # the thermostat's invariant T >= T_low and guard T <= T_low read x[0] directly
    compiled = CompiledModel(as_system(hybrid.load("specs/thermostat.yaml")))
    mode = compiled.mode(compiled.initial_key)
    assert len(mode.transitions) + len(mode.invariants) >= 2
    assert type(mode.invariants[0].rho(0.0, np.array([20.0]))) is np.float64
    assert mode.terms is None


def test_no_joint_form_for_an_oriented_equality_guard() -> None:
    text = """
automaton: level
state: {x: {initial: 0.0}, y: {initial: 1.0}}
locations:
  up:
    flow: {x: 1.0, y: 0.0}
    invariant: "sin(x) <= 2"
initial: {location: up}
edges:
  - {name: hit, from: up, to: up, guard: "cos(x) * y == 0.5", reset: {y: "2.0 * y"}}
"""
    _, mode = _mode(text)
    assert mode.terms is not None  # type: ignore[attr-defined]
    watch = Watch(mode, [True], 0.0, np.array([0.0, 1.0]), 1e-9, {})  # type: ignore[arg-type]
    # the guard is read oriented (its level atom one-sided): term by term, not jointly
    assert watch.value is not None and "_values" not in watch.value.__code__.co_freevars
