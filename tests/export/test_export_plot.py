"""`--plot`: each state against t, jumps marked; clear errors without matplotlib."""

from __future__ import annotations

import builtins
import subprocess
import sys
from pathlib import Path
from typing import Any

import matplotlib.image
import pytest
from support import REPO as ROOT

import hybrid
from hybrid.export.plot import figure_of, plot_run


def _dashed_lines(ax: Any) -> list[float]:
    return sorted(line.get_xdata()[0] for line in ax.lines if line.get_linestyle() == "--")


@pytest.mark.parametrize("dense", [False, True])
def test_one_panel_per_state_and_a_line_per_jump(dense: bool) -> None:
    run = hybrid.simulate(hybrid.load(ROOT / "specs/bouncing_ball.yaml"), t_end=6.0, dense=dense)
    fig = figure_of(run)
    assert [ax.get_ylabel() for ax in fig.axes] == ["h", "v"]
    jump_times = sorted(j.t for j in run.jumps)
    assert len(jump_times) == 3  # impacts at 1.43, 3.71, 5.54 s (closed form)
    for ax in fig.axes:
        assert _dashed_lines(ax) == pytest.approx(jump_times)
        solid = [line for line in ax.lines if line.get_linestyle() == "-"]
        assert len(solid) == len(jump_times) + 1  # the curve is broken at every jump


def test_cli_writes_a_png(tmp_path: Path) -> None:
    out = tmp_path / "ball.png"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "hybrid",
            "simulate",
            str(ROOT / "specs/bouncing_ball.yaml"),
            "--t-end",
            "3",
            "--plot",
            str(out),
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert result.returncode == 0, result.stderr
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    height, width, _ = matplotlib.image.imread(out).shape
    assert width > 500 and height > 300
    assert [p.name for p in tmp_path.iterdir()] == ["ball.png"]  # no temporary left


def test_unknown_figure_format_is_a_clear_error(tmp_path: Path) -> None:
    run = hybrid.simulate(hybrid.load(ROOT / "specs/thermostat.yaml"), t_end=5.0)
    with pytest.raises(hybrid.SimulationError, match=r"cannot write '\.xyz' figures"):
        plot_run(run, tmp_path / "fig.xyz")
    assert list(tmp_path.iterdir()) == []


def test_without_matplotlib_the_error_says_what_to_install(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    real_import = builtins.__import__

    def no_matplotlib(name: str, *args: Any, **kwargs: Any) -> Any:
        if name.startswith("matplotlib"):
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_matplotlib)
    run = hybrid.simulate(hybrid.load(ROOT / "specs/thermostat.yaml"), t_end=5.0)
    with pytest.raises(hybrid.SimulationError, match=r"pip install 'hybrid-automata\[plot\]'"):
        figure_of(run)
