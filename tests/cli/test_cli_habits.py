"""Messages for the habits people bring from C, MATLAB and YAML elsewhere, from the real command.

Each row is a mistake an engineer makes on a first try, the place the message must
point at (counted by hand in the spec below) and what it must say. The specs are
checked by ``python -m hybrid validate`` in a fresh process; the Python API's
mistakes by ``python -c`` (a user's script).
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from support import REPO, assert_no_traceback, run_cli

# The guard's value starts at column 12 of line 12 ("    guard: " is 11 characters).
SPEC = """\
automaton: habits
parameters: {k: 1.0}
state:
  h: {initial: 1.0}
  v: {initial: 0.0}
locations:
  a:
    flow: {h: v, v: -1}
edges:
  - from: a
    to: a
    guard: GUARD
"""

GUARDS = [
    # (guard as typed, column of the culprit, what the message says)
    ("h = 0", 14, "'=' assigns; to compare, use '=='"),
    ("h => 0", 14, "'=>' is not a comparison: write '>='"),
    ("h <= 0 && v < 0", 19, "'&&' is not an operator here: write 'and'"),
    ("h <= 0 || v < 0", 19, "'||' is not an operator here: write 'or'"),
    ("h ~= 0", 14, "'~=' is MATLAB's not-equal: write '!='"),
    ("!(h > 0)", 12, "'!' is not negation here (YAML reads it as a tag): write 'not'"),
    ("h <= 0 and !(v > 0)", 23, "'!' is not negation here: write 'not'"),
    ("~(h > 0)", 12, "'~' is not negation here: write 'not'"),
    ("!v", 12, "YAML tags (!v) are not allowed in specs; if '!' meant negation, write 'not'"),
    # MATLAB's element-wise operators, modulo, an unfinished exponent, a product of conditions:
    # each said only "syntax error", "'%' is not supported" or "not a product"
    ("h .* v <= 0", 14, "'.*' is MATLAB's element-wise product: write '*'"),
    ("h.^2 <= 0", 13, "'.^' is MATLAB's element-wise power: write '**'"),
    ("h % 2 <= 0", 12, "'%' is not supported: there is no modulo; write x - m * floor(x / m)"),
    ("h >= 3.0e", 17, "'3.0e' is not a number: an exponent needs its digits (3.0e3), a product its '*' (3.0 * e)"),
    ("(h <= 0) * (v < 0) > 0", 13, "expected a number here, got a condition (conditions join "
     "with 'and' and 'or'; a value that depends on a condition is a location's signal)"),
    # YAML's non-specific tag: read as 'v > 0' without a word until this was refused
    ("! v > 0", 12, "'!' is not negation here (YAML reads '! ' as a tag and drops it): write 'not'"),
]


@pytest.mark.parametrize(("guard", "column", "message"), GUARDS, ids=[g for g, _, _ in GUARDS])
def test_an_operator_from_c_or_matlab_is_named(
    guard: str, column: int, message: str, tmp_path: Path
) -> None:
    spec = tmp_path / "habits.yaml"
    spec.write_text(SPEC.replace("GUARD", guard))
    result = run_cli("validate", spec)
    assert result.returncode == 2
    assert_no_traceback(result.stderr)
    assert result.stderr.strip() == f"{spec}:12:{column}: {message}"


# The flow of v starts at column 22 of line 8 ("    flow: {h: v, v: '" is 21 characters).
FLOWS = [
    # (flow of v as typed, column of the culprit, what the message says)
    ("2h", 22, "'2h' is not a product here: write '2 * h'"),
    ("-1.5e-2v + 1", 23, "'1.5e-2v' is not a product here: write '1.5e-2 * v'"),
    ("h;", 23, "';' ends nothing here: an expression is one line without it"),
    ("pow(h, 2)", 22, "unknown function 'pow': write a ** b for pow(a, b)"),
    ("-mod(h, k)", 23, "unknown function 'mod': there is no modulo function: "
                       "for MATLAB's mod(x, m) write x - m * floor(x / m)"),
    ("ln(h)", 22, "unknown function 'ln': log is the natural logarithm: write log(x)"),
    ("h(1)", 22, "'h' is a state variable, not a function: write h"),
    ("-k(1)", 23, "'k' is a parameter, not a function: write k"),
    ("t(1)", 22, "'t' is the time, not a function: write t"),
]  # fmt: skip


@pytest.mark.parametrize(("flow", "column", "message"), FLOWS, ids=[f for f, _, _ in FLOWS])
def test_a_function_or_literal_from_c_or_matlab_is_named(
    flow: str, column: int, message: str, tmp_path: Path
) -> None:
    """MATLAB's and C's spellings of products, functions and indexing: before, '2h' was
    Python's "invalid decimal literal", pow and mod "unknown function" and h(1) "unknown
    function 'h'"."""
    spec = tmp_path / "flows.yaml"
    spec.write_text(SPEC.replace("GUARD", "h <= 0").replace("v: -1}", f"v: '{flow}'}}"))
    result = run_cli("validate", spec)
    assert result.returncode == 2
    assert_no_traceback(result.stderr)
    assert result.stderr.strip() == f"{spec}:8:{column}: {message}"


def test_the_operators_we_spell_that_way_still_parse(tmp_path: Path) -> None:
    spec = tmp_path / "ours.yaml"
    spec.write_text(
        SPEC.replace("GUARD", "h == 0 or (h != 1 and not v >= 0 and h <= k)").replace(
            "v: -1}", "v: '-1e-3*h + 2.5e+2 * v + .5 - 1.e1'}"
        )
    )
    result = run_cli("validate", spec)
    assert (result.returncode, result.stderr) == (0, "")


YAML = [
    # (spec text, line:column, message)
    (
        SPEC.replace("GUARD", "h <= 0").replace("  h: {initial", "\th: {initial"),
        "4:1",
        "invalid YAML: a tab: YAML indents with spaces only (replace the tab with spaces)",
    ),
    (
        SPEC.replace("GUARD", "h <= 0").replace("    flow:", "\tflow:"),
        "8:1",
        "invalid YAML: a tab: YAML indents with spaces only (replace the tab with spaces)",
    ),
    (
        SPEC.replace("GUARD", "h <= 0") + "    reset: {h: max(h, 0)}\n",
        "13:16",
        "a comma cut 'max(h, 0)' in two: inside {...} or [...] a comma ends the entry; "
        "quote it: h: 'max(h, 0)'",
    ),
    (
        SPEC.replace("    guard: GUARD\n", "  - {from: a, to: a, guard: min(h, v) <= 0}\n").replace(
            "  - from: a\n    to: a\n", ""
        ),
        "10:29",
        "a comma cut 'min(h, v) <= 0' in two: inside {...} or [...] a comma ends the entry; "
        "quote it: guard: 'min(h, v) <= 0'",
    ),
]


@pytest.mark.parametrize(
    ("text", "where", "message"), YAML, ids=["tab", "tab-deep", "reset", "guard"]
)
def test_a_yaml_pitfall_is_named(text: str, where: str, message: str, tmp_path: Path) -> None:
    spec = tmp_path / "pitfall.yaml"
    spec.write_text(text)
    result = run_cli("validate", spec)
    assert result.returncode == 2
    assert_no_traceback(result.stderr)
    assert result.stderr.strip() == f"{spec}:{where}: {message}"


def test_the_quoted_form_the_message_offers_is_accepted(tmp_path: Path) -> None:
    spec = tmp_path / "quoted.yaml"
    spec.write_text(SPEC.replace("GUARD", "h <= 0") + "    reset: {h: 'max(h, 0)'}\n")
    result = run_cli("validate", spec)
    assert (result.returncode, result.stderr) == (0, "")


PYTHON = [
    (
        'run = hybrid.simulate(model, t_end=1.0)\nrun["h3"]',
        "hybrid.errors.UnknownName: no state variable or signal 'h3'; did you mean 'h'?",
    ),
    (  # another case: difflib alone finds 'H' no closer to 'h' than to 'v'
        'run = hybrid.simulate(model, t_end=1.0)\nrun["H"]',
        "hybrid.errors.UnknownName: no state variable or signal 'H'; did you mean 'h'?",
    ),
    (
        'hybrid.simulate(model, t_end="10")',
        "t_end must be a finite time after t_start=0.0, got the string '10': "
        "pass a number, not text",
    ),
    (
        'hybrid.simulate(model, t_end=10.0, rtol="1e-6")',
        "rtol must be a number, got the string '1e-6': pass a number, not text",
    ),
]


@pytest.mark.parametrize(("code", "said"), PYTHON, ids=["did-you-mean", "another-case", "t_end", "rtol"])
def test_a_python_mistake_is_named(code: str, said: str) -> None:
    import subprocess

    script = f"import hybrid\nmodel = hybrid.load('specs/bouncing_ball.yaml')\n{code}\n"
    result = subprocess.run(
        [sys.executable, "-c", script],
        cwd=REPO,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert result.returncode == 1
    assert result.stderr.strip().splitlines()[-1].endswith(said), result.stderr


FLAGS = [
    # (words after the spec, the one error line)
    (["--tend", "5"], "unrecognized argument --tend; did you mean '--t-end'?"),
    (["--t_end=5"], "unrecognized argument --t_end=5; did you mean '--t-end'?"),
    (["--t-end", "5", "-o", "x.csv"], "unrecognized argument -o; did you mean '--out'?"),
    (["--t-end", "5", "--set", "e=0.5"], "unrecognized argument --set; did you mean '--param'?"),
    (["--t-end", "5", "--x0", "h=3"], "unrecognized argument --x0; did you mean '--init'?"),
    (["--t-end", "5", "--RelTol", "1e-8"], "unrecognized argument --RelTol; did you mean '--rtol'?"),
    (["--t-end", "5", "--max_jumps", "3"],
     "unrecognized argument --max_jumps; did you mean '--max-jumps'?"),
    (["--t-end", "5", "--rtool", "1e-8"], "unrecognized argument --rtool; did you mean '--rtol'?"),
    (["--t-end", "5", "--zzz"], "unrecognized argument --zzz"),
    # no abbreviations: this one was taken as --initial-location h=2
    (["--t-end", "5", "--initial", "h=2"], "unrecognized argument --initial; did you mean '--init'?"),
    (["--t-end", "5", "--max-j", "3"], "unrecognized argument --max-j; did you mean '--max-jumps'?"),
    (["--t-end", "5", "--method", "ode45"],
     "argument --method: MATLAB's ode45 is 'RK45' here (the same Dormand-Prince 5(4) pair)"),
    (["--t-end", "5", "--method", "ode15s"],
     "argument --method: MATLAB's ode15s is 'BDF' here (the nearest: variable-order BDF for "
     "stiff flows)"),
    (["--t-end", "5", "--backend", "numba"],
     "argument --backend: invalid choice: 'numba' (choose from 'scipy', 'compiled', 'auto'); "
     "did you mean 'compiled'?"),
]  # fmt: skip


@pytest.mark.parametrize(("words", "said"), FLAGS, ids=[" ".join(w) for w, _ in FLAGS])
def test_a_flag_from_another_tool_is_named_with_ours(
    words: list[str], said: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """Before, '--tend 5' said only that --t-end is required, '-o' and '--RelTol' were
    "unrecognized arguments" without a hint, and MATLAB's ode45 an invalid choice."""
    from support import SPECS, main_in_process

    assert main_in_process("simulate", SPECS / "bouncing_ball.yaml", *words) == 2
    captured = capsys.readouterr()
    assert (captured.out, captured.err) == ("", f"hybrid: error: {said}\n")


def test_a_falsify_given_a_grid_is_pointed_at_vary(capsys: pytest.CaptureFixture[str]) -> None:
    """Before: "did you mean '--dt'?" (difflib's closest flag of falsify)."""
    from support import SPECS, main_in_process

    words = ["--grid", "e=0:1:5", "--t-end", "5"]
    assert main_in_process("falsify", SPECS / "bouncing_ball.yaml", *words) == 2
    captured = capsys.readouterr()
    assert captured.err == "hybrid: error: unrecognized argument --grid; did you mean '--vary'?\n"


def test_a_mistyped_command_is_named_in_a_real_process() -> None:
    result = run_cli("simulat", "specs/bouncing_ball.yaml", "--t-end", "1")
    assert result.returncode == 2
    assert_no_traceback(result.stderr)
    assert result.stderr.strip().endswith("; did you mean 'simulate'?")


def test_the_python_api_names_matlab_solvers_too() -> None:
    import hybrid
    from hybrid.errors import UsageError

    with pytest.raises(UsageError, match=r"unknown method 'ode23': MATLAB's ode23 is 'RK23'"):
        hybrid.simulate(hybrid.load(REPO / "specs" / "bouncing_ball.yaml"), t_end=1.0,
                        method="ode23")  # fmt: skip


def test_import_and_export_given_the_other_direction_say_which_to_use(tmp_path: Path) -> None:
    """Before: importing a YAML spec said "malformed XML: not well-formed", and exporting a
    SpaceEx model read the .xml as a spec."""
    spec = REPO / "specs" / "bouncing_ball.yaml"
    model = REPO / "tests" / "data" / "spaceex" / "bball" / "bball.xml"
    done = run_cli("import", "spaceex", spec, "--out", tmp_path / "imported")
    assert done.returncode == 2 and not (tmp_path / "imported").exists()
    assert done.stderr.strip() == (
        f"{spec}: import reads a SpaceEx model (.xml); to write this spec as one, use "
        f"hybrid export spaceex {spec} --out MODEL.xml"
    )
    done = run_cli("export", "spaceex", model, "--out", tmp_path / "out.xml")
    assert done.returncode == 2 and not (tmp_path / "out.xml").exists()
    assert done.stderr.strip() == (
        f"{model}: export writes a spec as SpaceEx; to read this SpaceEx model, use "
        f"hybrid import spaceex {model} --out DIR"
    )
    # the configuration in the model's place: before, a note that it would use the .cfg
    # as its own configuration, then "malformed XML" at 1:2
    cfg = model.with_suffix(".cfg")
    done = run_cli("import", "spaceex", cfg, "--out", tmp_path / "imported")
    assert done.returncode == 2 and not (tmp_path / "imported").exists()
    assert done.stderr.strip() == (
        f"{cfg}: this is a SpaceEx configuration (.cfg); give the model (.xml) first: "
        f"hybrid import spaceex {model} --cfg {cfg}"
    )


def test_initial_location_on_a_system_names_the_flag_and_where_to_set_it() -> None:
    """Before: the API's words, "initial_location applies to an automaton"."""
    system = REPO / "specs" / "uvms_mission_2.yaml"
    done = run_cli("simulate", system, "--t-end", "1", "--initial-location", "q1")
    assert done.returncode == 2
    assert_no_traceback(done.stderr)
    assert done.stderr.strip() == (
        f"{system}: --initial-location applies to an automaton; in a system each "
        "component's initial location is set in the system file (initial: {location: ...})"
    )


def test_a_grid_written_start_step_stop_names_the_grid_meant(tmp_path: Path) -> None:
    """MATLAB's 0.5:0.1:0.9 (start:step:stop) is five values: LO:HI:N 0.5:0.9:5 here."""
    out = tmp_path / "runs.csv"
    spec = REPO / "specs" / "bouncing_ball.yaml"
    done = run_cli("sweep", spec, "--grid", "e=0.5:0.1:0.9", "--t-end", "5", "--out", out)
    assert done.returncode == 2 and not out.exists()
    assert_no_traceback(done.stderr)
    assert done.stderr.strip() == (
        f"{spec}: 'e=0.5:0.1:0.9': N must be a whole number (LO:HI:N: N values from LO to "
        "HI; MATLAB's start:step:stop 0.5:0.1:0.9 is e=0.5:0.9:5)"
    )



@pytest.mark.parametrize(("grid", "said"), [
    ("e=0:0.1:1", "N = 1 takes LO alone (LO:HI:N: N values from LO to HI; MATLAB's "
                  "start:step:stop 0:0.1:1 is e=0:1:11)"),
    ("e=1:0.1:2", "the range is empty (LO > HI) (LO:HI:N: N values from LO to HI; MATLAB's "
                  "start:step:stop 1:0.1:2 is e=1:2:11)"),
    ("e=0.5:0.9:1", "N = 1 takes LO alone (LO:HI:N: N values from LO to HI; MATLAB's "
                    "start:step:stop 0.5:0.9:1 is e=0.5:0.5:1)"),
])  # fmt: skip
def test_a_start_step_stop_grid_of_whole_stop_is_refused(grid: str, said: str,
                                                         tmp_path: Path) -> None:  # fmt: skip
    """MATLAB's 0:0.1:1 read as LO:HI:N was one run at e = 0 (0 to 0.1, one value), exit 0;
    1:0.1:2 said only that the range was empty. A grid of one value across a range is
    refused from Python too (``{"init.h": 1}`` over a declared set was its low end)."""
    out = tmp_path / "runs.csv"
    spec = REPO / "specs" / "bouncing_ball.yaml"
    done = run_cli("sweep", spec, "--grid", grid, "--t-end", "5", "--out", out)
    assert done.returncode == 2 and not out.exists()
    assert_no_traceback(done.stderr)
    assert done.stderr.strip() == f"{spec}: '{grid}': {said}"
    from hybrid.campaigns.space import Axis
    from hybrid.errors import UsageError

    with pytest.raises(UsageError, match=r"one grid value across \[0, 0.1\] would be LO"):
        Axis.of("e", 0.0, 0.1, 1)
    assert Axis.of("e", 0.5, 0.5, 1).values() == [0.5]  # one value, given as such


def test_an_unknown_name_in_a_campaign_is_placed_as_simulate_places_it(tmp_path: Path) -> None:
    """Before: sweep and falsify said "FILE: f: unknown parameter 'f' ..." without the place
    that simulate gives for the same name."""
    spec = REPO / "specs" / "bouncing_ball.yaml"
    alone = run_cli("simulate", spec, "--t-end", "1", "--param", "f=0.5")
    swept = run_cli("sweep", spec, "--t-end", "1", "--grid", "f=0.5:0.9:3", "--out",
                    tmp_path / "r.csv")  # fmt: skip
    searched = run_cli("falsify", spec, "--t-end", "1", "--vary", "f=0:1", "--requirement", "x")
    assert alone.stderr.startswith(f"{spec}:2:1: unknown parameter 'f'")
    for done in (alone, swept, searched):
        assert done.returncode == 2
        assert done.stderr == alone.stderr
