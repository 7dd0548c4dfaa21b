"""The compiled backend and the field features: each runs as scipy runs it, or is refused by name."""

from __future__ import annotations

import numpy as np
import pytest

import hybrid
from hybrid.compose import compose
from hybrid.errors import UsageError

pytest.importorskip("numba")

TOL = {"rtol": 1e-10, "atol": 1e-12, "handle_sigint": False}

TANK = """
automaton: tank
state: {h: {initial: 2.0}}
locations:
  fill: {flow: {h: 1}}
  drain: {flow: {h: -2}}
edges:
  - {name: full, from: fill, to: drain, guard: h >= 4}
  - {name: empty, from: drain, to: fill, guard: h <= 1}
"""
# the same tank under other names (no clash in a composition), filling at a rate read as input u
OTHER = (
    TANK.replace("tank", "other").replace("{h: 1}", "{g: 0.5}").replace("{h: -2}", "{g: -2}")
    .replace("h: {", "g: {").replace("h >=", "g >=").replace("h <=", "g <=")
)  # fmt: skip
INPUT = TANK.replace("state:", "inputs: {u: {range: [0.5, 1.5]}}\nstate:").replace("{h: 1}", "{h: u}")
SOURCE = """
automaton: source
state: {u: {initial: 1.0}}
locations: {on: {flow: {u: 0.1}}}
"""


def agree(model: hybrid.Automaton | hybrid.System, t_end: float = 12.0) -> hybrid.Run:
    compiled = hybrid.simulate(model, t_end=t_end, backend="compiled", **TOL)  # type: ignore[arg-type]
    reference = hybrid.simulate(model, t_end=t_end, **TOL)  # type: ignore[arg-type]
    assert [(j.edge, j.source, j.target) for j in compiled.jumps] == [
        (j.edge, j.source, j.target) for j in reference.jumps
    ]
    np.testing.assert_allclose(compiled.jump_times, reference.jump_times, rtol=1e-10, atol=1e-9)
    assert compiled.termination.cause == reference.termination.cause
    assert compiled.settings["start"] == reference.settings["start"]
    return compiled


def test_initial_set_starts_at_its_nominal_point() -> None:
    tank = hybrid.load_text(TANK.replace("{initial: 2.0}", "{initial: [1.0, 3.0], nominal: 2.5}"))
    run = agree(tank)
    assert run.jump_times[:3] == pytest.approx([1.5, 3.0, 6.0], abs=1e-9)  # from 2.5 up to 4 at rate 1


def test_several_initial_locations_start_in_the_first() -> None:
    tank = hybrid.load_text(TANK.replace("state:", "initial: {location: [drain, fill]}\nstate:"))
    run = agree(tank)
    assert run.jumps[0].edge == "empty" and run.jumps[0].t == pytest.approx(0.5, abs=1e-9)


def test_input_bound_to_a_state_variable_of_another_component() -> None:
    system = compose(hybrid.load_text(SOURCE), hybrid.load_text(INPUT), name="bound")
    run = agree(system)
    # h = 2 + t + 0.05 t^2 reaches 4 at t = 10 (sqrt(1.4) - 1)
    assert run.jump_times[0] == pytest.approx(10 * (np.sqrt(1.4) - 1), rel=1e-9)


def test_independent_components_merged_in_hybrid_time() -> None:
    system = compose(hybrid.load_text(TANK), hybrid.load_text(OTHER), name="apart")
    run = agree(system)
    assert {j.edge for j in run.jumps} >= {"tank.full", "other.full", "other.empty"}


def test_a_free_input_with_a_range_is_held_at_its_nominal_value() -> None:
    # u in [0.5, 1.5], no nominal given: held at the midpoint 1, so h = 2 + t reaches 4 at
    # t = 2, then h = 4 - 2 (t - 2) reaches 1 at t = 3.5; alone, and beside another tank
    run = agree(hybrid.load_text(INPUT))
    assert run.jump_times[:2] == pytest.approx([2.0, 3.5], abs=1e-9)
    assert run.settings["start"]["inputs"] == {"u": 1.0}
    nominal = INPUT.replace("range: [0.5, 1.5]", "range: [0.5, 1.5], nominal: 0.5")
    assert agree(hybrid.load_text(nominal)).jump_times[0] == pytest.approx(4.0, abs=1e-9)
    system = agree(compose(hybrid.load_text(INPUT), hybrid.load_text(OTHER), name="open"))
    assert next(j.t for j in system.jumps if j.edge == "tank.full") == pytest.approx(2.0, abs=1e-9)


URGENT = TANK.replace("drain: {flow", "drain: {urgent: true, flow")


def test_an_urgent_location_blocks_at_once_where_no_edge_fires() -> None:
    # h = 2 + t reaches 4 at t = 2; drain is urgent and `empty` (h <= 1) is false there
    run = agree(hybrid.load_text(URGENT))
    assert run.jump_times == pytest.approx([2.0], abs=1e-9)
    assert run.termination.cause == "blocked" and run.termination.t == pytest.approx(2.0, abs=1e-9)
    assert "urgent location drain" in run.termination.message


def test_a_free_input_without_a_range_needs_a_value_on_both_backends() -> None:
    unbounded = hybrid.load_text(INPUT.replace("{u: {range: [0.5, 1.5]}}", "{u: {}}"))
    with pytest.raises(UsageError, match="input 'u' needs a value"):
        hybrid.simulate(unbounded, t_end=1.0, handle_sigint=False)
    with pytest.raises(UsageError, match=r"input 'u' of tank needs a value.*backend='scipy'"):
        hybrid.simulate(unbounded, t_end=1.0, backend="compiled", handle_sigint=False)
