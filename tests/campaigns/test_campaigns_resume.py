"""A campaign killed (kill -9) or stopped by Ctrl-C resumes and runs only the missing runs.

The command runs in a process of its own session (its workers with it); the test
waits for the first chunk of finished rows on disk, kills the whole session with
SIGKILL (or sends SIGINT to the command, as a terminal's Ctrl-C does), counts the
rows on disk, and runs the same command with --resume: it must report exactly
those rows as done and run only the others, and its table must be the one an
uninterrupted campaign writes.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from support import REPO, assert_no_traceback, run_cli

import hybrid
from hybrid.errors import UsageError

WAVE = """
automaton: wave
parameters: {w: 1.0}
state: {x: {initial: 0.0}}
locations: {on: {flow: {x: cos(w*t)}}}
requirements: [{name: small, always: "x <= 0.2"}]
"""
# 1250 steps a run (max_step 0.004 over 5 s): 60 to 200 ms (the engine's own RK step
# made them cheaper); 48 runs on one worker take 3 s or more, well beyond the first
# chunk (written a second after the first row), so the test has time to stop the
# campaign half-way (with 24 runs of 68 ms, a fast moment of a CI machine finished the
# campaign before its first chunk). x = sin(w t) / w goes above 0.2 for w < 5: some
# runs violate the requirement (exit 1).
MAX_STEP = 0.004
ARGS = ["--t-end", "5", "--grid", "w=1:48:48", "--max-step", str(MAX_STEP), "--workers", "1"]
ARGS += ["--quiet", "--backend", "scipy"]  # slow on purpose: auto may pick the fast one
RUNS = 48


def _start(spec: Path, out: Path, *extra: str) -> subprocess.Popen[str]:
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    return subprocess.Popen(
        [sys.executable, "-m", "hybrid", "sweep", str(spec), *ARGS, "--out", str(out), *extra],
        cwd=REPO,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )


def _rows_on_disk(parts: Path) -> set[int]:
    done = set()
    for chunk in parts.glob("chunk-*.jsonl"):
        done |= {json.loads(line)["run"] for line in chunk.read_text().splitlines()}
    return done


def _wait_for_a_chunk(parts: Path, process: subprocess.Popen[str]) -> None:
    deadline = time.monotonic() + 60
    while not any(parts.glob("chunk-*.jsonl")):
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "no chunk written within a minute"
        time.sleep(0.02)


@pytest.fixture(scope="module")
def reference() -> str:
    """The table of the campaign run whole, in this process."""
    table = hybrid.sweep(
        hybrid.load_text(WAVE), t_end=5.0, grid={"w": [float(w) for w in range(1, RUNS + 1)]},
        max_step=MAX_STEP, workers=0, backend="scipy",
    )  # fmt: skip
    return table.csv_text()


def test_kill_9_then_resume_runs_only_the_missing_runs(tmp_path: Path, reference: str) -> None:
    spec, out = tmp_path / "wave.yaml", tmp_path / "results.csv"
    spec.write_text(WAVE)
    parts = out.with_name("results.csv.parts")
    process = _start(spec, out)
    _wait_for_a_chunk(parts, process)
    os.killpg(process.pid, signal.SIGKILL)
    process.communicate()
    done = _rows_on_disk(parts)
    assert 0 < len(done) < RUNS and not out.exists()
    again = run_cli("sweep", spec, *ARGS, "--out", out, "--resume", timeout=120)
    assert_no_traceback(again.stderr)
    assert f"resumed: {len(done)} of {RUNS} runs were done; ran {RUNS - len(done)}" in again.stderr
    assert again.returncode == 1
    assert out.read_text() == reference
    assert not parts.exists()


def test_without_resume_a_folder_of_unfinished_work_is_not_overwritten(tmp_path: Path) -> None:
    out = tmp_path / "results.csv"
    parts = out.with_name("results.csv.parts")
    parts.mkdir()
    (parts / "campaign.json").write_text('{"fingerprint": "another"}')
    wave = hybrid.load_text(WAVE)
    with pytest.raises(UsageError, match="add --resume"):
        hybrid.sweep(wave, t_end=1.0, grid={"w": [1.0]}, out=out, workers=0)
    with pytest.raises(UsageError, match="another campaign"):
        hybrid.sweep(wave, t_end=1.0, grid={"w": [1.0]}, out=out, resume=True, workers=0)
    assert (parts / "campaign.json").read_text() == '{"fingerprint": "another"}'


def test_ctrl_c_stops_cleanly_keeps_the_rows_and_says_how_to_resume(
    tmp_path: Path, reference: str
) -> None:
    spec, out = tmp_path / "wave.yaml", tmp_path / "results.csv"
    spec.write_text(WAVE)
    parts = out.with_name("results.csv.parts")
    process = _start(spec, out)
    _wait_for_a_chunk(parts, process)
    process.send_signal(signal.SIGINT)
    _, stderr = process.communicate(timeout=60)
    assert_no_traceback(stderr)
    assert process.returncode == 1, stderr
    assert "interrupted" in stderr and "--resume" in stderr
    kept = _rows_on_disk(parts)
    assert 0 < len(kept) < RUNS and not out.exists()  # stopped before its end, rows kept
    again = run_cli("sweep", spec, *ARGS, "--out", out, "--resume", timeout=120)
    assert f"resumed: {len(kept)} of {RUNS} runs were done" in again.stderr
    assert out.read_text() == reference
