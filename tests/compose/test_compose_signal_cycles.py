"""Signals defined through each other across components: reported only where the
definitions can be in force together (one location per component)."""

from __future__ import annotations

import numpy as np
import pytest

import hybrid
from hybrid.binding import COMBINATIONS_CHECKED
from hybrid.compose import compose

SWITCHER = """
automaton: a
state: {x: {initial: 0}}
inputs: [v]
signals: {s1: "0", s2: "0"}
locations:
  a1: {flow: {x: 1}, signals: {s1: "v + 1"}}
  a2: {flow: {x: 1}, signals: {s2: "{S2}"}}
edges:
  - {from: a1, to: a2, guard: "x >= 1", reset: {x: 0}}
  - {from: a2, to: a1, guard: "x >= 1", reset: {x: 0}}
"""

DOUBLER = """
automaton: b
state: {y: {initial: 0}}
inputs: [s2]
signals: {v: "2 * s2"}
locations:
  b1: {flow: {y: v}}
"""


def _system(s2: str) -> hybrid.System:
    a = hybrid.load_text(SWITCHER.replace("{S2}", s2))
    b = hybrid.load_text(DOUBLER)
    assert isinstance(a, hybrid.Automaton) and isinstance(b, hybrid.Automaton)
    return compose(a, b, name="ab")


def test_a_cycle_only_through_the_union_of_locations_is_no_cycle() -> None:
    # s1 -> v -> s2 -> s1 uses s1's definition in a1 and s2's in a2: never both at once
    run = hybrid.simulate(_system("s1 + 1"), t_end=2.5, handle_sigint=False)
    assert [j.target for j in run.jumps] == ["a.a2|b.b1", "a.a1|b.b1"]
    a1 = run.location == "a.a1|b.b1"
    a2 = run.location == "a.a2|b.b1"
    # by hand: in a1, s2 = 0 so v = 0 and s1 = v + 1 = 1; in a2, s1 = 0, s2 = 1, v = 2
    np.testing.assert_array_equal(run["s1"][a1], 1.0)
    np.testing.assert_array_equal(run["v"][a1], 0.0)
    np.testing.assert_array_equal(run["v"][a2], 2.0)
    # y' = v: 0 on [0, 1], 2 on [1, 2], 0 after
    assert run["y"][-1] == pytest.approx(2.0, abs=1e-9)


def test_a_cycle_in_one_combination_names_it() -> None:
    with pytest.raises(hybrid.SpecError) as err:
        _system("v + 1")  # in a2: s2 -> v -> s2
    assert err.value.message.endswith(
        "signals of the components form a circular definition when a is in a2: s2 -> v -> s2"
    )


def test_too_many_combinations_fall_back_to_the_union() -> None:
    count = 2 * int(COMBINATIONS_CHECKED**0.5)  # two components: count**2 combinations
    params = ", ".join(f"k{i}: {i}" for i in range(count))

    def automaton(name: str, mine: str, other: str) -> hybrid.Automaton:
        # each location reads another parameter: distinct definitions, one per location
        body = ", ".join(f'l{i}: {{signals: {{{mine}: "{other} + k{i}"}}}}' for i in range(count))
        model = hybrid.load_text(
            f"automaton: {name}\nparameters: {{{params}}}\ninputs: [{other}]\n"
            f"signals: {{{mine}: '0'}}\nlocations: {{{body}}}\n"
        )
        assert isinstance(model, hybrid.Automaton)
        return model

    assert count**2 > COMBINATIONS_CHECKED
    with pytest.raises(hybrid.SpecError, match=r"in some location of each\): p -> q -> p"):
        compose(automaton("left", "p", "q"), automaton("right", "q", "p"), name="many")


PLANT = """
automaton: plant
state: {x: {initial: 20}}
inputs: [cmd]
parameters: {P: 2}
signals: {power: cmd * P}
locations:
  cooling: {flow: {x: -x + power}}
  heating: {flow: {x: -x + power}, signals: {power: P}}
"""

CONTROLLER = """
automaton: ctrl
state: {c: {initial: 0}}
inputs: [power]
signals:
  cmd: 0
locations:
  idle: {flow: {c: 1}}
  on:
    flow: {c: 1}
    signals: {cmd: power}
"""


def test_a_cycle_names_every_component_s_location_and_is_placed_in_it() -> None:
    """The loop cmd -> power -> cmd needs plant in cooling (no power of its own there) and
    ctrl in on: the message named ctrl alone, and was placed at ctrl's file-level 'cmd: 0',
    which is not in the loop."""
    plant = hybrid.load_text(PLANT, file="plant.yaml")
    ctrl = hybrid.load_text(CONTROLLER, file="ctrl.yaml")
    assert isinstance(plant, hybrid.Automaton) and isinstance(ctrl, hybrid.Automaton)
    with pytest.raises(hybrid.SpecError) as err:
        compose(plant, ctrl, name="loop")
    assert err.value.message.endswith(
        "form a circular definition when plant is in cooling and ctrl is in on: "
        "cmd -> power -> cmd"
    )
    on = ctrl.locations["on"].position
    assert (err.value.position.file, err.value.position.line) == ("ctrl.yaml", on.line)
