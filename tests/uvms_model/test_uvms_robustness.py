"""Which of our parameter choices keep the missions' outcomes, classified strictly.

Each own parameter (``OWN_PARAMETERS``: the numeric choices docs/uvms.md marks as
ours) at 0.9 and 1.1 times its value, one at a time, and each initial joint angle
moved by -0.1, -0.05, +0.05 and +0.1 rad; each run classified by the strict
classifier (mission 2: epsilon then beta before the end, no re-entry). Mission 1
keeps its outcome everywhere; mission 2's window is pinned as measured
(``MISSION_2_LOST``). Tolerances: rtol 1e-6 and a 100 ms recording grid, on
which min |gamma| is read (near the bottom of a dip |gamma| is a parabola of
curvature ~1 /s^2, so a 100 ms grid reads it to ~1e-3; the nominal missions give the
same outcome and min |gamma| to 2e-3 as at rtol 1e-8 on a 2 ms grid, checked below).
Two processes (the machine has two cores).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib.image
import pytest

from uvms_model.missions import OWN_PARAMETERS
from uvms_model.robustness import (
    Outcome,
    Variant,
    classify,
    one_at_a_time,
    outcome_of,
    robustness_map,
    write_map_figure,
)

RTOL, ATOL = 1e-6, 1e-9

MISSION_2_LOST: dict[str, str] = {}
"""Mission 2's variants that lose the paper's outcome, as measured (strict classifier)."""


@pytest.fixture(scope="module")
def variants() -> dict[str, list[Variant]]:
    return {
        m: one_at_a_time(m, rtol=RTOL, atol=ATOL, workers=2)
        for m in ("uvms_mission_1", "uvms_mission_2")
    }


def test_classify_mission_1_by_hand() -> None:
    m1 = "uvms_mission_1"
    assert classify(Outcome(m1, "t_end", 0.7, 0.2)) == "paper"
    assert classify(Outcome(m1, "t_end", 0.65, 0.2)) == "low gamma"  # strictly above gamma_tol
    assert classify(Outcome(m1, "t_end", 0.6, 0.2)) == "low gamma"
    assert classify(Outcome(m1, "t_end", 0.7, 0.2, epsilon=1, beta=1)) == "switched"
    assert classify(Outcome(m1, "t_end", 0.7, 0.2, epsilon=1)) == "switched"
    assert classify(Outcome(m1, "solver_failure", 0.7, 0.2)) == "ended solver_failure"


def test_classify_mission_2_strictly_by_hand() -> None:
    """The paper's mission 2: epsilon at gamma_tol, then kinematic state 3 "until gamma
    takes the unit value again" (beta), before the end; nothing else."""
    m2 = "uvms_mission_2"
    assert classify(Outcome(m2, "t_end", 0.57, 0.25, epsilon=1, beta=1)) == "paper"
    # one switch without beta: the run ends still in kinematic state 3
    assert classify(Outcome(m2, "t_end", 0.57, 0.25, epsilon=1)) == "no beta"
    assert classify(Outcome(m2, "t_end", 0.7, 0.2)) == "no switch"
    # a re-entry into kinematic state 3, from q2 or from q0 after at_rest
    again = Outcome(m2, "t_end", 0.57, 0.25, epsilon=1, beta=1, epsilon_again=1)
    assert classify(again) == "re-entered"
    assert classify(Outcome(m2, "t_end", 0.57, 0.25, epsilon=1, beta=2, epsilon_again=1)) == (
        "re-entered"
    )
    assert classify(Outcome(m2, "t_end", 0.57, 0.25, epsilon=2, beta=2)) == "re-entered"
    assert classify(Outcome(m2, "t_end", 0.5, 0.25, epsilon=1, beta=1)) == "low gamma"
    assert classify(Outcome(m2, "t_end", 0.49, 0.25, epsilon=1, beta=1)) == "low gamma"
    assert classify(Outcome(m2, "blocked", 0.6, 0.27, epsilon=1, beta=1)) == "ended blocked"
    assert again.switches == 3


def test_the_variants_are_what_they_claim(variants: dict[str, list[Variant]]) -> None:
    names = [v.name for v in variants["uvms_mission_1"]]
    assert len(names) == 2 * len(OWN_PARAMETERS) + 12
    assert names[0].endswith(" x0.9") and names[1].endswith(" x1.1")
    steps = ("-0.1", "-0.05", "+0.05", "+0.1")
    assert names[-12:] == [f"{q} {s} rad" for q in ("q1", "q2", "q3") for s in steps]


def test_mission_1_keeps_its_outcome_for_every_variant(
    variants: dict[str, list[Variant]],
) -> None:
    lost = [(v.name, v.verdict, v.outcome) for v in variants["uvms_mission_1"]]
    assert [item for item in lost if item[1] != "paper"] == []


def test_mission_2_window_as_measured(variants: dict[str, list[Variant]]) -> None:
    """The measured window of mission 2 under the strict classifier (docs/uvms.md):
    every variant not listed keeps the paper's outcome, and each listed one loses it
    the way it is listed. A change that narrows the window (or widens it) fails here."""
    verdicts = {v.name: v.verdict for v in variants["uvms_mission_2"]}
    lost = {name: verdict for name, verdict in verdicts.items() if verdict != "paper"}
    assert lost == MISSION_2_LOST
    # the margin that stays thin: min |gamma| against the requirement's 0.5 (measured
    # 0.589-0.618 over the variants at rtol 1e-7)
    assert min(v.outcome.min_abs_gamma for v in variants["uvms_mission_2"]) > 0.58


def test_relaxed_tolerances_give_the_nominal_outcome() -> None:
    for mission in ("uvms_mission_1", "uvms_mission_2"):
        fine = outcome_of(mission, rtol=1e-8, atol=1e-10, dt=0.005)
        relaxed = outcome_of(mission, rtol=RTOL, atol=ATOL)
        assert classify(relaxed) == classify(fine) == "paper"
        assert (relaxed.cause, relaxed.epsilon, relaxed.beta) == (
            fine.cause,
            fine.epsilon,
            fine.beta,
        )
        assert relaxed.min_abs_gamma == pytest.approx(fine.min_abs_gamma, abs=2e-3)


def test_map_grid_and_figure(tmp_path: Path) -> None:
    grid = robustness_map(
        "uvms_mission_2", "uvms.v_max", [0.28, 0.32], "polarization.theta_accel", [0.95],
        rtol=RTOL, atol=ATOL,
    )  # fmt: skip
    assert grid.nominal == (0.30, 0.95)
    assert len(grid.outcomes) == 1 and len(grid.outcomes[0]) == 2
    assert all(classify(o) == "paper" for o in grid.outcomes[0])
    for o in grid.outcomes[0]:
        # the requirement's robustness is the exact minimum of |gamma| less 0.5; the
        # summary reads it on the 0.1 s grid (a parabola of curvature ~1 /s^2 there)
        assert o.dexterity <= o.min_abs_gamma - 0.5 + 1e-12
        assert o.dexterity == pytest.approx(o.min_abs_gamma - 0.5, abs=2e-3)
    path = write_map_figure(grid, tmp_path / "map.png")
    height, width, _ = matplotlib.image.imread(path).shape
    assert width >= 600 and height >= 400
