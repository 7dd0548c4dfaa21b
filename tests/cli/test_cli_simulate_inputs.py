"""``hybrid simulate --input NAME=EXPR`` and ``--input-csv FILE``: free inputs from the command line."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from support import assert_no_traceback, main_in_process, read_csv, read_json

RELAY = """
automaton: relay
inputs: [u]
state: {x: {initial: 0.0}}
signals: {seen: u}
locations:
  low: {flow: {x: u}}
  high: {flow: {x: u}}
edges:
  - {name: up, from: low, to: high, guard: u >= 0.5}
  - {name: down, from: high, to: low, guard: u <= -0.5}
"""


@pytest.fixture
def relay(tmp_path: Path) -> Path:
    spec = tmp_path / "relay.yaml"
    spec.write_text(RELAY)
    return spec


def test_an_expression_of_t_drives_the_input(relay: Path, tmp_path: Path) -> None:
    out, events = tmp_path / "traj.csv", tmp_path / "events.json"
    code = main_in_process(
        "simulate", relay, "--t-end", "5", "--input", "u=sin(2*t)", "--dt", "0.01",
        "--rtol", "1e-10", "--atol", "1e-12", "--out", out, "--events", events,
    )  # fmt: skip
    assert code == 0
    jumps = read_json(events)["jumps"]
    # up where sin(2t) = 1/2, down where sin(2t) = -1/2
    expected = [math.pi / 12, 7 * math.pi / 12, 13 * math.pi / 12, 19 * math.pi / 12]
    assert [j["edge"] for j in jumps] == ["up", "down", "up", "down"]
    assert [j["t"] for j in jumps] == pytest.approx(expected, abs=1e-9)
    _, rows = read_csv(out)
    t = np.array([float(r["t"]) for r in rows])
    np.testing.assert_allclose([float(r["seen"]) for r in rows], np.sin(2 * t), atol=1e-12)
    # x' = u: x = (1 - cos 2t) / 2
    np.testing.assert_allclose([float(r["x"]) for r in rows], (1 - np.cos(2 * t)) / 2, atol=1e-8)


def test_a_csv_time_series_drives_the_input_linearly(relay: Path, tmp_path: Path) -> None:
    series = tmp_path / "u.csv"
    series.write_text("t,u\n0,0\n1,1\n3,-1\n4,1\n")
    events = tmp_path / "events.json"
    code = main_in_process(
        "simulate", relay, "--t-end", "4", "--input-csv", series, "--events", events
    )
    assert code == 0
    jumps = read_json(events)["jumps"]
    # u: 0 -> 1 on [0, 1] (1/2 at t = 0.5), 1 -> -1 on [1, 3] (-1/2 at 2.5), -1 -> 1 on [3, 4]
    # (1/2 at 3.75)
    assert [(j["edge"], round(j["t"], 9)) for j in jumps] == [
        ("up", 0.5),
        ("down", 2.5),
        ("up", 3.75),
    ]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        ([], "input 'u' needs a value: give --input u=EXPR (an expression of t) or --input-csv"),
        (["--input", "v=t"], "--input v: 'v' is not a free input of relay (inputs: u)"),
        (["--input", "u=sin(2*x)"], "input u = sin(2*x): column 7: unknown name 'x'"),
        (["--input", "u=sin(2*t"], "input u = sin(2*t: column 4: syntax error"),
        (["--input", "u=t > 1"], "input u = t > 1: column 1: expected a number, got a condition"),
        (
            ["--input", "u=t", "--input", "u=2*t"],
            "input 'u' is given twice (--input u and --input u)",
        ),
        (["--input", "u=__import__('os')"], "input u = __import__('os')"),
    ],
)
def test_bad_inputs_exit_2_with_one_line(
    relay: Path, capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    assert main_in_process("simulate", relay, "--t-end", "1", *args) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    assert message in err
    assert_no_traceback(err)


@pytest.mark.parametrize(
    ("text", "place", "message"),
    [
        ("", "1:1", "empty file"),
        ("time,u\n0,1\n1,2\n", "1:1", "the first column must be 't', got 'time'"),
        ("t,u\n0,1\n1,abc\n", "3:3", "not a number: 'abc'"),
        ("t,u\n0,1\n0,2\n", "3:1", "times must increase: t=0 after t=0"),
        ("t,u\n0,1\n1,nan\n", "3:3", "not a finite number: 'nan'"),
        ("t,u\n0,1\n1\n", "3:1", "1 values, but the header has 2 columns"),
        ("t,u\n0,1\n", "1:1", "at least two sample rows are needed"),
        ("t,u,u\n0,1,1\n1,1,1\n", "1:5", "column 'u' appears twice"),
    ],
)
def test_bad_series_files_are_reported_at_their_place(
    relay: Path,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    text: str,
    place: str,
    message: str,
) -> None:
    series = tmp_path / "u.csv"
    series.write_text(text)
    assert main_in_process("simulate", relay, "--t-end", "1", "--input-csv", series) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"{series}:{place}: {message}"), err
    assert_no_traceback(err)


def test_a_series_must_cover_the_run(
    relay: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    series = tmp_path / "u.csv"
    series.write_text("t,u\n0,0\n2,1\n")
    assert main_in_process("simulate", relay, "--t-end", "3", "--input-csv", series) == 2
    err = capsys.readouterr().err
    assert "input u from" in err and "covers t in [0, 2] but the run goes from t=0 to t=3" in err


def test_an_input_that_fails_ends_the_run_as_nonfinite(
    relay: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main_in_process("simulate", relay, "--t-end", "1", "--input", "u=log(t - 0.5)") == 1
    err = capsys.readouterr().err
    assert "nonfinite" in err and "input u = log(t - 0.5) failed at t=0: math domain error" in err
    assert_no_traceback(err)
