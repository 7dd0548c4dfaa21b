"""Progress of ``hybrid simulate`` on stderr: on a terminal only, silenced by ``--quiet``."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from support import SPECS, run_on_a_terminal

THERMOSTAT = SPECS / "thermostat.yaml"
# a run of about a second at least (short steps), so the 0.2 s reporter shows it, and a
# CSV large enough for its writing to be reported too: 1.2 million rows take about 1.4 s
# of CPU here (150,000 rows took 0.17 s, under the reporter's interval on a fast host)
ARGS = ["simulate", str(THERMOSTAT), "--t-end", "600", "--dt", "0.0005", "--max-step", "0.05"]


def on_a_terminal(*extra: str, out: Path) -> tuple[int, str, str]:
    """The simulation with stderr on a pseudo-terminal; exit code, stdout and what stderr showed."""
    return run_on_a_terminal(*ARGS, "--out", str(out), *extra)


@pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals are POSIX")
def test_progress_is_shown_on_a_terminal_and_cleared(tmp_path: Path) -> None:
    code, stdout, shown = on_a_terminal(out=tmp_path / "traj.csv")
    assert code == 0
    assert "simulate: " in shown and " s (" in shown and "jumps" in shown and "points" in shown
    assert "per second" in shown and "left" in shown
    assert "writing traj.csv: " in shown and " rows (" in shown
    assert shown.endswith("\r") and shown.split("\r")[-2].strip() == ""  # the line is erased
    assert "t_end at t=600" in stdout


@pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals are POSIX")
def test_quiet_silences_it(tmp_path: Path) -> None:
    code, _, shown = on_a_terminal("--quiet", out=tmp_path / "traj.csv")
    assert code == 0
    assert shown == ""


# Not a terminal: nothing on stderr (tests/cli/test_cli_simulate_flags.py, a normal run).
