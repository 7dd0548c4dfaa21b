"""One model type inside: an automaton becomes a system once, and that system stands for it.

The public entry points turn the user's model into a :class:`System` with
``as_system`` and pass only systems below. The system of one automaton must
then behave as the automaton in everything a user sees: its parameter names
and their messages, its locations' plain names, its runs; and it must be the
same object for the same automaton, so that the caches keyed by a model's
identity (compiled forms, flowpipe forms) still serve repeated runs.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from support import SPECS

import hybrid
from hybrid.campaigns.space import declared_ranges
from hybrid.compose import Model, System, as_system
from hybrid.simulation.start import held_inputs

BALL = SPECS / "bouncing_ball.yaml"
DRIFT = """\
automaton: drift
state: {x: {initial: [0, 2]}}
inputs: {u: {range: [1, 3]}}
locations: {l: {flow: {x: u}}}
"""


def test_the_same_automaton_gives_the_same_system() -> None:
    ball = hybrid.load(BALL)
    system = as_system(ball)
    assert as_system(ball) is system and as_system(system) is system
    assert system.single and system.components[0].automaton is ball
    other = hybrid.load(BALL)  # equal, but another object: its own system
    assert as_system(other) is not system and as_system(other).name == system.name


def test_a_system_of_one_takes_the_automatons_parameter_names_and_messages() -> None:
    ball = hybrid.load(BALL)
    system = as_system(ball)
    moon = system.with_parameters({"g": 1.62})
    assert isinstance(moon, System) and moon.single
    assert moon.components[0].automaton.parameters["g"] == 1.62
    for bad in ({"gravity": 1.0}, {"bouncing_ball.g": 1.0}, {"g": "heavy"}):
        with pytest.raises(hybrid.SpecError) as from_automaton:
            ball.with_parameters(bad)  # type: ignore[dict-item]
        with pytest.raises(hybrid.SpecError) as from_system:
            system.with_parameters(bad)  # type: ignore[dict-item]
        assert str(from_system.value) == str(from_automaton.value)


def test_a_system_of_one_runs_as_its_automaton() -> None:
    ball = hybrid.load(BALL)
    a = hybrid.simulate(ball, 3.0, rtol=1e-10, atol=1e-12, handle_sigint=False)
    s = hybrid.simulate(as_system(ball), 3.0, rtol=1e-10, atol=1e-12, handle_sigint=False)
    np.testing.assert_array_equal(a.states, s.states)
    assert a.location.tolist() == s.location.tolist()  # plain names: 'falling', not 'ball.falling'
    assert abs(a.jumps[0].t - math.sqrt(2 * 10 / 9.81)) < 1e-9


def test_what_both_models_share_is_read_without_converting() -> None:
    drift = hybrid.load_text(DRIFT)

    def shared(model: Model) -> tuple[object, ...]:
        return (model.name, model.state_names, model.initial_vector(), model.initial_set(),
                model.input_ranges())  # fmt: skip

    assert shared(drift) == shared(as_system(drift))
    assert declared_ranges(drift) == declared_ranges(as_system(drift)) == {
        "init.x": (0.0, 2.0),
        "input.u": (1.0, 3.0),
    }
    held = held_inputs(drift, None)
    assert list(held) == ["u"] and held["u"](0.0) == 2.0  # the midpoint of [1, 3]
