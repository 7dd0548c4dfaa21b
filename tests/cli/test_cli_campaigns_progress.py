"""Progress of ``hybrid sweep`` and ``hybrid falsify`` on stderr: on a terminal only.

stderr is replaced by a fake terminal (a text stream that says it is a tty) and the
commands run in this process; what they drew is read back. Each campaign lasts well
over the reporter's 0.2 s (runs of 20 to 100 ms, 20 of them), so the line is drawn
while it runs: runs done of runs planned, violations (and failed runs) so far, the
rate and the time left; it is erased at the end. ``--quiet``, or a stderr that is
not a terminal, shows nothing.
"""

from __future__ import annotations

import io
import re
import sys
from pathlib import Path

import pytest
from support import FakeTerminal, main_in_process

WAVE = """automaton: wave
parameters: {w: 1.0}
state: {x: {initial: 0.0}}
locations: {on: {flow: {x: cos(w*t)}}}
requirements:
  - {name: small, always: "x <= 0.2"}
  - {name: bounded, always: "x <= 2"}
"""
# x = sin(w t) / w: above 0.2 for w < 5 (4 of the 20 runs of w = 1..20 violate `small`)
RUN = ["--t-end", "5", "--max-step", "0.01", "--workers", "0", "--backend", "scipy"]  # slow enough to draw


@pytest.fixture
def spec(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.chdir(tmp_path)
    Path("wave.yaml").write_text(WAVE)
    return Path("wave.yaml")


def _on(stream: io.StringIO, monkeypatch: pytest.MonkeyPatch, *args: str | Path) -> int:
    monkeypatch.setattr(sys, "stderr", stream)
    return main_in_process(*args)


def _drawn(shown: str, task: str) -> list[str]:
    """The status lines drawn for ``task`` (each starts after a carriage return)."""
    return [part.strip() for part in shown.split("\r") if part.startswith(f"{task}: ")]


def test_sweep_shows_runs_violations_rate_and_time_left(
    spec: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    terminal = FakeTerminal()
    code = _on(terminal, monkeypatch, "sweep", spec, "--grid", "w=1:20:20", *RUN, "--out", "r.csv")
    assert code == 1  # `small` is violated
    shown = terminal.getvalue()
    lines = _drawn(shown, "sweep")
    assert lines, shown
    pattern = re.compile(
        r"sweep: (\d+)/20 runs \(\d+%\), (\d+) violations, 0 failed, "
        r"[\d.,]+ runs per second, [\d.]+ s left"
    )
    matches = [pattern.fullmatch(line) for line in lines]
    assert all(matches), lines
    done = [int(m.group(1)) for m in matches if m]
    violations = [int(m.group(2)) for m in matches if m]
    assert done == sorted(done) and 0 < done[-1] <= 20
    # runs 0..3 (w = 1..4) violate `small` and come first: the count is right as it goes
    assert violations == [min(4, d) for d in done]
    assert shown.endswith("\r") and shown.split("\r")[-2].strip() == ""  # the line is erased
    assert "20 runs (20 t_end); results in r.csv" in capsys.readouterr().out


def test_falsify_shows_runs_and_violations_found(
    spec: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    terminal = FakeTerminal()
    args = ["--requirement", "bounded", "--vary", "w=1:20", "--budget", "20", *RUN]
    assert _on(terminal, monkeypatch, "falsify", spec, *args) == 0  # |x| <= 1 < 2: holds
    lines = _drawn(terminal.getvalue(), "falsify")
    assert lines, terminal.getvalue()
    pattern = re.compile(r"falsify: (\d+)/20 runs \(\d+%\), 0 violations, .* runs per second.*")
    matches = [pattern.fullmatch(line) for line in lines]
    assert all(matches), lines
    assert 0 < int(matches[0].group(1)) <= 20  # type: ignore[union-attr]
    terminal = FakeTerminal()
    args[1] = "small"  # w < 5 violates it: found in the first round (10 runs)
    assert _on(terminal, monkeypatch, "falsify", spec, *args) == 1
    counts = [
        (int(m.group(1)), int(m.group(2)))
        for m in map(
            re.compile(r"falsify: (\d+)/20 runs \(\d+%\), (\d+) violations.*").fullmatch,
            _drawn(terminal.getvalue(), "falsify"),
        )
        if m
    ]
    assert counts and all(d <= 10 and v <= d for d, v in counts)


@pytest.mark.parametrize("stream", ["quiet", "not a terminal"])
def test_quiet_or_no_terminal_shows_nothing(
    spec: Path, monkeypatch: pytest.MonkeyPatch, stream: str
) -> None:
    terminal = FakeTerminal() if stream == "quiet" else io.StringIO()
    quiet = ["--quiet"] if stream == "quiet" else []
    code = _on(terminal, monkeypatch, "sweep", spec, "--grid", "w=5:40:10", *RUN, *quiet,
               "--out", "r.csv")  # fmt: skip
    assert code == 0
    assert "sweep:" not in terminal.getvalue() and "\r" not in terminal.getvalue()
