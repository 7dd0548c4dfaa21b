"""hybrid.progress: throttled statuses with rate and time left, drawn only on a terminal."""

from __future__ import annotations

import io

import pytest
from support import FakeTerminal

from hybrid.progress import Status, TerminalLine, Tracker, terminal_reporter


class FakeClock:
    def __init__(self) -> None:
        self.now = 100.0

    def __call__(self) -> float:
        return self.now


def test_the_tracker_reports_at_most_once_per_interval() -> None:
    clock, seen = FakeClock(), []
    tracker = Tracker(
        "simulate", total=10.0, unit="s", report=seen.append, interval=0.5, clock=clock
    )
    for k in range(64):  # 64 updates over 2 s of wall time (steps of 1/32 s: exact)
        clock.now += 0.03125
        tracker.update(k / 10, jumps=k)
    assert [s.elapsed for s in seen] == [0.5, 1.0, 1.5, 2.0]
    final = tracker.finish(10.0, jumps=100)
    assert final.final and seen[-1] is final and final.done == 10.0


def test_rate_and_time_left_of_a_sweep() -> None:
    # 30 of 120 runs done in 15 s: 2 runs a second, 45 s left; 3 violations so far
    status = Status("sweep", 30, 120, "runs", elapsed=15.0, counters=(("violations", 3),))
    assert (status.fraction, status.rate, status.eta) == (0.25, 2.0, 45.0)
    assert status.text() == "sweep: 30/120 runs (25%), 3 violations, 2 runs per second, 45 s left"


def test_a_simulation_counts_simulated_time_from_its_start() -> None:
    status = Status("simulate", 15.0, 20.0, "s", elapsed=2.0, start=10.0)
    assert (status.fraction, status.rate, status.eta) == (0.5, 2.5, 2.0)


def test_no_total_no_fraction_and_no_eta() -> None:
    status = Status("check", 5000, None, "modes", elapsed=2.0)
    assert status.fraction is None and status.eta is None and status.rate == 2500
    assert status.text() == "check: 5,000 modes, 2,500 modes per second"


def test_durations_read_like_a_person_writes_them() -> None:
    long = Status("sweep", 1, 10000, "runs", elapsed=1.0)
    assert long.text().endswith("2 h 46 min left")
    medium = Status("sweep", 1, 200, "runs", elapsed=1.0)
    assert medium.text().endswith("3 min 19 s left")


def test_the_terminal_line_redraws_in_place_and_clears_at_the_end() -> None:
    stream = FakeTerminal()
    line = TerminalLine(stream)
    line(Status("simulate", 1.0, 10.0, "s", elapsed=1.0))
    line(Status("simulate", 2.0, 10.0, "s", elapsed=2.0))
    assert stream.getvalue().count("\r") == 2 and "\n" not in stream.getvalue()
    line(Status("simulate", 10.0, 10.0, "s", elapsed=5.0, final=True))
    assert stream.getvalue().endswith("\r")  # the line is erased: output starts clean
    line.message("hybrid: still writing")
    assert stream.getvalue().endswith("hybrid: still writing\n")


def test_nothing_is_drawn_on_a_pipe_or_with_quiet() -> None:
    pipe = io.StringIO()
    assert terminal_reporter(stream=pipe) is None
    assert terminal_reporter(quiet=True, stream=FakeTerminal()) is None
    assert isinstance(terminal_reporter(stream=FakeTerminal()), TerminalLine)
    line = TerminalLine(pipe)
    line(Status("simulate", 1.0, 10.0))
    assert pipe.getvalue() == ""


def test_simulate_reports_progress_through_the_callback() -> None:
    import hybrid

    seen: list[Status] = []
    ball = hybrid.load("specs/bouncing_ball.yaml")
    run = hybrid.simulate(ball, t_end=3.0, progress=seen.append, zeno=False)
    final = seen[-1]
    assert final.final and final.task == "simulate" and final.unit == "s"
    assert final.done == run.termination.t == 3.0 and final.total == 3.0
    assert dict(final.counters) == {"jumps": len(run.jumps), "points": len(run)}
    assert all(not s.final for s in seen[:-1])


@pytest.mark.parametrize("value", [0.0, 0.25, 1.0])
def test_fraction_is_between_zero_and_one(value: float) -> None:
    assert Status("x", value, 1.0).fraction == value
