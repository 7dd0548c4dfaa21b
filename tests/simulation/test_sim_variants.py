"""Variants of a model (a sweep's points) share what their changed parameters do not reach.

A variant's bound expressions are the same objects as its sibling's wherever the
parameters they read have the same values, bit for bit (``hybrid.modes``), and a
generated source met again is not compiled again (``hybrid.expr.generated``). Each
variant must still run with its own values: the bouncing ball's impact times have a
closed form in ``g`` and ``e``, checked for variants run one after another in one
process, where everything they could share is shared.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support import SPECS

import hybrid
from hybrid.compose import as_system
from hybrid.expr import ir
from hybrid.expr.generated import define
from hybrid.modes import Binder, mode_of
from hybrid.simulation.compiled import CompiledModel

BALL = hybrid.load(SPECS / "bouncing_ball.yaml")
H0 = 10.0


def _impacts(g: float, e: float, count: int) -> list[float]:
    """t1 = sqrt(2 h0 / g), then a flight of 2 e^k t1 after the k-th impact."""
    t1 = math.sqrt(2 * H0 / g)
    times = [t1]
    for k in range(1, count):
        times.append(times[-1] + 2 * e**k * t1)
    return times


def test_variants_run_one_after_another_each_with_its_own_values() -> None:
    # e changes the reset only, g the flow and the energy; some pairs repeat a value
    for g, e in [(9.81, 0.8), (9.81, 0.5), (3.7, 0.5), (3.7, 0.8), (9.81, 0.8), (1.62, 0.9)]:
        variant = BALL.with_parameters({"g": g, "e": e})
        run = hybrid.simulate(variant, t_end=6.0, max_jumps=5, rtol=1e-11, atol=1e-13)
        expected = [t for t in _impacts(g, e, 5) if t <= 6.0]
        assert [jump.t for jump in run.jumps] == pytest.approx(expected, abs=1e-8), (g, e)
        energy = run["energy"][0]
        assert energy == pytest.approx(g * H0, rel=1e-12), (g, e)


def _view(model: hybrid.Automaton) -> tuple[ir.Expr, ir.Expr, ir.Expr]:
    """The bound flow of v, the bound reset of v and the bound energy of the ball's mode."""
    system = as_system(model)
    view = mode_of(system, system.initial_mode, binder=Binder(system))
    (transition,) = view.transitions
    return view.flow["v"], transition.reset["v"], view.signals["energy"]


def test_a_variant_shares_the_bound_expressions_its_change_does_not_reach() -> None:
    flow, reset, energy = _view(BALL)
    other_flow, other_reset, other_energy = _view(BALL.with_parameters({"e": 0.5}))
    assert other_flow is flow and other_energy is energy  # they read g only
    assert other_reset is not reset
    assert 0.5 in {n.value for n in ir.walk(other_reset) if isinstance(n, ir.Num)}
    assert 0.8 in {n.value for n in ir.walk(reset) if isinstance(n, ir.Num)}


def test_a_zero_of_the_other_sign_is_another_value() -> None:
    _, zero, _ = _view(BALL.with_parameters({"e": 0.0}))
    _, negative_zero, _ = _view(BALL.with_parameters({"e": -0.0}))
    assert negative_zero is not zero
    (value,) = {math.copysign(1.0, n.value) for n in ir.walk(negative_zero) if isinstance(n, ir.Num)}
    assert value == -1.0


def test_a_variant_compiles_again_only_what_its_change_reaches() -> None:
    key = as_system(BALL).initial_mode
    base = CompiledModel(as_system(BALL)).mode(key)
    reset_only = CompiledModel(as_system(BALL.with_parameters({"e": 0.25}))).mode(key)
    flow_too = CompiledModel(as_system(BALL.with_parameters({"g": 1.62}))).mode(key)
    assert reset_only.rhs.__code__ is base.rhs.__code__  # the same source: compiled once
    assert flow_too.rhs.__code__ is not base.rhs.__code__
    x = np.array([1.0, -2.0])
    assert base.rhs(0.0, x)[1] == -9.81 and flow_too.rhs(0.0, x)[1] == -1.62


def test_a_source_met_again_is_compiled_once_per_name() -> None:
    source = "def twice(x):\n    return 2.0 * x\n"
    first, again = define("twice", source, {}), define("twice", source, {"_unused": 1})
    assert first.__code__ is again.__code__ and again(21.0) == 42.0
    renamed = define("twice_b", source.replace("twice", "twice_b"), {})
    assert renamed.__code__ is not first.__code__
    assert renamed.__code__.co_filename == "<hybrid:twice_b>"
