"""The field's constructs in simulation, against closed forms.

Initial sets start at their nominal point (else the midpoint), several initial
locations at the first, free inputs with a range are held at their nominal value
when none is given; each choice is recorded in ``run.settings["start"]`` and
printed by the CLI. Urgent locations let no time pass. A template bound twice
with ``rename``, and an input bound to another component's state variable,
compose and simulate as the closed forms say.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from support import run_cli

import hybrid
from hybrid.model import Range

TOL = {"rtol": 1e-10, "atol": 1e-12}

RAMP = """
automaton: ramp
state:
  x: {initial: [0.0, 2.0]NOMINAL}
locations:
  low: {flow: {x: 1}}
  high: {}
edges:
  - {name: up, from: low, to: high, guard: x >= 3}
"""


def test_an_initial_set_starts_at_its_midpoint_and_says_so() -> None:
    m = hybrid.load_text(RAMP.replace("NOMINAL", ""))
    assert m.initial_set()["x"] == Range(0.0, 2.0, 1.0, False)
    run = hybrid.simulate(m, t_end=5.0, **TOL)
    # x = 1 + t reaches 3 at t = 2
    assert run.jumps[0].t == pytest.approx(2.0, abs=1e-12)
    start = run.settings["start"]
    assert start["state"] == {"x": 1.0} and start["location"] == "low"
    assert start["notes"] == ["x starts at the midpoint 1 of its initial set [0, 2]"]


def test_a_nominal_point_is_where_the_run_starts() -> None:
    m = hybrid.load_text(RAMP.replace("NOMINAL", ", nominal: 0.5"))
    run = hybrid.simulate(m, t_end=5.0, **TOL)
    assert run.jumps[0].t == pytest.approx(2.5, abs=1e-12)  # x = 0.5 + t
    assert run.settings["start"]["notes"] == [
        "x starts at its nominal 0.5 of its initial set [0, 2]"
    ]


def test_an_override_is_a_point_and_no_choice_to_report() -> None:
    m = hybrid.load_text(RAMP.replace("NOMINAL", ""))
    run = hybrid.simulate(m, t_end=5.0, initial={"x": 1.75}, **TOL)
    assert run.jumps[0].t == pytest.approx(1.25, abs=1e-12)
    assert run.settings["start"]["notes"] == []
    assert m.with_initial(state={"x": 1.75}).initial_set()["x"].is_point


def test_initial_sets_in_initial_state_and_in_a_component() -> None:
    m = hybrid.load_text(
        RAMP.replace("NOMINAL", "")
        + "initial: {location: low, state: {x: {initial: [1, 2], nominal: 1.25}}}\n"
    )
    assert m.initial_set()["x"] == Range(1.0, 2.0, 1.25, True)
    assert hybrid.simulate(m, t_end=5.0, **TOL).jumps[0].t == pytest.approx(1.75, abs=1e-12)


INPUT = """
automaton: drift
state: {x: {initial: 0}}
inputs: {u: {range: [1, 3]NOMINAL}}
locations:
  go: {flow: {x: u}}
  stop: {}
edges:
  - {from: go, to: stop, guard: x >= 6}
"""


@pytest.mark.parametrize(("nominal", "expected"), [("", 3.0), (", nominal: 1.5", 4.0)])
def test_a_free_input_is_held_at_its_nominal_value(nominal: str, expected: float) -> None:
    m = hybrid.load_text(INPUT.replace("NOMINAL", nominal))
    run = hybrid.simulate(m, t_end=10.0, **TOL)
    # x = u t reaches 6 at t = 6 / u (u = 2, the midpoint, or the nominal 1.5)
    assert run.jumps[0].t == pytest.approx(expected, abs=1e-12)
    assert run.settings["start"]["inputs"] == {"u": 6.0 / expected}
    assert "input u is held at" in run.settings["start"]["notes"][0]


def test_a_given_input_replaces_the_nominal_value() -> None:
    m = hybrid.load_text(INPUT.replace("NOMINAL", ""))
    run = hybrid.simulate(m, t_end=10.0, inputs={"u": lambda t: 3.0}, **TOL)
    assert run.jumps[0].t == pytest.approx(2.0, abs=1e-12)
    assert run.settings["start"]["inputs"] == {} and run.settings["start"]["notes"] == []


def test_an_input_without_a_range_still_needs_a_value() -> None:
    m = hybrid.load_text(
        "automaton: a\nstate: {x: {}}\ninputs: [u]\nlocations: {l: {flow: {x: u}}}\n"
    )
    with pytest.raises(hybrid.UsageError, match="input 'u' needs a value"):
        hybrid.simulate(m, t_end=1.0)


URGENT = """
automaton: relay
state: {x: {initial: 0}, c: {initial: 0}}
locations:
  charge: {flow: {x: 1}}
  decide: {urgent: true, flow: {x: 1}}
  fire: {flow: {x: -1}}
edges:
  - {name: full, from: charge, to: decide, guard: x >= 1}
  - {name: go, from: decide, to: fire, guard: c >= LEVEL, reset: {c: c + 1}}
  - {name: back, from: fire, to: charge, guard: x <= 0}
"""




def test_an_urgent_location_is_left_at_once(backend: str) -> None:
    run = hybrid.simulate(hybrid.load_text(URGENT.replace("LEVEL", "0")), t_end=5.0,
                          backend=backend, **TOL)  # fmt: skip
    # charge 1 s, decide and fire at the same instant, discharge 1 s, ...
    times = [j.t for j in run.jumps]
    assert [j.edge for j in run.jumps[:4]] == ["full", "go", "back", "full"]
    assert times[:4] == pytest.approx([1.0, 1.0, 2.0, 3.0], abs=1e-12)
    assert run.termination.cause == "t_end"


def test_an_urgent_location_with_no_edge_enabled_blocks_at_once(backend: str) -> None:
    run = hybrid.simulate(hybrid.load_text(URGENT.replace("LEVEL", "1")), t_end=5.0,
                          backend=backend, **TOL)  # fmt: skip
    assert [j.edge for j in run.jumps] == ["full"]
    term = run.termination
    assert term.cause == "blocked" and term.t == pytest.approx(1.0, abs=1e-12)
    assert term.location == "decide" and "urgent location decide" in term.message
    assert run.t[-1] == term.t  # no time passed in decide, although its flow would let it


def test_several_initial_locations_start_in_the_first_and_say_so() -> None:
    m = hybrid.load_text(URGENT.replace("LEVEL", "0") + "initial: {location: [fire, charge]}\n")
    assert m.initial_locations == ("fire", "charge") and m.initial_location == "fire"
    run = hybrid.simulate(m, t_end=0.5)
    assert run.location[0] == "fire" and run.jumps[0].edge == "back" and run.jumps[0].t == 0.0
    assert run.settings["start"]["notes"] == [
        "starts in 'fire', the first of its initial locations fire, charge"
    ]
    other = hybrid.simulate(m, t_end=0.5, initial_location="charge")
    assert other.location[0] == "charge" and other.settings["start"]["notes"] == []


LAG = """
automaton: lag
parameters: {k: 1.0}
state: {y: {initial: 0}}
inputs: [u]
labels: [tick]
locations:
  track: {flow: {y: k * (u - y)}}
"""
SOURCE = """
automaton: source
state: {s: {initial: 1}}
signals: {level: 2}
locations:
  decay: {flow: {s: -s}}
"""


def _system(tmp_path: Path, components: str) -> hybrid.System:
    (tmp_path / "lag.yaml").write_text(LAG)
    (tmp_path / "source.yaml").write_text(SOURCE)
    (tmp_path / "system.yaml").write_text("system: chain\ncomponents:\n" + components)
    m = hybrid.load(tmp_path / "system.yaml")
    assert isinstance(m, hybrid.System)
    return m


def test_a_template_bound_twice_with_renames(tmp_path: Path) -> None:
    m = _system(
        tmp_path,
        "  - {spec: source.yaml}\n"
        "  - {spec: lag.yaml, as: first, rename: {u: level, y: y1}, parameters: {k: 2.0}}\n"
        "  - {spec: lag.yaml, as: second, rename: {u: s, y: y2}, initial: {state: {y: 0.5}}}\n",
    )
    assert m.state_names == ("s", "y1", "y2")
    run = hybrid.simulate(m, t_end=3.0, dt=0.25, **TOL)
    t = run.t
    # y1' = 2 (2 - y1), y1(0) = 0: y1 = 2 (1 - e^(-2t)); s = e^-t;
    # y2' = e^-t - y2, y2(0) = 0.5: y2 = (t + 0.5) e^-t
    assert np.abs(run["y1"] - 2 * (1 - np.exp(-2 * t))).max() < 1e-8
    assert np.abs(run["y2"] - (t + 0.5) * np.exp(-t)).max() < 1e-8


def test_a_free_input_of_a_system_is_held_at_its_nominal_value(tmp_path: Path) -> None:
    (tmp_path / "drift.yaml").write_text(INPUT.replace("NOMINAL", ""))
    (tmp_path / "two.yaml").write_text(
        "system: two\ncomponents:\n  - {spec: drift.yaml, as: a}\n"
        "  - {spec: drift.yaml, as: b, rename: {x: z}}\n"
    )
    m = hybrid.load(tmp_path / "two.yaml")
    assert isinstance(m, hybrid.System) and m.free_inputs == ("u",)
    run = hybrid.simulate(m, t_end=10.0, **TOL)
    assert [j.t for j in run.jumps] == pytest.approx([3.0, 3.0], abs=1e-12)
    given = hybrid.simulate(m, t_end=10.0, inputs={"u": lambda t: 1.0}, **TOL)
    assert [j.t for j in given.jumps] == pytest.approx([6.0, 6.0], abs=1e-12)


def test_the_command_line_prints_the_choices(tmp_path: Path) -> None:
    spec = tmp_path / "ramp.yaml"
    spec.write_text(INPUT.replace("NOMINAL", "").replace("initial: 0", "initial: [0, 1]"))
    done = run_cli("simulate", spec, "--t-end", "10")
    assert done.returncode == 0, done.stderr
    assert f"{spec}: note: x starts at the midpoint 0.5 of its initial set [0, 1]" in done.stderr
    assert f"{spec}: note: input u is held at the midpoint 2 of its range [1, 3]" in done.stderr
    given = run_cli(
        "simulate", spec, "--t-end", "10", "--input", "u=3", "--events", tmp_path / "e.json"
    )
    assert given.returncode == 0 and "input u is held" not in given.stderr
    import json

    events = json.loads((tmp_path / "e.json").read_text())
    assert events["jumps"][0]["t"] == pytest.approx(5.5 / 3, rel=1e-6)
    assert events["settings"]["start"]["state"] == {"x": 0.5}


def test_closed_form_of_the_midpoint_is_exact() -> None:
    # the midpoint of [lo, hi] is lo + (hi - lo) / 2: exact for the interval's floats
    r = Range.of(0.1, 0.3)
    assert r.nominal == 0.1 + (0.3 - 0.1) / 2 and r.lo <= r.nominal <= r.hi
    assert math.isclose(r.nominal, 0.2)


def test_the_command_line_drives_a_free_input_of_a_system(tmp_path: Path) -> None:
    (tmp_path / "drift.yaml").write_text(INPUT.replace("NOMINAL", ""))
    (tmp_path / "two.yaml").write_text(
        "system: two\ncomponents:\n  - {spec: drift.yaml, as: a}\n"
        "  - {spec: drift.yaml, as: b, rename: {x: z}}\n"
    )
    done = run_cli("simulate", tmp_path / "two.yaml", "--t-end", "10", "--input", "u=1.5")
    assert done.returncode == 0, done.stderr
    assert "t_end at t=10 j=2" in done.stdout and "note" not in done.stderr
    wrong = run_cli("simulate", tmp_path / "two.yaml", "--t-end", "10", "--input", "x=1")
    assert wrong.returncode == 2 and "'x' is not a free input of two (inputs: u)" in wrong.stderr


def test_a_start_outside_the_sets_is_said_to_be_outside_the_claims() -> None:
    m = hybrid.load_text(INPUT.replace("NOMINAL", "").replace("initial: 0", "initial: [0, 1]"))
    run = hybrid.simulate(m, t_end=1.0, initial={"x": 5.0}, inputs={"u": lambda t: 4.0})
    assert run.settings["start"]["notes"] == [
        "x starts at 5, outside its initial set [0, 1] (the claims of hybrid check do not "
        "cover this run)",
        "input u starts at 4, outside its range [1, 3] (the claims of hybrid check do not "
        "cover this run)",
    ]
    inside = hybrid.simulate(m, t_end=1.0, initial={"x": 0.25}, inputs={"u": lambda t: 2.5})
    assert inside.settings["start"]["notes"] == []
