"""`hybrid check` proves the case study's graph properties on the composed systems.

What must hold: every location of both automata reachable, no dead edge, the
polarization FSM and the automaton deterministic, no zero-time cycle; and the
properties are declared in the specs, so CI keeps proving them. Deadlock freedom
is not claimed: every location has the vehicle's speed limit as its invariant, and
a run that would need a faster vehicle ends `blocked` (the checker sees it).
"""

from __future__ import annotations

from pathlib import Path

import pytest

import hybrid
from uvms_model.missions import MISSIONS, specs_dir

ALL_LOCATIONS = {f"uvms.{q}" for q in ("q0", "q1", "q2")} | {
    f"polarization.{s}" for s in ("S1", "S2", "S3")
}


@pytest.mark.parametrize("mission", MISSIONS)
def test_composed_mission_is_proved(mission: str) -> None:
    model = hybrid.load(specs_dir() / f"{mission}.yaml")
    assert isinstance(model, hybrid.System)
    # the properties are declared in the spec, so CI proves them on every change
    assert set(model.properties.reachable) == ALL_LOCATIONS
    assert model.properties.deterministic is True
    report = hybrid.check(model)
    assert report.ok
    assert report.findings == ()


def test_the_speed_limit_is_why_deadlock_freedom_is_not_claimed(tmp_path: Path) -> None:
    text = (specs_dir() / "uvms_singularity.yaml").read_text()
    claimed = text.replace(
        "  deterministic: true\n", "  deterministic: true\n  deadlock_free: true\n"
    )
    assert claimed != text
    (tmp_path / "uvms_singularity.yaml").write_text(claimed)
    report = hybrid.check(hybrid.load(tmp_path / "uvms_singularity.yaml"))
    # not proved (a warning: --strict fails on it), with the candidate path
    assert report.failed(strict=True)
    messages = [f.message for f in report.findings if f.rule == "property-unproved"]
    assert any("deadlock_free" in m and "invariant" in m for m in messages)
    # without the invariants (no speed limit) the claim would hold
    unlimited = claimed.replace("    invariant: vehicle_speed <= v_max\n", "")
    (tmp_path / "uvms_singularity.yaml").write_text(unlimited)
    unlimited_report = hybrid.check(hybrid.load(tmp_path / "uvms_singularity.yaml"))
    assert unlimited_report.ok and not unlimited_report.failed(strict=True)


def test_polarization_fsm_alone_is_deterministic_and_live() -> None:
    report = hybrid.check(hybrid.load(specs_dir() / "polarization.yaml"))
    assert report.ok and report.findings == ()


def test_the_checks_would_catch_a_broken_strategy(tmp_path: Path) -> None:
    # without the priority on epsilon_again, q2 has two same-priority edges whose
    # guards can hold together: the spec claims determinism, so this must be reported
    text = (specs_dir() / "uvms_singularity.yaml").read_text()
    assert "    priority: 1\n" in text
    (tmp_path / "uvms_singularity.yaml").write_text(text.replace("    priority: 1\n", ""))
    for name in ("polarization.yaml", "uvms_mission_2.yaml"):
        (tmp_path / name).write_text((specs_dir() / name).read_text())
    report = hybrid.check(hybrid.load(tmp_path / "uvms_mission_2.yaml"))
    rules = {f.rule for f in report.findings}
    assert report.failed(strict=True)  # warnings: CI with --strict fails on them
    assert "nondeterminism" in rules and "property-unproved" in rules
