"""``hybrid.Settings``: one options object for every entry point, keywords as overrides.

A run given its options as a :class:`hybrid.Settings` must be the very run the
same options as keywords give (compared value for value, on both backends); a
keyword given with the object wins over its field; a bad field is refused when
the object is made, naming the field; and the command line's flags reach the
settings of its runs (``--rtol`` changes a run as ``rtol=`` does).
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from support import SPECS, run_cli

import hybrid
from hybrid.simulation.settings import OPTIONS

BALL = SPECS / "bouncing_ball.yaml"
FINE = {"rtol": 1e-10, "atol": 1e-12}
FIRST_IMPACT = math.sqrt(2 * 10 / 9.81)  # dropped from h = 10 m at g = 9.81 m/s^2


@pytest.fixture(scope="module")
def ball() -> hybrid.Automaton:
    return hybrid.load(BALL)


def assert_same_run(a: hybrid.Run, b: hybrid.Run) -> None:
    """Two runs equal value for value: points, jumps, end and settings."""
    np.testing.assert_array_equal(a.t, b.t)
    np.testing.assert_array_equal(a.j, b.j)
    np.testing.assert_array_equal(a.states, b.states)
    assert [(j.t, j.edge, j.before, j.after) for j in a.jumps] == [
        (j.t, j.edge, j.before, j.after) for j in b.jumps
    ]
    assert a.termination == b.termination
    assert a.settings == b.settings


@pytest.mark.parametrize("backend", ["scipy", "compiled"])
def test_settings_give_the_run_the_keywords_give(ball: hybrid.Automaton, backend: str) -> None:
    options = {**FINE, "max_jumps": 1, "dt": 0.05, "backend": backend}
    by_keywords = hybrid.simulate(ball, 4.0, handle_sigint=False, **options)
    by_object = hybrid.simulate(
        ball, settings=hybrid.Settings(t_end=4.0, **options), handle_sigint=False
    )
    assert_same_run(by_object, by_keywords)
    assert by_object.termination.cause == "max_jumps"
    assert abs(by_object.jumps[0].t - FIRST_IMPACT) < 1e-8
    assert by_object.settings["backend"] == backend


def test_keywords_override_the_settings(ball: hybrid.Automaton) -> None:
    coarse = hybrid.Settings(t_end=3.0, rtol=1e-3, atol=1e-3, max_jumps=1)
    overridden = hybrid.simulate(ball, settings=coarse, handle_sigint=False, **FINE)
    expected = hybrid.simulate(ball, 3.0, max_jumps=1, handle_sigint=False, **FINE)
    assert_same_run(overridden, expected)
    assert overridden.settings["rtol"] == 1e-10 and overridden.settings["max_jumps"] == 1
    assert abs(overridden.jumps[0].t - FIRST_IMPACT) < 1e-8
    # the coarse settings alone give another run: the override did something
    alone = hybrid.simulate(ball, settings=coarse, handle_sigint=False)
    assert alone.settings["rtol"] == 1e-3 and len(alone) != len(overridden)
    # a positional t_end overrides the settings' one
    early = hybrid.simulate(ball, 1.0, settings=coarse, handle_sigint=False)
    assert early.termination.cause == "t_end" and early.termination.t == 1.0
    assert coarse.t_end == 3.0  # the object itself is never changed


@pytest.mark.parametrize(
    ("field", "value", "message"),
    [
        ("t_end", math.nan, "t_end must be a finite time"),
        ("t_start", math.inf, "t_start must be a finite number"),
        ("max_jumps", -1, "max_jumps must be >= 0"),
        ("rtol", 1.5, "rtol must be at least"),
        ("atol", 0.0, "atol must be > 0"),
        ("max_step", -1.0, "max_step must be > 0"),
        ("method", "Euler", "unknown method 'Euler'"),
        ("dt", 0.0, "dt must be > 0"),
        ("dense", "yes", "dense must be True or False"),
        ("zeno", None, "zeno must be True or False"),
        ("max_jumps_per_instant", 0, "max_jumps_per_instant must be >= 1"),
        ("backend", "gpu", "unknown backend 'gpu'"),
    ],
)
def test_a_bad_field_is_a_usage_error_naming_it(field: str, value: Any, message: str) -> None:
    fields: dict[str, Any] = {"t_end": 2.0, field: value}
    with pytest.raises(hybrid.UsageError, match=message):
        hybrid.Settings(**fields)


def test_every_field_is_tried_for_a_bad_value() -> None:
    tried = {p[0] for p in test_a_bad_field_is_a_usage_error_naming_it.pytestmark[0].args[1]}
    assert tried == set(OPTIONS)


def test_a_bad_override_or_object_is_a_usage_error(ball: hybrid.Automaton) -> None:
    good = hybrid.Settings(t_end=2.0)
    with pytest.raises(hybrid.UsageError, match="rtol must be a finite number, got inf"):
        hybrid.simulate(ball, settings=good, rtol=math.inf)
    with pytest.raises(hybrid.UsageError, match=r"settings must be a hybrid\.Settings"):
        hybrid.simulate(ball, settings={"t_end": 2.0})  # type: ignore[arg-type]
    with pytest.raises(hybrid.UsageError, match="t_end must be a finite time"):
        hybrid.simulate(ball)  # neither t_end nor settings


def test_simulate_many_takes_the_settings(ball: hybrid.Automaton) -> None:
    table = {"init.h": [5.0, 10.0]}
    options = {**FINE, "max_jumps": 2, "dt": 0.1}
    by_keywords = hybrid.simulate_many(ball, 2.0, parameters=table, handle_sigint=False, **options)
    by_object = hybrid.simulate_many(
        ball, settings=hybrid.Settings(t_end=2.0, **options), parameters=table, handle_sigint=False
    )
    for a, b in zip(by_object, by_keywords, strict=True):
        assert_same_run(a, b)
    # h = 10: the first impact at sqrt(2 h / g); a keyword overrides the object's t_end
    assert abs(by_object[1].jumps[0].t - FIRST_IMPACT) < 1e-8
    shorter = hybrid.simulate_many(
        ball, 1.0, settings=hybrid.Settings(t_end=2.0, **options), parameters=table
    )
    assert shorter.t.tolist() == [1.0, 1.0]
    with pytest.raises(hybrid.UsageError, match="method 'Radau'"):
        hybrid.simulate_many(ball, settings=hybrid.Settings(t_end=2.0, method="Radau"))


def test_sweep_takes_the_settings(ball: hybrid.Automaton) -> None:
    grid = {"e": [0.5, 0.9]}
    common: dict[str, Any] = {"grid": grid, "workers": 0, "summaries": ["jump_t:1", "max:v"]}
    by_keywords = hybrid.sweep(ball, 2.0, **common, **FINE)
    by_object = hybrid.sweep(ball, settings=hybrid.Settings(t_end=2.0, **FINE), **common)
    assert by_object.rows == by_keywords.rows
    assert abs(by_object.rows[0]["jump_t:1"] - FIRST_IMPACT) < 1e-8
    coarse = hybrid.Settings(t_end=2.0, rtol=1e-3, atol=1e-3)
    overridden = hybrid.sweep(ball, settings=coarse, **common, **FINE)
    assert overridden.rows == by_keywords.rows
    assert hybrid.sweep(ball, settings=coarse, **common).rows != by_keywords.rows


def test_sweep_takes_the_backend_of_the_settings(ball: hybrid.Automaton) -> None:
    # the two backends agree within 1e-9 here, not to the last bit: the rows tell them apart
    common: dict[str, Any] = {"grid": {"e": [0.5]}, "workers": 0, "summaries": ["jump_t:1"]}
    compiled = hybrid.Settings(t_end=2.0, backend="compiled", **FINE)
    by_object = hybrid.sweep(ball, settings=compiled, **common)
    by_keyword = hybrid.sweep(ball, 2.0, backend="compiled", **common, **FINE)
    on_scipy = hybrid.sweep(ball, 2.0, backend="scipy", **common, **FINE)  # the default is auto
    assert by_object.rows == by_keyword.rows
    assert abs(by_object.rows[0]["jump_t:1"] - on_scipy.rows[0]["jump_t:1"]) < 1e-9
    assert by_object.rows != on_scipy.rows
    # the keyword wins over the object's backend
    assert hybrid.sweep(ball, settings=compiled, backend="scipy", **common).rows == on_scipy.rows


HEATER = """\
automaton: heater
parameters: {k: 0.1}
state: {x: {initial: 20.0}}
locations: {cooling: {flow: {x: -k*x}}}
requirements: [{name: warm, always: "x >= 15"}]
"""


def test_falsify_takes_the_settings() -> None:
    heater = hybrid.load_text(HEATER)
    common: dict[str, Any] = {"budget": 8, "seed": 1, "workers": 0}
    by_keywords = hybrid.falsify(heater, "warm", {"k": (0.0, 0.1)}, t_end=5.0, **common, **FINE)
    by_object = hybrid.falsify(
        heater, "warm", {"k": (0.0, 0.1)}, settings=hybrid.Settings(t_end=5.0, **FINE), **common
    )
    assert by_object.as_dict() == by_keywords.as_dict()
    # x(5) = 20 exp(-5 k) < 15 exactly when k > ln(4/3)/5
    assert by_object.found and by_object.values["k"] > math.log(4 / 3) / 5


def test_reach_reads_the_horizon_of_the_settings(ball: hybrid.Automaton) -> None:
    by_object = hybrid.reach(ball, settings=hybrid.Settings(t_end=1.0), max_jumps=1, step=0.01)
    by_keyword = hybrid.reach(ball, 1.0, max_jumps=1, step=0.01)
    assert by_object.t_end == by_keyword.t_end == 1.0
    assert [s.mode for s in by_object.sets] == [s.mode for s in by_keyword.sets]
    # before the first impact (t < 1.43) the height is 10 - g t^2 / 2 >= 5.095 at t = 1
    lo, _ = by_object.hull()
    assert 5.0 < lo[0] < 5.1


def test_the_flags_reach_the_settings(tmp_path: Path, ball: hybrid.Automaton) -> None:
    events = tmp_path / "events.json"
    done = run_cli(
        "simulate", BALL, "--t-end", "4", "--rtol", "1e-10", "--atol", "1e-12",
        "--max-jumps", "1", "--events", events, "--quiet",
    )  # fmt: skip
    assert done.returncode == 1, done.stderr  # max_jumps: not t_end
    written = json.loads(events.read_text())
    run = hybrid.simulate(ball, 4.0, rtol=1e-10, atol=1e-12, max_jumps=1)
    assert [j["t"] for j in written["jumps"]] == [j.t for j in run.jumps]
    assert written["termination"]["t"] == run.termination.t  # the second impact, not taken
    assert written["settings"]["rtol"] == 1e-10 and written["settings"]["max_jumps"] == 1
    default = hybrid.simulate(ball, 4.0, max_jumps=1)
    assert [j["t"] for j in written["jumps"]] != [j.t for j in default.jumps]


def test_the_flags_reach_a_sweep(tmp_path: Path, ball: hybrid.Automaton) -> None:
    out = tmp_path / "results.csv"
    done = run_cli(
        "sweep", BALL, "--t-end", "2", "--grid", "e=0.5:0.9:2", "--summary", "jump_t:1",
        "--rtol", "1e-3", "--atol", "1e-3", "--workers", "0", "--out", out, "--quiet",
        "--backend", "scipy",  # auto (the default) may choose differently in each process
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    header, *lines = out.read_text().splitlines()
    column = header.split(",").index("jump_t:1")
    from_cli = [float(line.split(",")[column]) for line in lines]
    table = hybrid.sweep(
        ball, 2.0, grid={"e": [0.5, 0.9]}, summaries=["jump_t:1"], workers=0, rtol=1e-3, atol=1e-3,
        backend="scipy",
    )
    assert from_cli == [row["jump_t:1"] for row in table.rows]
    fine = hybrid.sweep(
        ball, 2.0, grid={"e": [0.5]}, summaries=["jump_t:1"], workers=0, backend="scipy", **FINE
    )
    assert from_cli[0] != fine.rows[0]["jump_t:1"]  # the coarse tolerance changed the run


def test_the_cli_builds_its_settings_in_one_place() -> None:
    import argparse

    from hybrid.cli.main import build_parser
    from hybrid.cli.settings import settings_from

    parser = build_parser()
    flags = ["--t-end", "2", "--rtol", "1e-8", "--max-step", "0.5", "--dt", "0.25"]
    for command in (["simulate", "x.yaml"], ["sweep", "x.yaml", "--out", "r.csv"],
                    ["falsify", "x.yaml", "--requirement", "r"]):  # fmt: skip
        args: argparse.Namespace = parser.parse_args([*command, *flags, "--backend", "compiled"])
        assert settings_from(args) == hybrid.Settings(
            t_end=2.0, rtol=1e-8, max_step=0.5, dt=0.25, backend="compiled"
        )
        defaults = settings_from(parser.parse_args([*command, "--t-end", "2"]))
        assert defaults == hybrid.Settings(t_end=2.0)

    # the flags are declared once: every command has the same ones, with the same defaults
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    flags = {"--t-end", "--max-jumps", "--rtol", "--atol", "--max-step", "--method", "--dt"}
    declared = {
        name: {(a.option_strings[0], a.default, tuple(a.choices or ())) for a in
               sub.choices[name]._actions if a.option_strings and a.option_strings[0] in flags}
        for name in ("simulate", "sweep", "falsify")
    }  # fmt: skip
    assert len(declared["simulate"]) == len(flags)
    assert declared["simulate"] == declared["sweep"] == declared["falsify"]


def test_numpy_numbers_in_the_settings_are_written_to_the_events_file(
    ball: hybrid.Automaton, tmp_path: Path
) -> None:
    # t_end=np.int64(3) is kept as given, and write_events failed in the json module
    from hybrid.export import write_events

    given = {"t_end": np.int64(3), "t_start": np.float32(0.5), "max_jumps": np.int64(50),
             "rtol": np.float32(1e-6), "max_step": np.float64(0.25), "dt": np.float16(0.5),
             "max_jumps_per_instant": np.int32(20)}  # fmt: skip
    run = hybrid.simulate(ball, **given)
    write_events(run, tmp_path / "events.json")
    written = json.loads((tmp_path / "events.json").read_text())["settings"]
    assert {name: written[name] for name in given} == {k: v.item() for k, v in given.items()}


def test_the_settings_a_run_recorded_make_the_same_run_again(ball: hybrid.Automaton) -> None:
    # run.settings writes max_step None ("not limited"), which Settings refused
    run = hybrid.simulate(ball, t_end=3.0, rtol=1e-9, atol=1e-11)
    recorded = {k: v for k, v in run.settings.items() if k != "start"}
    assert recorded["max_step"] is None
    again = hybrid.simulate(ball, settings=hybrid.Settings(**recorded))
    assert again.settings == run.settings and again.t.tolist() == run.t.tolist()
    assert hybrid.Settings(t_end=1.0, max_step=None).max_step == math.inf
