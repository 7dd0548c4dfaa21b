"""``hybrid reach`` and ``hybrid check`` with reach, as a user runs them.

Exit codes of the contract: 0 every entry proved, 1 one refuted, 3 none refuted
and one unknown, 2 invalid input (a model that is not affine, an output that
cannot be written: refused before the work). The heater below reaches at most
``3 / 0.7 = 4.2857`` (x0 <= 2, u <= 1.5: ``x = x0 e^{-0.7 t} + (3/0.7)(1 - e^{-0.7 t})``),
so ``x > 4.3`` is proved and ``x > 4`` refuted (from t = 2.97).
"""

from __future__ import annotations

import importlib
import json
import math
import re
import sys
from pathlib import Path
from typing import Any

import jsonschema
import numpy as np
import pytest
from support import REPO, FakeTerminal, assert_no_traceback, main_in_process, read_csv, run_cli

import hybrid
from hybrid.progress import Status, Tracker

HEATER = """automaton: heater
state: {x: {initial: [1, 2]}}
inputs: {u: {range: [0.5, 1.5]}}
locations: {on: {flow: {x: -0.7 * x + 2 * u}}}
properties:
  forbidden:
    - {when: x > 4.3}
"""
REFUTED = HEATER + "    - {when: x > 4.0}\n"
# `go` fires as soon as x reaches 1 (the simulator's semantics); reach's may-semantics
# lets `a` flow on, so it meets x > 1.5 in `a` and no run does: unknown
UNKNOWN = """automaton: early
state: {x: {initial: 0}}
locations: {a: {flow: {x: 1}}, b: {flow: {x: 0}}}
edges: [{name: go, from: a, to: b, guard: x >= 1}]
properties: {forbidden: [{location: a, when: x > 1.5}]}
"""
NONLINEAR = """automaton: sq
state: {x: {initial: 1}}
locations: {l: {flow: {x: x * x}}}
"""


def _spec(tmp_path: Path, text: str, name: str = "m.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def test_exit_codes_follow_the_verdicts(tmp_path: Path) -> None:
    proved = run_cli("reach", _spec(tmp_path, HEATER, "p.yaml"), "--t-end", "6")
    assert proved.returncode == 0, proved.stderr
    assert "p.yaml:7:7: proved: forbidden state 'x > 4.3' is never reached" in proved.stdout
    refuted = run_cli("reach", _spec(tmp_path, REFUTED, "r.yaml"), "--t-end", "6")
    assert refuted.returncode == 1, refuted.stderr
    assert "r.yaml:8:7: refuted: forbidden state 'x > 4.0' is reached at t = " in refuted.stdout
    unknown = run_cli("reach", _spec(tmp_path, UNKNOWN, "u.yaml"), "--t-end", "3")
    assert unknown.returncode == 3, unknown.stderr
    assert "unknown: forbidden state 'a with x > 1.5' may be reached" in unknown.stdout
    assert re.search(r"meets it from t = 1\.49\d*,", unknown.stdout), unknown.stdout


def test_a_model_with_no_forbidden_entry_is_not_said_proved(tmp_path: Path) -> None:
    """Nothing to decide: the sets are computed, exit 0, and the summary does not say
    "proved" (it did: a user read it as a proof of something)."""
    plain = HEATER.split("properties:")[0]
    done = run_cli("reach", _spec(tmp_path, plain, "n.yaml"), "--t-end", "6")
    assert done.returncode == 0, done.stderr
    (line,) = done.stdout.splitlines()
    assert line.startswith(f"{tmp_path / 'n.yaml'}: no forbidden state to decide (properties: forbidden): ")
    assert "proved" not in line and "t <= 6," in line


def test_a_proof_the_jump_bound_cut_short_says_so_in_reach_and_check(tmp_path: Path) -> None:
    """'proved ... within t <= 60 and 10 jumps' and check's 'ok' read as proved to t = 60;
    jump 11 may come from t = 32.5 (closed form in test_reach_closed_forms)."""
    from test_reach_closed_forms import THERMO_CYCLES

    spec = _spec(tmp_path, THERMO_CYCLES, "cycles.yaml")
    done = run_cli("reach", spec, "--t-end", "60")
    assert done.returncode == 0, done.stderr
    verdict, summary = done.stdout.splitlines()
    assert "(a run may take jump 11 from t = 32." in verdict
    assert summary.endswith("(jump 11 may come from t = 32.44 on: not covered)"), summary
    checked = run_cli("check", spec, "--reach-t-end", "60")
    assert checked.returncode == 0, checked.stderr
    assert "within t <= 60 and 10 jumps; jump 11 may come from t = 32.44 on, not covered" in (
        checked.stdout
    )
    covered = run_cli("reach", spec, "--t-end", "60", "--max-jumps", "20")
    assert "not covered" not in covered.stdout


def test_a_model_that_is_not_affine_is_refused_at_its_place(tmp_path: Path) -> None:
    done = run_cli("reach", _spec(tmp_path, NONLINEAR), "--t-end", "1")
    assert done.returncode == 2
    assert_no_traceback(done.stderr)
    assert "m.yaml:3:27: the flow of x in location 'l' is not affine" in done.stderr
    assert "'x * x'" in done.stderr


@pytest.mark.parametrize(("flow", "named"), [
    ("sin(t) + x", "'sin(t)'"), ("abs(x)", "'abs(x)'"), ("x ** 2", "'x ** 2'"),
])  # fmt: skip
def test_what_is_not_affine_is_named_as_written(flow: str, named: str) -> None:
    """The message quoted generated code: '_sin(t)', '_abs(x)', '_pow(x, 2.0)'."""
    text = f"automaton: m\nstate: {{x: {{initial: [0, 1]}}}}\nlocations: {{l: {{flow: {{x: {flow}}}}}}}\n"
    with pytest.raises(hybrid.SpecError, match="not affine") as raised:
        hybrid.reach(hybrid.load_text(text), 1.0)
    assert f"not affine in the state and inputs: {named};" in str(raised.value)


def test_a_power_of_one_or_zero_is_affine() -> None:
    """x ** 1 was refused as not affine. x' = x ** 1 + 0 * x ** 0 from [0, 1]: the sets'
    hull at t = 1 reaches e (closed form x0 e^t)."""
    text = "automaton: m\nstate: {x: {initial: [0, 1]}}\nlocations: {l: {flow: {x: x ** 1 + 0 * x ** 0}}}\n"
    lo, hi = hybrid.reach(hybrid.load_text(text), 1.0).hull()
    assert lo[0] <= 0.0 and math.e <= hi[0] <= math.e * (1 + 1e-6)


def test_a_horizon_is_needed_and_read_from_the_spec(tmp_path: Path) -> None:
    done = run_cli("reach", _spec(tmp_path, HEATER))
    assert done.returncode == 2 and "--t-end" in done.stderr
    done = run_cli("reach", _spec(tmp_path, HEATER + "checks: {reach: {t_end: 6}}\n", "h.yaml"))
    assert done.returncode == 0, done.stderr
    assert "t <= 6," in done.stdout


@pytest.mark.parametrize("step", ["1e-300", "1e-12", "1e-7"])
def test_a_step_too_small_to_finish_is_refused_at_once(tmp_path: Path, step: str) -> None:
    """t_end / step over a million steps a flowpipe: one line and exit 2, not a traceback
    (1e-300 and 1e-12 overflowed numpy's arrays) or a run that never ends (1e-7)."""
    done = run_cli("reach", _spec(tmp_path, HEATER), "--t-end", "1", "--step", step, timeout=30)
    assert done.returncode == 2, done.stderr
    assert f"step={float(step):g} gives {1 / float(step):.3g} steps to t_end=1" in done.stderr
    assert_no_traceback(done.stderr)
    with pytest.raises(hybrid.UsageError, match="the limit is 1e\\+06 a flowpipe"):
        hybrid.reach(hybrid.load(_spec(tmp_path, HEATER)), t_end=1.0, step=float(step))


def test_a_step_that_is_not_a_number_is_a_usage_error(tmp_path: Path) -> None:
    with pytest.raises(hybrid.UsageError, match=r"step must be a finite number > 0, got '0\.1'"):
        hybrid.reach(hybrid.load(_spec(tmp_path, HEATER)), t_end=1.0, step="0.1")  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("flag", "value", "text"),
    [
        ("--sets", "/proc/sets.json", "cannot write"),
        ("--sets", "{tmp}", "is a directory"),
        ("--sets", "{tmp}/missing/sets.json", "does not exist"),
        ("--sets", "{tmp}/sets.txt", ".json or .npz"),
        ("--witness", "{tmp}/m.yaml", "not a directory"),
    ],
)
def test_outputs_that_cannot_be_written_are_refused_first(
    tmp_path: Path, flag: str, value: str, text: str
) -> None:
    spec = _spec(tmp_path, NONLINEAR)  # refused before the model is even read
    done = run_cli("reach", spec, "--t-end", "1", flag, value.replace("{tmp}", str(tmp_path)))
    assert done.returncode == 2
    assert text in done.stderr and "not affine" not in done.stderr
    assert_no_traceback(done.stderr)


def test_sets_files_hold_what_the_api_returns(tmp_path: Path) -> None:
    spec = _spec(tmp_path, HEATER)
    result = hybrid.reach(hybrid.load(spec), 2.0, step=0.01)
    for suffix in ("json", "npz"):
        out = tmp_path / f"sets.{suffix}"
        done = run_cli("reach", spec, "--t-end", "2", "--step", "0.01", "--sets", out)
        assert done.returncode == 0, done.stderr
        if suffix == "json":
            document = json.loads(out.read_text())
            assert document["variables"] == ["x"]
            sets = document["sets"]
            assert len(sets) == len(result.sets) == 201  # the initial box, then 200 steps
            assert sets[7]["location"] == "on" and sets[7]["t"] == list(result.sets[7].t)
            assert sets[7]["lo"] == result.sets[7].lo.tolist()
        else:
            with np.load(out) as data:
                assert data["lo"].shape == (201, 1) and data["t"].shape == (201, 2)
                assert np.array_equal(data["hi"][:, 0], [s.hi[0] for s in result.sets])
                assert set(data["location"].tolist()) == {"on"}


def test_witness_files_replay_the_refutation(tmp_path: Path) -> None:
    spec = _spec(tmp_path, REFUTED)
    folder = tmp_path / "witness"
    done = run_cli("reach", spec, "--t-end", "6", "--witness", folder)
    assert done.returncode == 1, done.stderr
    overrides = json.loads((folder / "witness-2.overrides.json").read_text())
    assert 1.0 <= overrides["initial"]["state"]["x"] <= 2.0
    steps = overrides["inputs"]["u"]
    assert all(0.5 <= v <= 1.5 for _, v in steps)
    header, rows = read_csv(folder / "witness-2.csv")
    assert header[:4] == ["t", "j", "location", "x"]
    assert max(float(r["x"]) for r in rows) > 4.0
    events = json.loads((folder / "witness-2.events.json").read_text())
    assert events["termination"]["cause"] == "t_end"
    assert not (folder / "witness-1.csv").exists()  # the proved entry has none


def test_report_formats_are_those_of_check(tmp_path: Path) -> None:
    spec = _spec(tmp_path, REFUTED)
    done = run_cli("reach", spec, "--t-end", "6", "--format", "json")
    assert done.returncode == 1
    findings = json.loads(done.stdout)["findings"]
    assert [(f["rule"], f["severity"]) for f in findings] == [
        ("property-proved", "note"),
        ("property-violated", "error"),
    ]
    done = run_cli("reach", spec, "--t-end", "6", "--format", "sarif")
    schema = json.loads((REPO / "tests" / "data" / "sarif-schema-2.1.0.json").read_text())
    jsonschema.validate(json.loads(done.stdout), schema)
    done = run_cli("reach", spec, "--t-end", "6", "--format", "github")
    assert "::error file=" in done.stdout and "title=property-violated" in done.stdout


def test_structured_reports_fail_where_the_exit_code_does(tmp_path: Path) -> None:
    """An unknown exits 3, and the JSON said "ok": true, JUnit failures="0"; JUnit also
    passed eight graph rules reach never ran, in a suite named "hybrid check"."""
    import xml.etree.ElementTree as ET

    spec = _spec(tmp_path, UNKNOWN, "u.yaml")
    done = run_cli("reach", spec, "--t-end", "3", "--format", "json")
    assert done.returncode == 3 and json.loads(done.stdout)["ok"] is False
    done = run_cli("reach", spec, "--t-end", "3", "--format", "junit")
    assert done.returncode == 3
    root = ET.fromstring(done.stdout.split("?>", 1)[1])
    assert root.get("name") == "hybrid reach" and root.get("failures") == "1"
    names = {case.get("name", "").split(":")[0] for case in root.iter("testcase")}
    assert names == {"property-unproved", "property-proved", "property-violated"}
    proved = run_cli("reach", _spec(tmp_path, HEATER, "p.yaml"), "--t-end", "6", "--format", "json")
    assert proved.returncode == 0 and json.loads(proved.stdout)["ok"] is True


def test_plot_draws_the_sets(tmp_path: Path) -> None:
    pytest.importorskip("matplotlib")
    spec = _spec(tmp_path, REFUTED)
    fig = tmp_path / "fig.svg"
    done = run_cli("reach", spec, "--t-end", "6", "--plot", "t,x", "--out", fig)
    assert done.returncode == 1, done.stderr
    assert fig.read_text().lstrip().startswith("<?xml") and "<svg" in fig.read_text()
    bad = run_cli("reach", spec, "--t-end", "6", "--plot", "t,y", "--out", fig)
    assert bad.returncode == 2 and "'y' is not a state variable" in bad.stderr


def test_check_decides_forbidden_entries_with_reach(tmp_path: Path) -> None:
    proved = _spec(tmp_path, HEATER.replace("[1, 2]", "[1, 2], bounds: [0, 100]"), "p.yaml")
    plain = run_cli("check", proved)
    assert plain.returncode == 0 and "warning property-unproved" in plain.stdout
    with_reach = run_cli("check", proved, "--reach-t-end", "6")
    bounded = "ok (forbidden states: within t <= 6 and 10 jumps)"
    assert with_reach.returncode == 0 and with_reach.stdout.strip() == f"{proved}: {bounded}"
    in_spec = _spec(tmp_path, proved.read_text() + "checks: {reach: {t_end: 6}}\n", "s.yaml")
    assert run_cli("check", in_spec).stdout.strip() == f"{in_spec}: {bounded}"
    refuted = _spec(tmp_path, REFUTED + "checks: {reach: {t_end: 6}}\n", "r.yaml")
    done = run_cli("check", refuted)
    assert done.returncode == 1
    assert (
        "r.yaml:8:7: error property-violated: forbidden state 'x > 4.0' is reached" in done.stdout
    )


def test_a_step_the_bounds_overflow_at_is_refused_at_the_fastest_flow(tmp_path: Path) -> None:
    """|A| h = 1e6 * 0.1 for y: its flow is the place; x (slow) is not."""
    spec = _spec(
        tmp_path,
        "automaton: stiff\nstate:\n  x: {initial: 1.0}\n  y: {initial: 1.0}\n"
        "locations:\n  only:\n    flow:\n      x: -x\n      y: -1e6 * y\n",
    )
    with pytest.raises(hybrid.UsageError, match=r"overflow at step 0\.1") as caught:
        hybrid.reach(hybrid.load(spec), t_end=1.0, step=0.1)
    assert caught.value.at is not None
    assert (caught.value.at.line, caught.value.at.column) == (9, 10)  # "      y: -1e6 * y"
    done = run_cli("reach", spec, "--t-end", "1", "--step", "0.1")
    assert done.returncode == 2 and done.stderr.startswith(f"{spec}:9:10: the bounds of location")


def test_reach_reports_its_flowpipes_as_it_goes() -> None:
    """The ball from 10 m bounces once before t = 2 (at sqrt(20 / 9.81) = 1.43 s; the next
    is 2.28 s later): two flowpipes, the first bounce's the second. The last status counts
    them, the sets of the result, and nothing left waiting."""
    ball = hybrid.load(REPO / "specs" / "bouncing_ball.yaml")
    seen: list[Status] = []
    result = hybrid.reach(ball, t_end=2.0, max_jumps=3, step=0.001, progress=seen.append)
    last = seen[-1]
    assert last.final and last.task == "reach" and last.unit == "flowpipes"
    assert last.done == 2 and dict(last.counters) == {"sets": len(result.sets), "waiting": 0}
    assert {s.jumps for s in result.sets} == {0, 1}
    with pytest.raises(hybrid.UsageError, match="progress must be a function of a status"):
        hybrid.reach(ball, t_end=2.0, progress="yes")  # type: ignore[arg-type]


@pytest.mark.parametrize("quiet", [False, True])
def test_the_command_draws_its_progress_on_a_terminal_unless_quiet(
    monkeypatch: pytest.MonkeyPatch, quiet: bool
) -> None:
    """Drawn at every flowpipe here (a tracker without its 0.2 s spacing, so that the
    test does not depend on the machine's speed), and erased before the report."""

    class Eager(Tracker):
        def __init__(self, *args: Any, **kwargs: Any) -> None:
            super().__init__(*args, **{**kwargs, "interval": 0.0})

    api = importlib.import_module("hybrid.reach.api")  # hybrid.reach is also the function
    monkeypatch.setattr(api, "Tracker", Eager)
    terminal = FakeTerminal()
    monkeypatch.setattr(sys, "stderr", terminal)
    spec = REPO / "specs" / "bouncing_ball.yaml"
    code = main_in_process("reach", spec, "--t-end", "2", "--step", "0.001",
                           *(["--quiet"] if quiet else []))  # fmt: skip
    assert code == 0  # the ball declares no forbidden state: nothing to refute
    drawn = [part for part in terminal.getvalue().split("\r") if part.startswith("reach: ")]
    if quiet:
        assert drawn == [] and "\r" not in terminal.getvalue()
    else:
        assert [d.split(",")[0] for d in drawn] == ["reach: 1 flowpipes", "reach: 2 flowpipes"]
        assert terminal.getvalue().endswith("\r")  # erased


DOWN = """automaton: down
state:
  h: {initial: 5, bounds: [0, 12]}
locations:
  a: {flow: {h: -1}}
properties:
  forbidden:
    - {when: "h < -5"}
"""


@pytest.mark.parametrize("command", [("reach", "--t-end", "20"), ("check", "--reach-t-end", "20")])
def test_a_witness_leaving_its_bounds_is_one_warning_line(tmp_path: Path, command: tuple[str, ...]) -> None:
    # Python's own form of the BoundsWarning printed a line of the interpreter's code
    spec = tmp_path / "down.yaml"
    spec.write_text(DOWN)
    done = run_cli(command[0], spec, *command[1:])
    assert done.returncode == 1  # h < -5 is reached at t = 10 (h = 5 - t)
    warning = "hybrid: warning: h left its declared bounds [0, 12] at t="
    lines = done.stderr.splitlines()
    assert [line for line in lines if warning in line] == [line for line in lines if "warning" in line]
    assert any(line.startswith(warning) for line in lines), done.stderr
    assert "sys.exit" not in done.stderr and "BoundsWarning" not in done.stderr
    assert_no_traceback(done.stderr)


def test_a_jump_bound_without_a_horizon_is_a_note_not_silence(tmp_path: Path) -> None:
    # check --reach-max-jumps 3 on a spec with no reach horizon ran no reach and said nothing
    spec = tmp_path / "heater.yaml"
    spec.write_text(HEATER)
    done = run_cli("check", spec, "--reach-max-jumps", "3")
    assert done.returncode == 0, done.stderr
    assert done.stderr.strip() == (
        "hybrid: note: heater: reach_max_jumps (--reach-max-jumps) is not used: reach runs over "
        "a horizon, and none is given (reach_t_end, --reach-t-end, or checks: {reach: {t_end: "
        "...}} in the spec)"
    )
    with_horizon = run_cli("check", spec, "--reach-max-jumps", "3", "--reach-t-end", "1")
    assert "is not used" not in with_horizon.stderr


def test_the_nominal_run_drawn_over_the_sets_stays_in_them() -> None:
    """The ball's nominal run has a handful of step points (a parabola is exact for the
    integrator); drawn through them, its chords left the sets, as if the sets missed the
    run. Every drawn vertex, and the middle of every drawn segment, is in a set."""
    pytest.importorskip("matplotlib")
    import matplotlib.pyplot as plt

    ball = hybrid.load(REPO / "specs" / "bouncing_ball.yaml")
    result = hybrid.reach(ball, 3.0, max_jumps=2)
    ax = result.plot("t", "h")
    (line,) = [ln for ln in ax.get_lines() if ln.get_color() == "black"]
    t, h = (np.asarray(v, dtype=float) for v in line.get_data())
    t = np.concatenate([t, (t[1:] + t[:-1]) / 2])
    h = np.concatenate([h, (h[1:] + h[:-1]) / 2])
    k = list(result.variables).index("h")
    inside = np.zeros(t.size, dtype=bool)
    for s in result.sets:
        inside |= (s.t[0] - 1e-9 <= t) & (t <= s.t[1] + 1e-9) & (s.lo[k] - 1e-6 <= h) & (
            h <= s.hi[k] + 1e-6)  # fmt: skip
    assert inside.all(), (t[~inside][:3], h[~inside][:3])
    assert ax.get_title().endswith("no forbidden state to decide")
    plt.close("all")
