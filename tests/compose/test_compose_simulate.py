"""Composed simulation: synchronised jumps at closed-form instants.

A controller with a clock c (c' = 1) commands the heater every P seconds:
`on` at c = P while off, `off` at c = P while on. The heater's temperature
follows T' = a (T_heat - T) when on and T' = -a (T - T_out) when off, and its
edges carry the controller's labels, so they can only fire together with it.
Closed form: switches at t = k P exactly, T(t) piecewise exponential.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

import hybrid

CONTROLLER = """
automaton: controller
parameters: {P: 3.0}
state: {c: {initial: 0.0, bounds: [0, 10]}}
signals: {command: 0}
labels: [on, off]
locations:
  idle:
    flow: {c: 1}
    invariant: c <= P
  heating:
    flow: {c: 1}
    signals: {command: 1}
    invariant: c <= P
edges:
  - {name: start, from: idle, to: heating, label: on, guard: c >= P, reset: {c: 0}}
  - {name: stop, from: heating, to: idle, label: off, guard: c >= P, reset: {c: 0}}
"""

HEATER = """
automaton: heater
parameters: {a: 0.2, T_out: 10.0, T_heat: 40.0}
state: {T: {initial: 15.0, bounds: [0, 50]}}
inputs: [command]
labels: [on, off]
locations:
  cold: {flow: {T: -a*(T - T_out)}}
  hot: {flow: {T: a*(T_heat - T)}}
edges:
  - {from: cold, to: hot, label: on}
  - {from: hot, to: cold, label: off}
"""

SYSTEM = """
system: heated_room
components:
  - spec: controller.yaml
  - spec: heater.yaml
    as: room
"""


@pytest.fixture()
def system(tmp_path: Path) -> hybrid.System:
    (tmp_path / "controller.yaml").write_text(CONTROLLER)
    (tmp_path / "heater.yaml").write_text(HEATER)
    (tmp_path / "room.yaml").write_text(SYSTEM)
    model = hybrid.load(tmp_path / "room.yaml")
    assert isinstance(model, hybrid.System)
    return model


def closed_form_temperature(t: float, period: float = 3.0) -> float:
    a, t_out, t_heat, temp = 0.2, 10.0, 40.0, 15.0
    k = 0
    while (k + 1) * period <= t:
        target = t_out if k % 2 == 0 else t_heat
        temp = target + (temp - target) * math.exp(-a * period)
        k += 1
    target = t_out if k % 2 == 0 else t_heat
    return target + (temp - target) * math.exp(-a * (t - k * period))


def test_synchronised_jumps_fire_together_at_closed_form_instants(system: hybrid.System) -> None:
    run = hybrid.simulate(system, t_end=20.0, rtol=1e-11, atol=1e-12)
    assert run.termination.cause == "t_end"
    times = [jump.t for jump in run.jumps]
    assert times == pytest.approx([3.0 * k for k in range(1, 7)], abs=1e-9)
    # every jump is one synchronised transition: both components change location together
    assert [jump.label for jump in run.jumps] == ["on", "off"] * 3
    assert run.jumps[0].source == "controller.idle|room.cold"
    assert run.jumps[0].target == "controller.heating|room.hot"
    assert run.jumps[0].edge == "controller.start+room.cold->hot#0"
    assert all("+" in jump.edge for jump in run.jumps)


def test_composed_state_follows_closed_form(system: hybrid.System) -> None:
    run = hybrid.simulate(system, t_end=20.0, rtol=1e-11, atol=1e-12, dt=0.25)
    for t, temp in zip(run.t, run["T"], strict=True):
        assert temp == pytest.approx(closed_form_temperature(float(t)), abs=1e-8)
    # the input `command` of the heater is bound to the controller's signal
    heating = run.location == "controller.heating|room.hot"
    assert set(run["command"][heating]) == {1.0}
    assert set(run["command"][~heating]) == {0.0}


def test_unsynchronised_label_cannot_fire_alone(tmp_path: Path) -> None:
    # relabel the controller's `start` edge `off`: the heater offers `off` only from `hot`
    controller = CONTROLLER.replace("label: on,", "label: off,", 1)
    a = hybrid.load_text(controller)
    b = hybrid.load_text(HEATER, file="heater.yaml")
    assert isinstance(a, hybrid.Automaton) and isinstance(b, hybrid.Automaton)
    system = hybrid.compose(a, b, names=["controller", "room"])
    run = hybrid.simulate(system, t_end=10.0)
    # now controller.start carries `off`, which the heater only offers from `hot`:
    # the controller's start cannot fire, its invariant c <= P is left: blocked at P
    assert run.termination.cause == "blocked"
    assert run.termination.t == pytest.approx(3.0, abs=1e-9)


def test_name_clash_is_an_error_naming_both_places(tmp_path: Path) -> None:
    a = hybrid.load_text(CONTROLLER, file="a.yaml")
    b = hybrid.load_text(
        CONTROLLER.replace("automaton: controller", "automaton: other"), file="b.yaml"
    )
    assert isinstance(a, hybrid.Automaton) and isinstance(b, hybrid.Automaton)
    with pytest.raises(hybrid.SpecError) as info:
        hybrid.compose(a, b)
    text = str(info.value)
    assert "'c'" in text and "a.yaml" in text and "b.yaml" in text


def test_unbound_input_is_an_error(tmp_path: Path) -> None:
    b = hybrid.load_text(HEATER, file="heater.yaml")
    c = hybrid.load_text(CONTROLLER.replace("command", "order"), file="c.yaml")
    assert isinstance(b, hybrid.Automaton) and isinstance(c, hybrid.Automaton)
    with pytest.raises(hybrid.SpecError, match="input 'command'"):
        hybrid.compose(c, b)


def test_an_input_a_letter_off_a_signal_is_told_the_name() -> None:
    """An input typo in a system ('commnd' for the controller's 'command') got no
    suggestion, where the same typo in rename: did."""
    b = hybrid.load_text(HEATER.replace("command", "commnd"), file="heater.yaml")
    c = hybrid.load_text(CONTROLLER, file="c.yaml")
    assert isinstance(b, hybrid.Automaton) and isinstance(c, hybrid.Automaton)
    with pytest.raises(hybrid.SpecError, match=r"input 'commnd' of component 'heater' is not "
                       r"a signal or state variable of any other component \(did you mean "
                       r"'command'\?\); bind it"):  # fmt: skip
        hybrid.compose(c, b)


def test_qualified_parameter_override(system: hybrid.System) -> None:
    faster = system.with_parameters({"controller.P": 2.0, "a": 0.3})
    run = hybrid.simulate(faster, t_end=7.0)
    assert [j.t for j in run.jumps] == pytest.approx([2.0, 4.0, 6.0], abs=1e-7)
    with pytest.raises(hybrid.SpecError, match="no parameter 'Q'"):
        system.with_parameters({"controller.Q": 1.0})


def test_misspelt_system_parameter_suggests_the_right_one(system: hybrid.System) -> None:
    with pytest.raises(hybrid.SpecError, match=r"'Pp'; did you mean 'P'\?"):
        system.with_parameters({"Pp": 2.0})


SOURCE = """
automaton: source
state: {c: {initial: 0.0}}
signals: {u: 1}
locations:
  low: {flow: {c: 1}}
  high: {flow: {c: 1}, signals: {u: 2}}
edges:
  - {name: raise, from: low, to: high, guard: c >= 1}
"""

READER = """
automaton: reader
state: {x: {initial: 0.0}, y: {initial: 0.0}, k: {initial: 0.0}}
inputs: [u]
locations:
  a: {flow: {x: u, k: 1}}
  b: {flow: {x: u, k: 1}}
edges:
  - {name: take, from: a, to: b, guard: k >= 2.5, reset: {y: u}}
"""


def test_an_input_follows_its_provider_s_location(tmp_path: Path) -> None:
    """The reader's flow and reset read input u, which the source defines per location.

    u = 1 until t = 1, then 2; so x(3) = 1 + 2 * 2 = 5 and the reset at t = 2.5 takes
    y = 2. (Functions compiled for one mode must not be reused in a mode where an
    input's provider defines it otherwise.)
    """
    (tmp_path / "source.yaml").write_text(SOURCE)
    (tmp_path / "reader.yaml").write_text(READER)
    (tmp_path / "sys.yaml").write_text(
        "system: s\ncomponents:\n  - spec: source.yaml\n  - spec: reader.yaml\n"
    )
    run = hybrid.simulate(hybrid.load(tmp_path / "sys.yaml"), t_end=3.0, rtol=1e-10, atol=1e-12)
    assert [j.edge for j in run.jumps] == ["source.raise", "reader.take"]
    assert run.jumps[1].after["y"] == pytest.approx(2.0)
    assert run["x"][-1] == pytest.approx(5.0, abs=1e-9)
