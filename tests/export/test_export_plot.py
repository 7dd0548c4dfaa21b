"""Figures of a run over hybrid time, inspected through their matplotlib artists.

Independent truths: the units, signals and components are read from the YAML
files themselves; the jump instants and values of the bouncing ball and the
switching instants of the thermostat are their closed forms (see
tests/simulation/test_sim_bouncing_ball.py and test_sim_thermostat.py).
"""

from __future__ import annotations

import builtins
import math
import subprocess
import sys
from pathlib import Path
from typing import Any

import matplotlib.image
import matplotlib.pyplot as plt
import numpy as np
import pytest
import yaml
from matplotlib.figure import Figure
from support import REPO as ROOT

import hybrid
from hybrid.export.plot import MAX_JUMP_LINES, figure_of, figures_of, plot_run

H0, G, E = 10.0, 9.81, 0.8
T1, V0 = math.sqrt(2 * H0 / G), math.sqrt(2 * G * H0)
IMPACTS = np.array([T1 * (1 + 2 * E * (1 - E ** (k - 1)) / (1 - E)) for k in (1, 2, 3)])
V_BEFORE = -(E ** np.arange(3)) * V0  # just before impact k: -e^(k-1) v0
V_AFTER = E ** np.arange(1, 4) * V0  # just after it: e^k v0

# Thermostat: off cools 20 -> 18 in 10 ln(5/4); on heats 18 -> 22 in 10 ln(3/2), off cools
# 22 -> 18 in 10 ln(3/2) (a = 0.1, T_out = 10, T_heat = 30).
SWITCHES = np.cumsum([10 * math.log(1.25), 10 * math.log(1.5), 10 * math.log(1.5)])


def _spec(path: str) -> dict[str, Any]:
    return dict(yaml.safe_load((ROOT / path).read_text(encoding="utf-8")))


def _by_gid(ax: Any, gid: str) -> list[Any]:
    return [artist for artist in ax.get_children() if artist.get_gid() == gid]


@pytest.fixture(scope="module")
def ball_run() -> hybrid.Run:
    ball = hybrid.load(ROOT / "specs/bouncing_ball.yaml")
    return hybrid.simulate(ball, t_end=6.0, rtol=1e-10, atol=1e-12)


@pytest.fixture(scope="module")
def mission() -> hybrid.Run:
    return hybrid.simulate(hybrid.load(ROOT / "specs/uvms_mission_2.yaml"), t_end=40.0)


def test_axis_labels_carry_the_units_of_the_spec(ball_run: hybrid.Run) -> None:
    state = _spec("specs/bouncing_ball.yaml")["state"]
    fig = figure_of(ball_run)
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert labels == [
        "location",
        *(f"{name} [{var['unit']}]" for name, var in state.items()),
        "signals",
    ]
    assert fig.axes[-1].get_xlabel() == "t [s]"


def test_signals_have_a_legend_entry_each(ball_run: hybrid.Run) -> None:
    signals = list(_spec("specs/bouncing_ball.yaml")["signals"])
    ax = figure_of(ball_run).axes[-1]
    assert [text.get_text() for text in ax.get_legend().get_texts()] == signals
    line = next(line for line in ax.get_lines() if line.get_label() == "energy")
    kept = ~np.isnan(line.get_ydata())
    assert np.allclose(line.get_ydata()[kept], ball_run["energy"])  # the signal, point by point


def test_jumps_are_marked_before_and_after_at_the_closed_form(ball_run: hybrid.Run) -> None:
    fig = figure_of(ball_run)
    v_axis = fig.axes[2]
    (before,) = _by_gid(v_axis, "jump-before")
    (after,) = _by_gid(v_axis, "jump-after")
    assert np.allclose(before.get_xdata(), IMPACTS, atol=1e-7)
    assert np.allclose(after.get_xdata(), IMPACTS, atol=1e-7)
    assert np.allclose(before.get_ydata(), V_BEFORE, rtol=1e-6)
    assert np.allclose(after.get_ydata(), V_AFTER, rtol=1e-6)
    assert before.get_markerfacecolor() == "white" and after.get_markerfacecolor() != "white"
    (dashes,) = _by_gid(v_axis, "jump")
    assert dashes.get_linestyle() == "--"
    legend = fig.axes[1].get_legend()  # on the first panel of the state
    assert [t.get_text() for t in legend.get_texts()] == ["before a jump", "after a jump"]


@pytest.mark.parametrize("dense", [False, True])
def test_curves_break_at_every_jump(dense: bool) -> None:
    ball = hybrid.load(ROOT / "specs/bouncing_ball.yaml")
    run = hybrid.simulate(ball, t_end=6.0, dense=dense)
    h_axis = figure_of(run).axes[1]
    curve = next(line for line in h_axis.get_lines() if line.get_label() == "h")
    x = np.asarray(curve.get_xdata(), dtype=float)
    pieces = np.split(x, np.flatnonzero(np.isnan(x)))
    pieces = [p[~np.isnan(p)] for p in pieces if np.any(~np.isnan(p))]
    assert len(pieces) == len(run.jumps) + 1 == 4  # one piece per stay
    assert np.allclose([p[-1] for p in pieces[:-1]], [j.t for j in run.jumps])
    if dense:
        assert all(len(p) == 200 for p in pieces)  # drawn from the interpolants


def test_the_location_lane_shows_each_stay_at_the_closed_form() -> None:
    run = hybrid.simulate(
        hybrid.load(ROOT / "specs/thermostat.yaml"), t_end=12.0, rtol=1e-10, atol=1e-12
    )
    lane = figure_of(run).axes[0]
    assert [t.get_text() for t in lane.get_yticklabels()] == ["off", "on"]
    spans: dict[str, list[tuple[float, float]]] = {}
    for loc in ("off", "on"):
        (bars,) = _by_gid(lane, f"lane:{loc}")
        spans[loc] = [(p.get_x(), p.get_x() + p.get_width()) for p in _rects(bars)]
    assert np.allclose(spans["off"], [(0.0, SWITCHES[0]), (SWITCHES[1], SWITCHES[2])], atol=1e-7)
    assert np.allclose(spans["on"], [(SWITCHES[0], SWITCHES[1]), (SWITCHES[2], 12.0)], atol=1e-7)
    (marks,) = _by_gid(lane, "lane-jump-marks")
    assert np.allclose(marks.get_xdata(), SWITCHES, atol=1e-7)
    assert list(marks.get_ydata()) == [1, 0, 1]  # into 'on' (row 1), 'off' (row 0), 'on' again


def _rects(collection: Any) -> list[Any]:
    """The rectangles of a broken_barh collection, as objects with x and width."""
    out = []
    for path in collection.get_paths():
        xs = path.vertices[:, 0]
        out.append(_Span(float(xs.min()), float(xs.max() - xs.min())))
    return out


class _Span:
    def __init__(self, x: float, width: float) -> None:
        self.x, self.width = x, width

    def get_x(self) -> float:
        return self.x

    def get_width(self) -> float:
        return self.width


def test_against_j_and_both_are_the_hybrid_time_view(ball_run: hybrid.Run) -> None:
    fig = figure_of(ball_run, "v", against="j", signals=False)
    (before,) = _by_gid(fig.axes[1], "jump-before")
    (after,) = _by_gid(fig.axes[1], "jump-after")
    assert list(before.get_xdata()) == [0, 1, 2] and list(after.get_xdata()) == [1, 2, 3]
    assert fig.axes[-1].get_xlabel() == "j (jumps)"
    both = figure_of(ball_run, "v", against="both", signals=False)
    assert [ax.get_xlabel() for ax in both.axes[-2:]] == ["t [s]", "j (jumps)"]
    assert len(both.axes) == 4  # lane and v, against t and against j


def test_a_system_gets_one_figure_per_component(mission: hybrid.Run) -> None:
    system = _spec("specs/uvms_mission_2.yaml")
    names = [c.get("as") or _spec(f"specs/{c['spec']}")["automaton"] for c in system["components"]]
    figures = figures_of(mission)
    assert list(figures) == names
    for component in system["components"]:
        spec = _spec(f"specs/{component['spec']}")
        name = component.get("as") or spec["automaton"]
        axes = figures[name].axes
        states = list(spec.get("state", {}))
        units = {s: v.get("unit") for s, v in spec.get("state", {}).items()}
        assert [ax.get_ylabel() for ax in axes[1 : 1 + len(states)]] == [
            f"{s} [{units[s]}]" if units[s] else s for s in states
        ]
        lane_rows = [t.get_text() for t in axes[0].get_yticklabels()]
        assert set(lane_rows) <= set(spec["locations"]) and lane_rows  # plain location names
        legend = [t.get_text() for t in axes[-1].get_legend().get_texts()]
        assert {entry.split("[")[0] for entry in legend} == set(spec.get("signals", {}))
    whole = figure_of(mission, "q2", "theta_p")
    assert len(whole.subfigs) == 2
    assert [s._suptitle.get_text() for s in whole.subfigs] == [f"component {n}" for n in names]
    alone = mission.plot("theta_p", component="polarization")
    assert [ax.get_ylabel() for ax in alone.axes] == ["location", "signals"]


def test_run_plot_returns_the_figure_and_shows_or_saves_nothing_unless_asked(
    ball_run: hybrid.Run, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    shown: list[bool] = []
    monkeypatch.setattr(plt, "show", lambda *a, **k: shown.append(True))
    monkeypatch.chdir(tmp_path)
    before = plt.get_fignums()
    fig = ball_run.plot()
    assert isinstance(fig, Figure)
    assert shown == [] and list(tmp_path.iterdir()) == [] and plt.get_fignums() == before
    fig = ball_run.plot("h", path="ball.svg")
    assert (tmp_path / "ball.svg").read_text().lstrip().startswith("<?xml")
    assert shown == [] and plt.get_fignums() == before
    fig = ball_run.plot(show=True)
    assert shown == [True] and fig.number in plt.get_fignums()
    plt.close(fig)


def test_mistakes_are_clear(ball_run: hybrid.Run) -> None:
    with pytest.raises(
        hybrid.UsageError, match="no state variable or signal 'hh'; did you mean 'h'"
    ):
        ball_run.plot("hh")
    with pytest.raises(hybrid.UsageError, match="against must be one of t, j, both"):
        ball_run.plot(against="x")
    with pytest.raises(hybrid.UsageError, match="component= applies to a system"):
        ball_run.plot(component="ball")


def test_many_jumps_mark_only_the_first(ball: hybrid.Automaton) -> None:
    run = hybrid.simulate(ball, t_end=20.0, zeno=False, max_jumps=400)
    fig = figure_of(run, "v", signals=False)
    (before,) = _by_gid(fig.axes[1], "jump-before")
    assert len(before.get_xdata()) == MAX_JUMP_LINES < len(run.jumps)
    assert f"first {MAX_JUMP_LINES} marked" in fig._suptitle.get_text()


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
    with pytest.raises(hybrid.UsageError, match=r"^cannot write '\.xyz' figures"):  # no --plot here
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

    run = hybrid.simulate(hybrid.load(ROOT / "specs/thermostat.yaml"), t_end=5.0)
    monkeypatch.setattr(builtins, "__import__", no_matplotlib)
    with pytest.raises(
        hybrid.UsageError, match=r"pip install 'matplotlib>=3.7' \(the 'plot' extra\)"
    ):
        run.plot()


def test_import_hybrid_loads_neither_matplotlib_nor_pandas() -> None:
    code = (
        "import sys, hybrid, hybrid.export, hybrid.export.plot\n"
        "run = hybrid.simulate(hybrid.load('specs/bouncing_ball.yaml'), t_end=1.0)\n"
        "print(sorted(m for m in ('matplotlib', 'pandas', 'graphviz') if m in sys.modules))"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, timeout=120
    )
    assert result.returncode == 0, result.stderr
    assert result.stdout.strip() == "[]"


def test_a_signal_named_with_signals_off_is_refused_not_dropped() -> None:
    """``run.plot("heating_power", signals=False)`` drew a figure without the one curve
    asked for; states named with ``signals=False`` still draw as before."""
    run = hybrid.simulate(hybrid.load(ROOT / "specs" / "thermostat.yaml"), t_end=30.0)
    with pytest.raises(hybrid.UsageError, match="'heating_power' is a signal, and signals=False"):
        run.plot("T", "heating_power", signals=False)
    fig = figure_of(run, "T", signals=False)
    assert [ax.get_ylabel() for ax in fig.axes] == ["location", "T [degC]"]
    plt.close("all")
