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
        # values that used to hang the run instead of being refused
        (
            ["--t-end", "1", "--rtol", "1e400"],
            "argument --rtol: must be a finite number, got 1e400",
        ),
        (["--t-end", "1", "--param", "g=nan"], "value of 'g' must be a finite number, got 'nan'"),
        (["--t-end", "inf"], "argument --t-end: must be a finite number, got inf"),
        (["--t-end", "1", "--atol=-inf"], "argument --atol: must be > 0, got -inf"),
        (["--t-end", "1", "--input", "u"], "argument --input: expected NAME=EXPR"),
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
        # the last value used to win silently
        (["--t-end", "1", "--param", "e=0.5", "--param", "e=0.7"],
         "--param e is given twice (0.5 and 0.7): give it once"),
        (["--t-end", "1", "--init", "h=1", "--init", "h=2"],
         "--init h is given twice (1.0 and 2.0): give it once"),
        (["--t-end", "1", "--out", "traj.txt"], "--out: use a .csv, .npz or .mat file name"),
        # used to write JSON into ev.csv, exit 0
        (["--t-end", "1", "--events", "ev.csv"], "--events writes JSON, not .csv: name it 'ev.json'"),
        (["--t-end", "1", "--events", "ev.PNG"], "--events writes JSON, not .PNG: name it 'ev.json'"),
        (["--t-end", "10", "--max-step", "1e-300"], "max_step=1e-300 is below the resolution"),
        (["--t-end", "1e6", "--max-step", "1e-7"], "needs at least 1e+13 steps"),
        (["--t-end", "10", "--dt", "1e-12"], "dt=1e-12 gives 1e+13 points"),
        (["--t-end", "1", "--rtol", "1e-20"], "rtol must be at least 2.22e-14"),
        (["--t-end", "1", "--rtol", "2"], "and below 1, got 2.0"),
        (["--t-end", "1", "--input", "u=t"], "'u' is not a free input of bouncing_ball"),
    ],
)
def test_bad_values_found_later_exit_2_with_one_line(
    capsys: pytest.CaptureFixture[str], args: list[str], message: str
) -> None:
    assert main_in_process("simulate", BALL, *args) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and message in err
    assert_no_traceback(err)


def test_a_figure_format_matplotlib_cannot_write_is_refused_before_the_run(
    capsys: pytest.CaptureFixture[str], tmp_path: Path
) -> None:
    pytest.importorskip("matplotlib")
    out = tmp_path / "traj.csv"
    code = main_in_process("simulate", BALL, "--t-end", "1", "--out", out, "--plot", "fig.csv")
    assert code == 2
    captured = capsys.readouterr()
    assert captured.out == ""  # no run: it used to simulate, write traj.csv, then refuse
    assert "--plot: cannot write '.csv' figures; use one of" in captured.err
    assert list(tmp_path.iterdir()) == []


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


def test_a_refused_setting_ends_at_once_in_a_real_process() -> None:
    # --param g=nan used to hang the run (the other refused values above too)
    result = run_cli("simulate", BALL, "--t-end", "10", "--param", "g=nan", timeout=30)
    assert result.returncode == 2
    assert result.stdout == ""
    assert_no_traceback(result.stderr)


def test_every_simulate_flag_is_documented_in_cli_md() -> None:
    from support import DOCS

    from hybrid.cli.main import build_parser

    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    simulate = sub.choices["simulate"]  # type: ignore[index]
    page = (DOCS / "cli.md").read_text()
    section = page.split("## `hybrid simulate`", 1)[1].split("\n## ", 1)[0]
    flags = [o for a in simulate._actions for o in a.option_strings if o.startswith("--")]
    flags.remove("--help")
    missing = [f for f in flags if f"`{f}" not in section]
    assert not missing, f"not in the simulate section of docs/cli.md: {missing}"
