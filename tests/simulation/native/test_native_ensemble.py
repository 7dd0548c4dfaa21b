"""``hybrid.simulate_many``: every run of an ensemble equals the same run made alone."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pytest
from support import REPO, SPECS

import hybrid
from hybrid.errors import HybridError, UsageError

pytest.importorskip("numba")

TOL = {"rtol": 1e-10, "atol": 1e-12, "handle_sigint": False}


def test_each_run_equals_the_scipy_run_of_its_row(thermostat: hybrid.Automaton) -> None:
    table = {"init.T": [19.0, 20.0, 21.5, 18.5], "a": [0.1, 0.2, 0.05, 0.3]}
    runs = hybrid.simulate_many(thermostat, t_end=60.0, parameters=table, **TOL)
    assert len(runs) == 4
    for i, run in enumerate(runs):
        alone = hybrid.simulate(
            thermostat, t_end=60.0, parameters={"a": table["a"][i]}, initial={"T": table["init.T"][i]},
            **TOL,
        )  # fmt: skip
        assert [j.edge for j in run.jumps] == [j.edge for j in alone.jumps]
        np.testing.assert_allclose(run.jump_times, alone.jump_times, rtol=1e-10, atol=1e-9)
        assert run.termination.cause == alone.termination.cause
        assert run["T"][0] == table["init.T"][i]
    assert list(runs.causes) == ["t_end"] * 4
    assert list(runs.n_jumps) == [len(r.jumps) for r in runs]
    np.testing.assert_allclose(runs.t, 60.0)


def test_rows_outgrowing_the_first_are_run_again_alone(thermostat: hybrid.Automaton) -> None:
    # the first row switches rarely, the others often: their rows overflow and are rerun alone
    rows = [{"a": 0.01}] + [{"a": 1.0}] * 3
    runs = hybrid.simulate_many(thermostat, t_end=100.0, parameters=rows, **TOL)
    fast = hybrid.simulate(thermostat, t_end=100.0, parameters={"a": 1.0}, backend="compiled", **TOL)
    assert runs.n_jumps[0] < 5 and list(runs.n_jumps[1:]) == [len(fast.jumps)] * 3
    np.testing.assert_allclose(runs[3].jump_times, fast.jump_times, rtol=1e-12)


def test_ball_ensemble_zeno_and_initial_table(ball: hybrid.Automaton) -> None:
    heights = np.array([1.0, 5.0, 10.0])
    runs = hybrid.simulate_many(ball, t_end=30.0, initial={"h": heights}, **TOL)
    g, e = 9.81, 0.8
    t1 = np.sqrt(2 * heights / g)
    np.testing.assert_allclose([r.termination.zeno_time for r in runs], t1 * (1 + e) / (1 - e), rtol=1e-9)
    assert list(runs.causes) == ["zeno"] * 3


def test_bad_tables_are_refused(ball: hybrid.Automaton) -> None:
    with pytest.raises(HybridError, match="unknown parameter 'q'"):
        hybrid.simulate_many(ball, t_end=1.0, parameters={"q": [1.0]})
    with pytest.raises(UsageError, match="different"):
        hybrid.simulate_many(ball, t_end=1.0, parameters={"e": [0.5, 0.6], "g": [9.0]})
    with pytest.raises(UsageError, match="unknown state variable 'z'"):
        hybrid.simulate_many(ball, t_end=1.0, initial={"z": [1.0]})


def test_a_run_failing_at_its_start_is_described_with_its_own_parameters() -> None:
    # both rows said "the flow of a gives x' = -0.8": the spec's c = 0.36, a finite value
    model = hybrid.load_text(
        "automaton: sq\nparameters: {c: 0.36}\nstate: {x: {initial: 1.0}}\n"
        "locations: {a: {flow: {x: -sqrt(x - c)}}}\n"
    )
    runs = hybrid.simulate_many(model, t_end=2.0, parameters={"c": [2.0, 3.0]})
    said = [run.termination.message for run in runs]
    assert said == [
        "the flow of a failed: sqrt(-1): math domain error (at t=0)",  # 1 - 2
        "the flow of a failed: sqrt(-2): math domain error (at t=0)",  # 1 - 3
    ]
    one = hybrid.simulate(model, t_end=2.0, parameters={"c": 2.0}, backend="compiled")
    assert one.termination.message == said[0]  # a single run's words


def test_tables_a_new_user_wrote_are_read_or_refused_as_meant(ball: hybrid.Automaton) -> None:
    pd = pytest.importorskip("pandas")
    # an empty table made one run with the spec's values
    for empty in ({}, [], pd.DataFrame()):
        with pytest.raises(UsageError, match="parameters: the table is empty"):
            hybrid.simulate_many(ball, t_end=1.0, parameters=empty)
    # rows naming the same columns in another order were refused
    rows = hybrid.simulate_many(ball, t_end=2.0, parameters=[{"e": 0.5, "g": 9.81}, {"g": 1.62, "e": 0.6}])
    assert rows.parameters["g"].tolist() == [9.81, 1.62] and rows.parameters["e"].tolist() == [0.5, 0.6]
    # the lengths are named with their columns
    with pytest.raises(UsageError, match=r"columns of different lengths \(e: 3, g: 2\)"):
        hybrid.simulate_many(ball, t_end=1.0, parameters={"e": [0.5, 0.6, 0.7], "g": [9.81, 1.6]})
    # a start given twice ran with the second silently
    with pytest.raises(UsageError, match="initial value of 'h' is given twice"):
        hybrid.simulate_many(ball, t_end=1.0, parameters={"init.h": [1.0]}, initial={"h": [2.0]})


def test_threads_apply_to_the_call_not_to_the_process(ball: hybrid.Automaton) -> None:
    numba = pytest.importorskip("numba")
    before = numba.get_num_threads()
    hybrid.simulate_many(ball, t_end=1.0, parameters={"e": [0.5, 0.6]}, threads=1)
    assert numba.get_num_threads() == before  # stayed at 1 for every later ensemble


def test_the_sizing_run_is_row_0_and_is_not_run_again(
    thermostat: hybrid.Automaton, monkeypatch: pytest.MonkeyPatch
) -> None:
    # the first row was run once alone to size the rows, then again with the others
    from hybrid.simulation.native.engine import CompiledNative

    given: list[list[float]] = []
    real = CompiledNative.run_many

    def recorded(self: CompiledNative, ps: np.ndarray, *args: object) -> None:
        given.append(ps[:, 0].tolist())
        real(self, ps, *args)  # type: ignore[arg-type]

    monkeypatch.setattr(CompiledNative, "run_many", recorded)
    rates = [0.05, 0.1, 0.2]
    runs = hybrid.simulate_many(thermostat, t_end=50.0, parameters={"a": rates})
    assert given == [rates[1:]]  # the kernel ran rows 1 and 2 only
    for k, rate in enumerate(rates):  # row 0 is the sizing run, bit for bit a single run
        one = hybrid.simulate(thermostat, t_end=50.0, parameters={"a": rate}, backend="compiled")
        assert runs[k].t.tolist() == one.t.tolist() and runs[k].states.tolist() == one.states.tolist()
        assert runs[k].jump_times.tolist() == one.jump_times.tolist()
    assert runs.n_jumps.tolist() == [len(r.jumps) for r in runs] and set(runs.causes) == {"t_end"}
    single = hybrid.simulate_many(thermostat, t_end=50.0, parameters={"a": [0.05]})
    assert len(single) == 1 and given == [rates[1:]]  # one row: no kernel call at all
    assert single[0].t.tolist() == runs[0].t.tolist()


IDLE_WAITS = """
import os, sys
import numba.np.ufunc.parallel as parallel
import hybrid
seen = []
launch = parallel._launch_threads
def launching():
    if not parallel._is_initialized:  # libgomp reads its settings now, once
        seen.append((os.environ.get("GOMP_SPINCOUNT"), os.environ.get("OMP_WAIT_POLICY")))
    launch()
parallel._launch_threads = launching
ball = hybrid.load(sys.argv[1])
hybrid.simulate_many(ball, t_end=1.0, parameters={{"e": [0.5, 0.6]}}, {threads})
print(seen[0])
"""


@pytest.mark.parametrize("threads", ["threads=1", "handle_sigint=False"])
@pytest.mark.parametrize(("given", "seen"), [
    ({}, "('10000', None)"),
    ({"OMP_WAIT_POLICY": "active"}, "(None, 'active')"),
    ({"GOMP_SPINCOUNT": "5"}, "('5', None)"),
])  # fmt: skip
def test_idle_threads_sleep_soon_unless_the_process_chose(threads: str, given: dict[str, str],
                                                          seen: str) -> None:  # fmt: skip
    """numba's OpenMP threads are started with a short spin (libgomp's default spins for
    milliseconds after every chunk); a wait the user's environment chose is kept. Both ways
    in: asking numba for its thread count (``threads=``) and loading the ensemble loop."""
    env = {k: v for k, v in os.environ.items() if k not in ("GOMP_SPINCOUNT", "OMP_WAIT_POLICY")}
    code = IDLE_WAITS.format(threads=threads)
    done = subprocess.run([sys.executable, "-c", code, str(SPECS / "bouncing_ball.yaml")],
                          capture_output=True, text=True, cwd=REPO, env={**env, **given},
                          timeout=600)  # fmt: skip  (a hang guard: a cold compile)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == seen
