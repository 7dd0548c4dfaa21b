"""Mistakes in calls of the public functions are UsageErrors that say what to do.

The contract: every error a user can cause is a ``SpecError`` or a
``SimulationError`` (``UsageError`` is one); anything else escaping is a bug.
Each case here once escaped as an AttributeError, TypeError or ValueError.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from support import RELAY, SPECS

import hybrid
from hybrid.errors import CannotWrite, OutOfRange

BALL = hybrid.load(SPECS / "bouncing_ball.yaml")
THERMOSTAT = hybrid.load(SPECS / "thermostat.yaml")

CALLS: dict[str, Callable[[Any], Any]] = {
    "simulate": lambda m: hybrid.simulate(m, t_end=1.0),
    "check": lambda m: hybrid.check(m),
    "reach": lambda m: hybrid.reach(m, t_end=1.0),
    "sweep": lambda m: hybrid.sweep(m, t_end=1.0, grid={"e": [0.5]}, workers=0),
    "falsify": lambda m: hybrid.falsify(m, "low", t_end=1.0),
    "simulate_many": lambda m: hybrid.simulate_many(m, t_end=1.0),
    "compose": lambda m: hybrid.compose(m),
}


@pytest.mark.parametrize("name", sorted(CALLS))
def test_a_file_name_instead_of_a_model_says_to_load_it(name: str) -> None:
    path = str(SPECS / "bouncing_ball.yaml")
    with pytest.raises(hybrid.UsageError) as caught:
        CALLS[name](path)
    assert str(caught.value) == (
        f"{name}() takes a model from hybrid.load(), not a file name: "
        f"hybrid.{name}(hybrid.load({path!r}), ...)"
    )
    with pytest.raises(hybrid.UsageError, match="not a file name"):
        CALLS[name](SPECS / "bouncing_ball.yaml")  # a Path too


@pytest.mark.parametrize("name", sorted(CALLS))
@pytest.mark.parametrize("value", [None, [], 3.0])
def test_something_else_instead_of_a_model_names_what_it_got(name: str, value: object) -> None:
    with pytest.raises(hybrid.UsageError) as caught:
        CALLS[name](value)
    assert f"got {type(value).__name__}: {value!r}" in str(caught.value)


def test_compose_takes_automata_not_a_system() -> None:
    system = hybrid.compose(BALL, THERMOSTAT)
    with pytest.raises(hybrid.UsageError, match="is a system: compose the automata"):
        hybrid.compose(system)


@pytest.mark.parametrize("seed", [-1, 1.5, True, "3"])
def test_a_seed_is_a_whole_number_at_least_zero(seed: object) -> None:
    with pytest.raises(hybrid.UsageError, match=r"the seed must be a whole number >= 0"):
        hybrid.sweep(BALL, t_end=1.0, vary={"e": (0.1, 0.9)}, samples=3, seed=seed, workers=0)  # type: ignore[arg-type]
    with pytest.raises(hybrid.UsageError, match=r"the seed must be a whole number >= 0"):
        hybrid.falsify(BALL, "x", t_end=1.0, seed=seed, workers=0)  # type: ignore[arg-type]


def test_the_same_seed_gives_the_same_samples_and_zero_is_one() -> None:
    def drawn(seed: int) -> list[float]:
        table = hybrid.sweep(BALL, t_end=0.5, vary={"e": (0.1, 0.9)}, samples=4, seed=seed, workers=0)
        return [row["e"] for row in table.rows]

    assert drawn(0) == drawn(0) != drawn(1)
    assert all(0.1 <= e <= 0.9 for e in drawn(0))


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"grid": {"e": 0.5}}, "e: a grid gives a list of values or a count, got 0.5"),
        ({"grid": {"e": "0:1:3"}}, "e: a grid gives a list of values or a count, got '0:1:3'"),
        ({"grid": {"e": ["a"]}}, "e: grid values must be numbers, got ['a']"),
        ({"grid": [1, 2]}, "a grid item is an Axis or (name, N), got 1"),
        ({"grid": 7}, "grid must be a mapping {name: values or N} or a list, got 7"),
        ({"vary": {"e": (0.1, 0.9)}, "samples": "3"}, "the number of samples must be a whole number, got '3'"),
    ],
)
def test_a_sweep_given_the_wrong_kind_of_grid_or_samples_says_so(
    kwargs: dict[str, Any], message: str
) -> None:
    with pytest.raises(hybrid.UsageError) as caught:
        hybrid.sweep(BALL, t_end=1.0, workers=0, **kwargs)
    assert str(caught.value) == message


@pytest.mark.parametrize("value", [".nan", ".inf", "-.inf"])
def test_a_spec_parameter_that_is_not_finite_is_refused_where_it_is_written(value: str) -> None:
    text = f"automaton: a\nparameters:\n  k: 1.0\n  g: {value}\nstate:\n  x: {{initial: 0}}\nlocations: {{l: {{flow: {{x: k}}}}}}\n"
    with pytest.raises(hybrid.SpecError) as caught:
        hybrid.load_text(text, file="a.yaml")
    assert (caught.value.file, caught.value.line, caught.value.column) == ("a.yaml", 4, 6)
    assert "parameters.g: Input should be a finite number" in caught.value.message


@pytest.mark.parametrize(
    ("parameters", "message"),
    [
        ({"e": float("nan")}, "value of 'e' must be a finite number, got nan"),
        ({"e": "inf"}, "value of 'e' must be a finite number, got 'inf'"),
        ({1: 1.0}, "a parameter is named by a string, got 1"),
        ([("e", 1.0)], "parameters must be a mapping of names to numbers, got [('e', 1.0)]"),
    ],
)
def test_parameter_overrides_are_names_and_finite_numbers(parameters: Any, message: str) -> None:
    with pytest.raises(hybrid.SpecError) as caught:
        hybrid.load(SPECS / "bouncing_ball.yaml", parameters=parameters)
    assert caught.value.message == message
    system = hybrid.compose(BALL, THERMOSTAT)
    with pytest.raises(hybrid.SpecError):
        system.with_parameters(parameters)


def test_load_and_load_text_say_which_one_takes_what() -> None:
    text = "automaton: a\nlocations: {only: {}}\n"
    with pytest.raises(hybrid.UsageError, match=r"this is the text of one: use hybrid.load_text\(text\)"):
        hybrid.load(text)
    for one_line in ("automaton: a", "{automaton: a, locations: {only: {}}}", "  system: s"):
        with pytest.raises(hybrid.UsageError, match=r"this is the text of one"):
            hybrid.load(one_line)  # before: "cannot read file: not found"
    with pytest.raises(hybrid.UsageError, match="got NoneType: None"):
        hybrid.load(None)  # type: ignore[arg-type]
    with pytest.raises(hybrid.UsageError, match="load_text\\(\\) takes the YAML text as a str, got NoneType"):
        hybrid.load_text(None)  # type: ignore[arg-type]
    assert hybrid.load_text(text.encode()).name == "a"  # bytes read from a file: UTF-8
    assert hybrid.load(str(SPECS / "bouncing_ball.yaml").encode()).name == "bouncing_ball"  # type: ignore[arg-type]
    with pytest.raises(hybrid.SpecError, match="not UTF-8"):
        hybrid.load_text(b"automaton: \xff\n")  # type: ignore[arg-type]


def test_a_run_is_indexed_by_names_and_says_how_to_get_a_point() -> None:
    run = hybrid.simulate(BALL, t_end=1.0)
    assert run["h"][0] == 10.0  # dropped from 10 m
    with pytest.raises(hybrid.UsageError, match="did you mean 'energy'") as caught:
        run["enrgy"]
    assert isinstance(caught.value, KeyError)  # code that looks names up as in a dict
    with pytest.raises(hybrid.UsageError, match="'H'; did you mean 'h'"):
        run["H"]  # MATLAB's capitals
    with pytest.raises(hybrid.UsageError, match=r"run\.t\[k\], run\.states\[k\]"):
        run[0]  # type: ignore[index]


def test_a_run_answers_in_and_names_its_table_columns_and_says_it_is_not_iterated() -> None:
    # 'h' in run and list(run) said "got 0" (Python's fallback indexing by 0, 1, ...)
    run = hybrid.simulate(BALL, t_end=2.0)
    assert ["h" in run, "energy" in run, "t" in run, "x" in run, 0 in run] == [True, True, True, False, False]
    assert run["t"] is run.t and run["j"] is run.j and run["location"] is run.location
    assert list(run.to_pandas().columns[:3]) == ["t", "j", "location"]  # the same names
    for iterate in (list, iter, lambda r: [p for p in r]):
        with pytest.raises(TypeError, match="a run is not iterated: its columns are run"):
            iterate(run)


@pytest.mark.parametrize("backend", ["scipy", "compiled"])
@pytest.mark.parametrize("name", ["max_jumps", "max_jumps_per_instant"])
def test_a_count_beyond_64_bits_is_refused_on_both_backends(backend: str, name: str) -> None:
    if backend == "compiled":
        pytest.importorskip("numba")
    with pytest.raises(hybrid.UsageError, match=rf"{name} must be at most 4611686018427387904"):
        hybrid.simulate(BALL, t_end=1.0, backend=backend, **{name: 2**70})
    run = hybrid.simulate(BALL, t_end=2.0, backend=backend, handle_sigint=False, **{name: 2**62})
    assert run.termination.cause == "t_end" and len(run.jumps) == 1  # the bound itself is taken


def test_the_command_line_refuses_a_huge_max_jumps_with_exit_2() -> None:
    from support import assert_no_traceback, run_cli

    done = run_cli("simulate", SPECS / "bouncing_ball.yaml", "--t-end", "1", "--max-jumps",
                   str(10**23), "--backend", "compiled", "--quiet")  # fmt: skip
    assert done.returncode == 2 and "max_jumps must be at most" in done.stderr
    assert_no_traceback(done.stderr)


def test_numbers_too_large_for_a_float_and_text_are_named() -> None:
    with pytest.raises(hybrid.UsageError, match="got an integer of 401 digits"):
        hybrid.simulate(BALL, t_end=10**400)
    with pytest.raises(hybrid.UsageError, match=r"max_step must be > 0, got the string '0\.1'"):
        hybrid.simulate(BALL, t_end=1.0, max_step="0.1")  # type: ignore[arg-type]


TANK = """automaton: tank
state: {x: {initial: [0, 1]}}
locations: {fill: {flow: {x: 1}}}
properties:
  forbidden: [{location: fill, when: "x >= 12"}]
"""


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"reach_t_end": 0}, "reach_t_end must be a finite number > 0, got 0"),
        ({"reach_t_end": float("nan")}, "reach_t_end must be a finite number > 0, got nan"),
        ({"reach_t_end": "5"}, "reach_t_end must be a finite number > 0, got '5'"),
        ({"reach_step": 0.0}, "reach_step must be a finite number > 0, got 0.0"),
        ({"reach_max_jumps": -1}, "reach_max_jumps must be a whole number >= 0, got -1"),
        ({"max_states": "a"}, "max_states must be a whole number >= 1, got 'a'"),
        ({"max_bytes": 0}, "max_bytes must be a whole number >= 1, got 0"),
        ({"progress": 3}, "progress must be a function of a status, got 3"),
    ],
)
def test_check_refuses_what_the_command_line_refuses(kwargs: dict[str, Any], message: str) -> None:
    """reach_t_end=0 used to prove the tank's entry over [0, 0] and drop its warning."""
    tank = hybrid.load_text(TANK, file="tank.yaml")
    with pytest.raises(hybrid.UsageError) as caught:
        hybrid.check(tank, **kwargs)
    assert str(caught.value) == message


def test_check_reads_one_rule_to_ignore_as_one_rule() -> None:
    tank = hybrid.load_text(TANK, file="tank.yaml")
    assert [f.rule for f in hybrid.check(tank).findings] == ["property-unproved"]
    assert hybrid.check(tank, ignore="property-unproved").findings == ()


@pytest.mark.parametrize("t_end", [0, 0.0, -1.0, float("nan")])
def test_reach_needs_a_horizon_after_zero(t_end: float) -> None:
    tank = hybrid.load_text(TANK, file="tank.yaml")
    with pytest.raises(hybrid.UsageError, match="t_end must be a finite number > 0"):
        hybrid.reach(tank, t_end=t_end)


def _writers(tmp: Path) -> dict[str, Callable[[Any], Any]]:
    from hybrid.export import write_csv, write_events, write_mat, write_npz

    run = hybrid.simulate(BALL, t_end=1.0)
    return {
        "write_csv": lambda p: write_csv(run, p),
        "write_npz": lambda p: write_npz(run, p),
        "write_events": lambda p: write_events(run, p),
        "write_mat": lambda p: write_mat(run, p),
        "Run.plot": lambda p: run.plot(path=p),
        "SweepTable.write": lambda p: hybrid.sweep(BALL, t_end=0.5, grid={"e": [0.5]}, workers=0).write(p),
        "sweep(out=)": lambda p: hybrid.sweep(BALL, t_end=0.5, grid={"e": [0.5]}, workers=0, out=p),
        "write_sets": lambda p: hybrid.reach(BALL, t_end=0.5, step=0.01).write_sets(p),
    }


SUFFIX = {"write_csv": ".csv", "write_npz": ".npz", "write_events": ".json", "write_mat": ".mat",
          "Run.plot": ".png", "SweepTable.write": ".csv", "sweep(out=)": ".csv", "write_sets": ".json"}  # fmt: skip


@pytest.mark.parametrize("writer", sorted(SUFFIX))
def test_an_output_that_cannot_be_written_is_a_usage_error_and_an_os_error(
    writer: str, tmp_path: Path
) -> None:
    """A missing folder, /proc and a directory named like the file: nothing is written, and
    no temporary file is left beside the target."""
    if writer in ("Run.plot", "write_mat"):
        pytest.importorskip("matplotlib" if writer == "Run.plot" else "scipy.io")
    write = _writers(tmp_path)[writer]
    suffix = SUFFIX[writer]
    clash = tmp_path / f"taken{suffix}"
    clash.mkdir()
    for target in (tmp_path / "missing" / f"x{suffix}", Path(f"/proc/x{suffix}"), clash):
        with pytest.raises(CannotWrite) as caught:
            write(target)
        assert isinstance(caught.value, hybrid.UsageError) and isinstance(caught.value, OSError)
        assert str(caught.value).startswith("cannot write '")
    assert sorted(p.name for p in tmp_path.iterdir()) == [clash.name]  # nothing else there
    write(tmp_path / f"good{suffix}")  # and a good path is written
    assert (tmp_path / f"good{suffix}").exists()


def test_writers_say_what_they_take() -> None:
    from hybrid.export import write_csv, write_npz

    with pytest.raises(hybrid.UsageError, match="a file to write is named by a str or Path, got int"):
        write_csv(hybrid.simulate(BALL, t_end=1.0), 5)  # type: ignore[arg-type]
    with pytest.raises(hybrid.UsageError, match=r"write_npz\(\) writes a run from hybrid.simulate, got NoneType"):
        write_npz(None, "x.npz")  # type: ignore[arg-type]
    with pytest.raises(hybrid.UsageError, match="sets are written to a path or a binary file, got 3"):
        hybrid.reach(BALL, t_end=0.5, step=0.01).write_sets(3)  # type: ignore[arg-type]


def test_runs_compare_by_identity_not_by_their_arrays() -> None:
    first, second = (hybrid.simulate(BALL, t_end=3.0) for _ in range(2))
    assert first == first and first != second  # no "truth value of an array is ambiguous"
    assert first in [first] and second not in [first]


@pytest.mark.parametrize(
    ("index", "message"),
    [
        (3, "run 3 of an ensemble of 3 runs"),
        (-4, "run -4 of an ensemble of 3 runs"),
        (1.0, "runs are indexed by whole numbers or slices, got 1.0"),
        ("a", "runs are indexed by whole numbers or slices, got 'a'"),
        (None, "runs are indexed by whole numbers or slices, got None"),
    ],
)
def test_an_ensemble_index_it_does_not_have_is_out_of_range(index: Any, message: str) -> None:
    pytest.importorskip("numba")
    ensemble = hybrid.simulate_many(BALL, t_end=3.0, parameters={"e": [0.5, 0.6, 0.7]})
    for get in (ensemble.__getitem__, ensemble.model_of):
        with pytest.raises(OutOfRange) as caught:
            get(index)
        assert str(caught.value) == message and isinstance(caught.value, IndexError)
    first = 2 * 10.0 / 9.81  # sqrt of it: the first impact from 10 m, the same for every e
    assert ensemble[-1].jumps[0].t == pytest.approx(first**0.5, abs=1e-6)
    assert [run.jumps[0].t for run in ensemble[0:2]] == pytest.approx([first**0.5] * 2, abs=1e-6)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"parameters": {"e": []}}, "parameters: column 'e' is empty"),
        ({"parameters": {"e": ["a", "b"]}}, "parameters: column 'e' must be numbers, got ['a', 'b']"),
        ({"parameters": {"e": "0.5"}}, "parameters: column 'e' must be a list of numbers, got '0.5'"),
        ({"parameters": {"e": [float("nan"), 0.5]}},
         "parameters: column 'e' must be finite numbers, got nan in row 0"),
        ({"parameters": {"e": [[0.5, 0.6], [0.1, 0.2]]}},
         "parameters: column 'e' must be one list of numbers, got shape (2, 2)"),
        ({"parameters": {"e": [0.5]}, "threads": "two"}, "threads must be a whole number >= 1, got 'two'"),
        ({"parameters": {"e": [0.5]}, "threads": 0}, "threads must be a whole number >= 1, got 0"),
    ],
)
def test_simulate_many_refuses_a_table_it_cannot_run(kwargs: dict[str, Any], message: str) -> None:
    pytest.importorskip("numba")
    with pytest.raises(hybrid.UsageError) as caught:
        hybrid.simulate_many(BALL, t_end=2.0, **kwargs)
    assert str(caught.value) == message




@pytest.mark.parametrize(
    ("value", "said"),
    [
        ("a", "an input gave 'a', not a number"),
        (None, "not 'NoneType'"),
        (1j, "not 'complex'"),
        (np.array([1.0, 2.0]), "arrays can be converted"),
    ],
)
def test_an_input_that_gives_no_number_ends_the_run_where_it_is_read(value: Any, said: str) -> None:
    relay = hybrid.load_text(RELAY)
    late = {"u": lambda t: 0.0 if t < 0.25 else value}  # a number at the start, not later
    run = hybrid.simulate(relay, t_end=1.0, inputs=late)
    assert run.termination.cause == "nonfinite" and 0.25 <= run.termination.t < 0.5
    assert said in run.termination.message and "the guard of up failed" in run.termination.message
    assert run.t[-1] < 0.25  # what was computed before it is kept
    good = hybrid.simulate(relay, t_end=1.0, inputs={"u": lambda t: math.sin(2 * t)}, rtol=1e-10, atol=1e-12)
    assert good.jumps[0].t == pytest.approx(math.pi / 12, abs=1e-8)  # sin(2t) = 0.5


@pytest.mark.parametrize(
    ("function", "message"),
    [
        (lambda t: "a", "input 'u' must give a number at each t, got str at t=0"),
        (lambda t: None, "input 'u' must give a number at each t, got NoneType at t=0"),
        (lambda t: np.array([t]), "got ndarray of shape (1,) at t=0"),
        (lambda t: [t], "got list at t=0"),
        (lambda t, x: t, "input 'u' cannot be called as f(t): "),
    ],
)
def test_an_input_that_is_not_a_number_at_the_start_is_refused_before_the_run(
    function: Any, message: str
) -> None:
    # these used to end the run at once as nonfinite, all its arrays flat
    relay = hybrid.load_text(RELAY)
    with pytest.raises(hybrid.UsageError, match=re.escape(message)):
        hybrid.simulate(relay, t_end=1.0, inputs={"u": function})
    for number in (lambda t: np.float64(0.5), lambda t: np.array(0.5), lambda t: 1):
        assert hybrid.simulate(relay, t_end=1.0, inputs={"u": number}).termination.cause == "t_end"
    failing = hybrid.simulate(relay, t_end=1.0, inputs={"u": lambda t: 1 / 0})  # a value, not a kind
    assert failing.termination.cause == "nonfinite" and "division by zero" in failing.termination.message


@pytest.mark.parametrize(
    ("keyword", "value", "message"),
    [
        ("initial", np.array([5.0, 0.0]),
         "initial= takes a mapping of names to numbers, e.g. {'h': ..., 'v': ...}, got ndarray "
         "array([5., 0.]); values in state order: dict(zip(model.state_names, x0))"),
        ("initial", [5.0, 0.0], "got list [5.0, 0.0]; values in state order"),
        ("parameters", np.array([1.62]), "parameters= takes a mapping of names to numbers, e.g. "
         "{'g': ..., 'e': ...}, got ndarray array([1.62])"),
    ],
)  # fmt: skip
def test_a_vector_for_initial_or_parameters_says_how_to_name_its_values(
    keyword: str, value: Any, message: str
) -> None:
    # an array used to raise numpy's "truth value of an array ... is ambiguous"
    ball = hybrid.load(SPECS / "bouncing_ball.yaml")
    with pytest.raises(hybrid.UsageError) as caught:
        hybrid.simulate(ball, t_end=2.0, **{keyword: value})
    assert message in str(caught.value)


def test_a_pandas_row_gives_parameters_and_initial_values_by_its_index() -> None:
    pd = pytest.importorskip("pandas")
    ball = hybrid.load(SPECS / "bouncing_ball.yaml")
    row = pd.DataFrame({"g": [9.81, 1.62], "e": [0.8, 0.5]}).iloc[1]
    run = hybrid.simulate(ball, t_end=4.0, parameters=row, initial=pd.Series({"h": 5.0}))
    assert run.jumps[0].t == pytest.approx(math.sqrt(2 * 5.0 / 1.62), rel=1e-6)
    assert run.jumps[0].after["v"] == pytest.approx(0.5 * math.sqrt(2 * 1.62 * 5.0), rel=1e-6)


@pytest.mark.parametrize(
    ("times", "values", "message"),
    [
        ([0, 1], [0, 1, 2], "TimeSeries 'u': 2 times but 3 values"),
        ([0, 1, 2], [0, 1], "TimeSeries 'u': 3 times but 2 values"),
        ([0, 2, 1], [0, 1, 2], "TimeSeries 'u': times must increase: t=1 after t=2 (sample 3)"),
        ([0, 1, 1], [0, 1, 2], "TimeSeries 'u': times must increase: t=1 after t=1 (sample 3)"),
        ([0, 1], [0, float("nan")], "TimeSeries 'u': values sample 2 is not finite: nan"),
        ([0, "x"], [0, 1], "TimeSeries 'u': times sample 2 is not a number: 'x'"),
        ([0], [1], "TimeSeries 'u': at least two samples are needed"),
    ],
)
def test_a_time_series_is_checked_as_a_file_of_samples_is(
    times: Any, values: Any, message: str
) -> None:
    # each used to be accepted, and gave a wrong run or a nonfinite end
    from hybrid.simulation.inputs import TimeSeries

    with pytest.raises(hybrid.UsageError) as caught:
        TimeSeries("u", times=times, values=values)
    assert str(caught.value) == message


def test_a_time_series_that_does_not_span_the_run_is_refused_as_the_cli_refuses_it() -> None:
    """Past its last sample a TimeSeries was held without a word from Python, while
    --input-csv refuses the same samples; a series that spans the run is taken."""
    from hybrid.simulation.inputs import TimeSeries

    model = hybrid.load_text(DRIVEN_BY_U)
    short = TimeSeries("u", times=[0, 1], values=[0, 1])
    with pytest.raises(hybrid.UsageError, match=r"input u from <series> covers t in \[0, 1\] but "
                       r"the run goes from t=0 to t=5: add samples or shorten the run"):  # fmt: skip
        hybrid.simulate(model, t_end=5.0, inputs={"u": short})
    run = hybrid.simulate(model, t_end=1.0, inputs={"u": short}, rtol=1e-10, atol=1e-12)
    assert run["x"][-1] == pytest.approx(0.5, abs=1e-9)  # x' = u = t from 0: t^2 / 2


DRIVEN_BY_U = """
automaton: driven
inputs: [u]
state: {x: {initial: 0}}
locations: {a: {flow: {x: u}}}
"""


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"names": ["p"]}, "names must give one name per automaton (2), got 1"),
        ({"names": "pq"}, "names must be a list of 2 names, got 'pq'"),
        ({"names": ["p|q", "r"]}, "a component's name must be a name (an ASCII letter or _, then letters, digits or _), got 'p|q'"),
        ({"names": ["p.q", "p"]}, "a component's name must be a name (an ASCII letter or _, then letters, digits or _), got 'p.q'"),
        ({"name": 5}, "name must be a name (an ASCII letter or _, then letters, digits or _), got 5"),
    ],
)
def test_compose_takes_names_as_specs_write_them(kwargs: dict[str, Any], message: str) -> None:
    """'p|q' once garbled the system's location names ('|' joins them, '.' qualifies)."""
    with pytest.raises(hybrid.UsageError) as caught:
        hybrid.compose(BALL, THERMOSTAT, **kwargs)
    assert str(caught.value) == message
    system = hybrid.compose(BALL, THERMOSTAT, names=["p", "q"], name="pq")
    assert hybrid.simulate(system, t_end=0.5).location[0] == "p.falling|q.off"


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"samples": 2, "vary": {"e": (0.1, 0.5, 0.9)}}, "e: a range is two numbers (low, high), got (0.1, 0.5, 0.9)"),
        ({"samples": 2, "vary": {"e": "0.1:0.5"}}, "e: a range is two numbers (low, high), got '0.1:0.5'"),
        ({"samples": 2, "vary": {"e": 0.9}}, "e: a range is two numbers (low, high), got 0.9"),
        ({"samples": 2, "vary": [1]}, "a range to vary is an Axis or a name, got 1"),
        ({"points": [0.5]}, "point 0 must be a mapping {name: value}, got 0.5"),
        ({"points": [{"e": "x"}]}, "point 0: values must be numbers, got {'e': 'x'}"),
    ],
)
def test_sweep_ranges_and_points_of_the_wrong_shape_are_named(kwargs: dict[str, Any], message: str) -> None:
    with pytest.raises(hybrid.UsageError) as caught:
        hybrid.sweep(BALL, t_end=1.0, workers=0, **kwargs)
    assert str(caught.value) == message
    table = hybrid.sweep(BALL, t_end=1.0, workers=0, samples=3, vary={"e": np.array([0.1, 0.9])})
    assert all(0.1 <= row["e"] <= 0.9 for row in table.rows)


def test_smaller_arguments_say_what_they_take() -> None:
    with pytest.raises(hybrid.UsageError, match="initial_location must be a location's name, got 3"):
        hybrid.simulate(BALL, t_end=1.0, initial_location=3)  # type: ignore[arg-type]
    with pytest.raises(hybrid.UsageError, match="progress must be a function of a status, got 5"):
        hybrid.simulate(BALL, t_end=1.0, progress=5)  # type: ignore[arg-type]
    with pytest.raises(hybrid.UsageError, match="resume=True finishes the campaign writing out="):
        hybrid.sweep(BALL, t_end=1.0, grid={"e": [0.5]}, workers=0, resume=True)
    for starts in (0, -1, 1.5):
        with pytest.raises(hybrid.UsageError, match="starts must be a whole number >= 1"):
            hybrid.falsify(BALL, "x", t_end=1.0, starts=starts, workers=0)  # type: ignore[arg-type]
    table = hybrid.sweep(BALL, t_end=2.0, grid={"e": [0.5, 0.9]}, workers=0)
    assert table.column("e") == [0.5, 0.9]
    with pytest.raises(hybrid.UsageError, match="no column 'zz'") as caught:
        table.column("zz")
    assert isinstance(caught.value, KeyError)


def test_numpy_true_and_false_are_flags_and_plot_takes_names() -> None:
    settings = hybrid.Settings(t_end=1.0, zeno=np.bool_(True), dense=np.bool_(False))
    assert settings.zeno is True and settings.dense is False  # Python's, as JSON writes them
    run = hybrid.simulate(BALL, settings=settings)
    with pytest.raises(hybrid.UsageError, match="plot\\(\\) takes names of state variables or signals, got 3"):
        run.plot(3)  # type: ignore[arg-type]
    with pytest.raises(hybrid.UsageError, match="names a file with a str or Path, got 3"):
        run.plot(path=3)  # type: ignore[arg-type]


def test_a_table_asked_for_a_requirement_it_does_not_have_says_so() -> None:
    heater = hybrid.load_text(
        "automaton: heater\nparameters: {k: 0.1}\nstate: {x: {initial: 20.0}}\n"
        "locations: {cooling: {flow: {x: -k*x}}}\n"
        "requirements: [{name: warm, always: 'x >= 20*exp(-0.95)'}]\n",
        file="heater.yaml",
    )
    table = hybrid.sweep(heater, t_end=1.0, grid={"k": [0.5, 1.0]}, workers=0)
    assert [row["k"] for row in table.violations("warm")] == [1.0]  # 20 e^-k < 20 e^-0.95
    with pytest.raises(hybrid.UsageError, match="no requirement 'wram' in the table; did you mean 'warm'") as caught:
        table.violations("wram")
    assert isinstance(caught.value, KeyError)


@pytest.mark.parametrize(
    ("t_end", "hint"),
    [
        (np.array(3.0), "got array(3.): an array of one value; give its number (float(t) or t.item())"),
        ([0, 10], "got [0, 10]: for MATLAB's tspan [t0, tf], give t_start=t0, t_end=tf"),
        (np.array([0.0, 10.0]), "for MATLAB's tspan [t0, tf], give t_start=t0, t_end=tf"),
    ],
)
def test_a_time_given_as_an_array_or_a_tspan_says_what_to_write(t_end: Any, hint: str) -> None:
    # said only "t_end must be a finite time after t_start=0.0, got ..."
    with pytest.raises(hybrid.UsageError) as caught:
        hybrid.simulate(hybrid.load(SPECS / "bouncing_ball.yaml"), t_end=t_end)
    assert str(caught.value).startswith("t_end must be a finite time after t_start=0.0, ")
    assert str(caught.value).endswith(hint)


def test_two_components_of_one_name_in_compose_say_where_and_how_to_rename() -> None:
    # pointed at "line 1" of the other file and said to write `as:` (a system file's key)
    tank, thermostat = hybrid.load(SPECS.parent / "docs/examples/tank.yaml"), THERMOSTAT
    with pytest.raises(hybrid.SpecError) as caught:
        hybrid.compose(tank, thermostat, names=["x", "x"])
    assert caught.value.message == (
        f"component name 'x' is used twice (also at {tank.position}): give each its own name "
        "(as: in a system file, names= in compose(); the automaton's name is the default)"
    )


def test_a_vector_signal_is_read_whole_by_its_name_and_matlab_indices_are_named() -> None:
    # run["q"] was an unknown name though run.plot("q") draws it; run["q(1)"] suggested q[1]
    pytest.importorskip("uvms_model")
    spec = (
        "automaton: law\nuses: [uvms_model]\nstate: {x: {initial: 0.0}}\n"
        "signals: {q: 'quintic(t, 0, 0, 0, 0, 1, 1)'}\nlocations: {a: {flow: {x: 1}}}\n"
    )
    run = hybrid.simulate(hybrid.load_text(spec), t_end=2.0)
    assert "q" in run and run["q"].shape == (len(run), 3)
    assert [run["q"][:, k].tolist() for k in range(3)] == [run[f"q[{k}]"].tolist() for k in range(3)]
    assert run["q"][-1].tolist() == [1.0, 0.0, 0.0]  # held at (pf, 0, 0) after the law's end
    with pytest.raises(hybrid.UsageError, match=re.escape(
        "did you mean 'q[0]'? (elements count from 0: MATLAB's q(1) is q[0])"
    )):  # fmt: skip
        run["q(1)"]


def test_times_given_by_position_as_in_matlab_say_to_use_keywords() -> None:
    # simulate(ball, 0, 10) raised Python's "takes from 1 to 2 positional arguments"
    with pytest.raises(hybrid.UsageError) as caught:
        hybrid.simulate(BALL, 0, 10)  # type: ignore[misc]
    said = str(caught.value)
    assert said.startswith("simulate() takes from 1 to 2 positional arguments but 3 were given: ")
    assert "give the others by keyword (" in said and "t_start=t0, t_end=tf" in said
    with pytest.raises(TypeError, match="missing 1 required positional argument"):
        hybrid.simulate()  # type: ignore[call-arg]


def test_numpy_numbers_are_parameter_values_when_a_model_is_loaded_or_copied() -> None:
    # with_parameters and load(parameters=) refused np.int64 and np.float32 ("must be a
    # number"), which simulate(parameters=) took
    values = {"g": np.float32(1.5), "e": np.int64(1)}
    for model in (BALL.with_parameters(values), hybrid.load(SPECS / "bouncing_ball.yaml", parameters=values)):
        assert model.parameters == {"g": 1.5, "e": 1.0}
        assert all(type(v) is float for v in model.parameters.values())
    with pytest.raises(hybrid.SpecError, match=re.escape("value of 'g' must be a number, got np.True_")):
        BALL.with_parameters({"g": np.True_})
