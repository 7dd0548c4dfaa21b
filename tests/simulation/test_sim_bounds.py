"""Declared bounds are watched: a run that leaves them says so once per variable, with t and j.

The model climbs at known rates from known values on a 0.1 s grid, so where it
leaves its bounds is known by hand: h = 1.5 + 0.5 t passes 3 at t = 3 and the
first grid point beyond is t = 3.1 (h = 3.05); v = -0.25 t passes -1 at t = 4,
first beyond at t = 4.1 (v = -1.025); the only jump is at t = 2 (c = t reaches 2),
so both are at j = 1. A reset that lands outside is caught at the jump itself.
"""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import pytest
from support import LEAKY_SPEC, REPO, assert_no_traceback, run_cli

import hybrid

EXPECTED = [
    ("h", 3.1, 1, 3.05, "h left its declared bounds [0, 3] at t=3.1 j=1 (h = 3.05)"),
    ("v", 4.1, 1, -1.025, "v left its declared bounds [-1, 1] at t=4.1 j=1 (v = -1.025)"),
]


def _simulate(
    text: str, t_end: float, backend: str
) -> tuple[hybrid.Run, list[warnings.WarningMessage]]:
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        run = hybrid.simulate(
            hybrid.load_text(text), t_end=t_end, dt=0.1, backend=backend, handle_sigint=False
        )
    return run, [w for w in caught if issubclass(w.category, hybrid.BoundsWarning)]


def test_a_run_that_leaves_its_bounds_warns_once_per_variable(backend: str) -> None:
    run, caught = _simulate(LEAKY_SPEC, 10.0, backend)
    assert run.termination.cause == "t_end"
    assert [jump.t for jump in run.jumps] == pytest.approx([2.0], abs=1e-12)  # c = t reaches 2
    assert [str(w.message) for w in caught] == [message for *_, message in EXPECTED]
    assert [(e.variable, e.j) for e in run.out_of_bounds] == [(n, j) for n, _, j, _, _ in EXPECTED]
    assert [e.t for e in run.out_of_bounds] == pytest.approx([t for _, t, *_ in EXPECTED])
    assert [e.value for e in run.out_of_bounds] == pytest.approx([x for *_, x, _ in EXPECTED])
    assert caught[0].filename == __file__  # points at the caller's line


def test_a_run_within_its_bounds_says_nothing(backend: str) -> None:
    run, caught = _simulate(LEAKY_SPEC, 2.9, backend)  # h reaches 2.95, v -0.725
    assert caught == [] and run.out_of_bounds == ()
    tank, caught = _simulate((REPO / "docs" / "examples" / "tank.yaml").read_text(), 12.0, backend)
    assert caught == [] and tank.out_of_bounds == () and len(tank.jumps) == 3


def test_a_reset_that_lands_outside_is_caught_at_the_jump(backend: str) -> None:
    text = LEAKY_SPEC.replace("guard: c >= 2}", "guard: c >= 2, reset: {h: 4}}")
    run, caught = _simulate(text, 2.5, backend)
    (excursion,) = run.out_of_bounds
    assert (excursion.variable, excursion.t, excursion.j, excursion.value) == ("h", 2.0, 1, 4.0)
    assert len(caught) == 1


def test_the_command_warns_and_the_events_file_records_it(tmp_path: Path) -> None:
    spec = tmp_path / "leaky.yaml"
    spec.write_text(LEAKY_SPEC)
    events = tmp_path / "leaky.json"
    result = run_cli("simulate", spec, "--t-end", "10", "--dt", "0.1", "--events", events)
    assert result.returncode == 0  # leaving the bounds is a warning, not a failed run
    assert_no_traceback(result.stderr)
    warned = [line for line in result.stderr.splitlines() if "warning" in line]
    assert warned == [f"{spec}: warning: {message}" for *_, message in EXPECTED]
    recorded = json.loads(events.read_text())["out_of_bounds"]
    assert [(r["variable"], r["j"], r["bounds"]) for r in recorded] == [
        ("h", 1, [0, 3]),
        ("v", 1, [-1, 1]),
    ]
    assert [r["t"] for r in recorded] == pytest.approx([3.1, 4.1])
    assert [r["value"] for r in recorded] == pytest.approx([3.05, -1.025])


def test_the_command_within_bounds_says_nothing(tmp_path: Path) -> None:
    events = tmp_path / "tank.json"
    result = run_cli(
        "simulate", REPO / "docs" / "examples" / "tank.yaml", "--t-end", "12", "--events", events
    )
    assert (result.returncode, result.stderr) == (0, "")
    assert json.loads(events.read_text())["out_of_bounds"] == []
