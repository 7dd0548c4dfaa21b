"""``hybrid simulate --init NAME=VALUE --initial-location LOC``: where a run starts, from the shell.

The Python API took ``initial=`` and ``initial_location=``; the command had no way
to start elsewhere than the spec says (a user had to edit the spec, or write
Python). Checked against closed forms:

- the ball dropped from ``h = 3`` (g = 9.81) first hits the floor at
  ``sqrt(2 * 3 / 9.81) = 0.782062`` s;
- the thermostat started in ``on`` at ``T = 21`` heats as
  ``T' = 0.1 (30 - T)`` and switches off at 22 after ``10 ln(9 / 8) = 1.177830`` s.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from support import SPECS, assert_no_traceback, main_in_process

BALL = str(SPECS / "bouncing_ball.yaml")
THERMOSTAT = str(SPECS / "thermostat.yaml")
MISSION = str(SPECS / "uvms_mission_2.yaml")


def _events(path: Path) -> dict:  # type: ignore[type-arg]
    return json.loads(path.read_text())


@pytest.mark.parametrize("backend", ["scipy", "compiled"])
def test_init_starts_the_ball_from_another_height(
    backend: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    if backend == "compiled":
        pytest.importorskip("numba")
    events = tmp_path / "e.json"
    code = main_in_process("simulate", BALL, "--t-end", "1", "--init", "h=3",
                           "--backend", backend, "--events", events)  # fmt: skip
    assert code == 0, capsys.readouterr().err
    doc = _events(events)
    assert doc["settings"]["start"]["state"] == {"h": 3.0, "v": 0.0}
    assert doc["jumps"][0]["t"] == pytest.approx(math.sqrt(2 * 3 / 9.81), abs=1e-6)
    assert "h starts at 3" in capsys.readouterr().err  # the note: not the spec's start


def test_initial_location_and_init_start_the_thermostat_heating(tmp_path: Path) -> None:
    events = tmp_path / "e.json"
    code = main_in_process("simulate", THERMOSTAT, "--t-end", "2", "--initial-location", "on",
                           "--init", "T=21", "--events", events)  # fmt: skip
    assert code == 0
    doc = _events(events)
    assert doc["settings"]["start"]["location"] == "on"
    first = doc["jumps"][0]
    assert first["edge"] == "turn_off"
    assert first["t"] == pytest.approx(10 * math.log(9 / 8), abs=1e-6)


@pytest.mark.parametrize(
    ("spec", "args", "message"),
    [
        (BALL, ["--init", "hh=3"], "unknown state variable 'hh'; did you mean 'h'?"),
        (BALL, ["--init", "h"], "argument --init: expected name=value, got 'h'"),
        (BALL, ["--init", "h=inf"], "value of 'h' must be a finite number"),
        (BALL, ["--initial-location", "flying"],
         "unknown initial location 'flying'; did you mean 'falling'?"),
        # none close: the names to choose from (they used to be left out)
        (BALL, ["--initial-location", "up"], "unknown initial location 'up' (locations: falling)"),
        (BALL, ["--param", "k=1"], "unknown parameter 'k' for automaton 'bouncing_ball' (parameters: g, e)"),
        (MISSION, ["--init", "phii=1"],
         "initial value for unknown state variable 'phii'; did you mean 'phi'?"),
        # a component's name before a state or a parameter of another component
        (MISSION, ["--init", "uvms.phi=1"], "initial value for unknown state variable "
         "'uvms.phi'; a system's state variables are named without their component: 'phi'"),
        (MISSION, ["--param", "uvms.gamma_max=1"],
         "component 'uvms' has no parameter 'gamma_max'; did you mean 'polarization.gamma_max'?"),
        (MISSION, ["--initial-location", "q0"],
         "--initial-location applies to an automaton; in a system each component"),
    ],
)  # fmt: skip
def test_a_bad_start_exits_2_with_one_line(
    spec: str, args: list[str], message: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main_in_process("simulate", spec, "--t-end", "0.1", *args) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], captured.err
    assert_no_traceback(captured.err)
