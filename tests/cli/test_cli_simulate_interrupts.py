"""Ctrl-C at any instant of ``hybrid simulate``: a clean end, and nothing lost by accident.

A real SIGINT from another process at random moments of a long run with many
events (so some land in root finding) must always give exit 1, cause
``interrupted``, complete and parseable outputs whose last point satisfies its
location's invariant and lies on the closed-form trajectory, and no traceback.
During writing, one Ctrl-C after an interrupted run (or two after a normal one)
abandons the outputs, and the message says so; a single Ctrl-C during the
writing of a normal run only warns.
"""

from __future__ import annotations

import itertools
import json
import math
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import pytest
from support import REPO, SPECS, assert_no_traceback, main_in_process, read_csv, read_json

import hybrid.export.trajectory as trajectory

THERMOSTAT = SPECS / "thermostat.yaml"
A, T_OUT, T_HEAT, LOW, HIGH = 0.1, 10.0, 30.0, 18.0, 22.0
MOMENTS = int(os.environ.get("HYBRID_INTERRUPT_MOMENTS", "6"))
"""SIGINTs sent in the suite (``make fuzz`` sends 20)."""

# One process runs the command once per line it reads, so imports are paid once;
# each command's stderr is captured and reported with its exit code.
CHILD = """
import contextlib, io, json, sys
import hybrid.cli.simulate, hybrid.simulation.engine, hybrid.export.trajectory, hybrid.reader.loader
from hybrid.cli.main import main
for line in sys.stdin:
    args = json.loads(line)
    buffer = io.StringIO()
    print("ready", flush=True)
    with contextlib.redirect_stderr(buffer):
        code = main(args)
    print(json.dumps({"code": code, "stderr": buffer.getvalue()}), flush=True)
"""


def closed_form(t: float, location: str, t0: float, temp0: float) -> float:
    """The temperature at ``t`` in ``location`` from ``temp0`` at ``t0``."""
    target = T_OUT if location == "off" else T_HEAT
    return target + (temp0 - target) * math.exp(-A * (t - t0))


def check_outputs(out: Path, events: Path) -> dict[str, Any]:
    doc = read_json(events)
    term = doc["termination"]
    header, rows = read_csv(out)
    assert header == ["t", "j", "location", "T", "heating_power"]
    assert rows, "the trajectory is not empty"
    t = [float(r["t"]) for r in rows]
    assert t[0] == 0.0 and all(b >= a for a, b in itertools.pairwise(t))
    assert t[-1] == term["t"] and int(rows[-1]["j"]) == term["j"] == len(doc["jumps"])
    last = rows[-1]
    temp, location = float(last["T"]), last["location"]
    # the last point satisfies the invariant of its location (within the band)
    if location == "off":
        assert temp >= LOW - 1e-9, temp
    else:
        assert temp <= HIGH + 1e-9, temp
    # ... and lies on the trajectory: the closed form from the last jump (or the start)
    if doc["jumps"]:
        jump = doc["jumps"][-1]
        t0, temp0 = jump["t"], jump["after"]["T"]
    else:
        t0, temp0 = 0.0, 20.0
    assert temp == pytest.approx(closed_form(term["t"], location, t0, temp0), abs=1e-5)
    return doc


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process is POSIX")
def test_sigint_at_random_moments_of_a_long_run(tmp_path: Path) -> None:
    rng = random.Random(20240610)
    proc = subprocess.Popen(
        [sys.executable, "-c", CHILD],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=REPO,
    )
    assert proc.stdin is not None and proc.stdout is not None
    ends: list[float] = []
    try:
        for k in range(MOMENTS):
            out, events = tmp_path / f"run{k}.csv", tmp_path / f"run{k}.json"
            args = ["simulate", str(THERMOSTAT), "--t-end", "1e6", "--out", str(out)]
            args += ["--events", str(events)]
            proc.stdin.write(json.dumps(args) + "\n")
            proc.stdin.flush()
            assert proc.stdout.readline().strip() == "ready"
            time.sleep(rng.uniform(0.03, 0.6))
            proc.send_signal(signal.SIGINT)
            result = json.loads(proc.stdout.readline())
            assert result["code"] == 1, result["stderr"]
            assert_no_traceback(result["stderr"])
            assert ": interrupted: interrupted by the user" in result["stderr"]
            assert "writing the outputs (press Ctrl-C again to abandon them)" in result["stderr"]
            doc = check_outputs(out, events)
            assert doc["termination"]["cause"] == "interrupted"
            ends.append(doc["termination"]["t"])
            assert sorted(p.name for p in tmp_path.iterdir() if p.suffix == ".tmp") == []
    finally:
        proc.stdin.close()
        proc.wait(timeout=60)
        stderr = proc.stderr.read() if proc.stderr else ""
    assert proc.returncode == 0, stderr
    assert len(ends) == MOMENTS and min(ends) < 1e6


def _interrupting_writer(presses: int) -> Any:
    """A ``write_csv`` that presses Ctrl-C ``presses`` times halfway through its rows."""
    real = trajectory.write_csv

    def write_csv(run: Any, path: Any, progress: Any = None) -> None:
        with trajectory.atomic_write(path) as handle:
            handle.write(b"t,j,location\n")  # a part of the file ...
            for _ in range(presses):
                signal.raise_signal(signal.SIGINT)  # ... then Ctrl-C
        real(run, path, progress)

    return write_csv


@pytest.mark.skipif(sys.platform == "win32", reason="raise_signal(SIGINT) is POSIX here")
def test_one_ctrl_c_while_writing_a_normal_run_only_warns(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(trajectory, "write_csv", _interrupting_writer(1))
    out, events = tmp_path / "traj.csv", tmp_path / "events.json"
    code = main_in_process(
        "simulate", THERMOSTAT, "--t-end", "30", "--out", out, "--events", events
    )
    err = capsys.readouterr().err
    assert code == 0, err
    assert "still writing the outputs; press Ctrl-C again to abandon them" in err
    check_outputs(out, events)
    assert read_json(events)["termination"]["cause"] == "t_end"


@pytest.mark.skipif(sys.platform == "win32", reason="raise_signal(SIGINT) is POSIX here")
def test_a_second_ctrl_c_while_writing_abandons_the_outputs_and_says_so(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(trajectory, "write_csv", _interrupting_writer(2))
    out, events = tmp_path / "traj.csv", tmp_path / "events.json"
    out.write_text("an older trajectory\n")
    code = main_in_process(
        "simulate", THERMOSTAT, "--t-end", "30", "--out", out, "--events", events
    )
    err = capsys.readouterr().err
    assert code == 130
    assert f"hybrid: interrupted again while writing: abandoned {out}, {events}" in err
    assert_no_traceback(err)
    assert out.read_text() == "an older trajectory\n", "the older file is left as it was"
    assert not events.exists()
    assert [p.name for p in tmp_path.iterdir() if p.suffix == ".tmp"] == []


@pytest.mark.skipif(sys.platform == "win32", reason="raise_signal(SIGINT) is POSIX here")
def test_after_an_interrupted_run_one_ctrl_c_while_writing_abandons(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    from hybrid.cli import simulate as command

    real_simulate = command.simulate

    def ctrl_c_then_simulate(*args: Any, **kwargs: Any) -> Any:
        signal.raise_signal(signal.SIGINT)  # Ctrl-C as the run starts: it ends at once
        return real_simulate(*args, **kwargs)

    monkeypatch.setattr(command, "simulate", ctrl_c_then_simulate)
    monkeypatch.setattr(trajectory, "write_csv", _interrupting_writer(1))
    out, events = tmp_path / "traj.csv", tmp_path / "events.json"
    code = main_in_process(
        "simulate", THERMOSTAT, "--t-end", "30", "--out", out, "--events", events
    )
    err = capsys.readouterr().err
    assert code == 130
    assert "interrupted at t=0; writing the outputs (press Ctrl-C again to abandon them)" in err
    assert f"hybrid: interrupted again while writing: abandoned {out}, {events}" in err
    assert_no_traceback(err)
    assert not out.exists() and not events.exists()
    assert [p.name for p in tmp_path.iterdir() if p.suffix == ".tmp"] == []
