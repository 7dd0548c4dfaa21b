"""``hybrid simulate`` on bad flags: exit 2, a one-line error, no traceback."""

from __future__ import annotations

from pathlib import Path

import pytest
from support import SPECS, assert_no_traceback, main_in_process, run_cli

BALL = str(SPECS / "bouncing_ball.yaml")


def error_lines(stderr: str) -> list[str]:
    """The message lines (argparse prints the usage before them)."""
    return [line for line in stderr.splitlines() if "error" in line]


@pytest.mark.parametrize(
    ("flags", "message"),
    [
        (["--t-end", "-1"], "argument --t-end: must be > 0, got -1"),
        (["--t-end", "0"], "argument --t-end: must be > 0, got 0"),
        (["--t-end", "1", "--rtol", "abc"], "argument --rtol: expected a number, got 'abc'"),
        (["--t-end", "1", "--atol=-1e-9"], "argument --atol: must be > 0, got -1e-9"),
        (["--t-end", "1", "--max-step", "0"], "argument --max-step: must be > 0"),
        (["--t-end", "1", "--dt", "nan"], "argument --dt: must be > 0"),
        (["--t-end", "1", "--max-jumps", "2.5"], "argument --max-jumps: expected a whole number"),
        (["--t-end", "1", "--method", "Euler"], "argument --method: invalid choice: 'Euler'"),
        (["--t-end", "1", "--param", "g"], "argument --param: expected name=value, got 'g'"),
        (["--t-end", "1", "--param", "g=heavy"], "value of 'g' must be a number"),
        ([], "the following arguments are required: --t-end"),
    ],
)
def test_bad_flags_exit_2_with_one_line(
    capsys: pytest.CaptureFixture[str], flags: list[str], message: str
) -> None:
    assert main_in_process("simulate", BALL, *flags) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = error_lines(captured.err)
    assert lines == [f"hybrid: error: {lines[0].split('hybrid: error: ', 1)[1]}"]
    assert message in lines[0]
    assert_no_traceback(captured.err)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["--t-end", "1", "--param", "gg=1"], "unknown parameter 'gg'"),
        (["--t-end", "1", "--out", "traj.txt"], "--out: use a .csv or .npz file name"),
    ],
)
def test_bad_values_found_later_exit_2_with_one_line(
    capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    assert main_in_process("simulate", BALL, *args) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and message in err
    assert_no_traceback(err)


def test_missing_file_exits_2(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    assert main_in_process("simulate", tmp_path / "nope.yaml", "--t-end", "1") == 2
    err = capsys.readouterr().err
    assert "nope.yaml" in err and len(err.strip().splitlines()) == 1
    assert_no_traceback(err)


def test_bad_flag_in_a_real_process() -> None:
    result = run_cli("simulate", BALL, "--t-end", "1", "--rtol", "abc")
    assert result.returncode == 2
    assert result.stdout == ""
    assert error_lines(result.stderr) == [
        "hybrid: error: argument --rtol: expected a number, got 'abc'"
    ]
    assert_no_traceback(result.stderr)


def test_a_normal_run_exits_0_with_a_summary(capsys: pytest.CaptureFixture[str]) -> None:
    assert main_in_process("simulate", BALL, "--t-end", "2") == 0
    captured = capsys.readouterr()
    assert captured.out.strip() == f"{BALL}: t_end at t=2 j=1 (1 jumps, {_points()} points)"
    assert captured.err == ""


def _points() -> int:
    import hybrid

    return len(hybrid.simulate(hybrid.load(BALL), t_end=2.0))
