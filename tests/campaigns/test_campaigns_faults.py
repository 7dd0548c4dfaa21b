"""Campaign faults met as users meet them: sizes, resumes, damaged chunks, dead workers.

Each once ended in a traceback, an out-of-memory kill, a mixed table or a
silent exit 0 (found by trying campaigns as a user would).
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from support import SPECS, run_cli

import hybrid
from hybrid.campaigns.resumable import ChunkStore
from hybrid.campaigns.runs import RunPlan
from hybrid.campaigns.sweep import _fingerprint

BALL = hybrid.load(SPECS / "bouncing_ball.yaml")


def test_a_grid_times_samples_over_the_limit_is_refused_before_any_point_is_made() -> None:
    """10,000 grid values times 10,000 samples: 1e8 runs (13 GB before, then the OOM killer)."""
    grid = {"e": [0.5 + k * 1e-5 for k in range(10_000)]}
    with pytest.raises(hybrid.UsageError, match="10000 points times 10000 samples are 100000000 runs"):
        hybrid.sweep(BALL, t_end=1.0, grid=grid, vary={"init.h": (1.0, 2.0)}, samples=10_000, workers=0)


@pytest.mark.parametrize("campaign", ["sweep", "falsify"])
def test_an_unknown_backend_is_refused_before_any_run(campaign: str) -> None:
    """backend="numba" was a campaign of failed rows (sweep), or a whole budget of failed
    runs reported as "no violation" (falsify); simulate refused it at once."""
    with pytest.raises(hybrid.UsageError, match="unknown backend 'numba'; choose one of"):
        if campaign == "sweep":
            hybrid.sweep(BALL, 3.0, grid={"e": [0.5, 0.6]}, backend="numba", workers=0)
        else:
            hybrid.falsify(BALL, "r", {"e": (0.5, 0.9)}, t_end=3.0, backend="numba", budget=4)


def test_summaries_given_as_one_string_are_refused_as_such() -> None:
    """summaries="max:v" was read letter by letter: "summary 'm': expected KIND:NAME"."""
    with pytest.raises(hybrid.UsageError, match=r"summaries is a list of KIND:NAME, got the "
                       r"string 'max:v': write \['max:v'\]"):  # fmt: skip
        hybrid.sweep(BALL, 3.0, grid={"e": [0.5]}, summaries="max:v", workers=0)


def test_a_different_run_timeout_is_another_campaign() -> None:
    """Resuming with another timeout mixed rows run with and without it into one table."""
    points = [{"e": 0.5}, {"e": 0.9}]
    base, parts = _fingerprint("m", RunPlan(t_end=1.0), ["run", "e"], points)
    assert _fingerprint("m", RunPlan(t_end=1.0), ["run", "e"], points) == (base, parts)
    other, changed = _fingerprint("m", RunPlan(t_end=1.0, timeout=0.5), ["run", "e"], points)
    assert other != base
    assert [k for k in parts if parts[k] != changed[k]] == ["timeout"]
    # the fingerprint of the campaigns before the parts were kept: their folders resume
    before = {"model": "m", "t_end": 1.0, "solver": [], "inputs": [], "backend": "scipy",
              "timeout": None, "columns": ["run", "e"],
              "points": [[("e", "0.5")], [("e", "0.9")]]}  # fmt: skip
    plan = RunPlan(t_end=1.0, backend="scipy")
    assert _fingerprint("m", plan, ["run", "e"], points)[0] == hashlib.sha256(
        json.dumps(before).encode()).hexdigest()  # fmt: skip


def test_a_refused_resume_names_what_differs(tmp_path: Path) -> None:
    """Every refusal said "(a different model, settings or points)", also when only a run
    timeout was added, as one does after finding hung runs."""
    out = tmp_path / "r.csv"
    from hybrid.campaigns.resumable import ChunkStore

    _, parts = _fingerprint("m", RunPlan(t_end=1.0), ["run", "e"], [{"e": 0.5}])
    ChunkStore(out, "earlier", resume=False, parts=parts).close()
    later = {**parts, "timeout": "x", "backend": "y"}
    with pytest.raises(hybrid.UsageError, match=r"another campaign \(it differs in the "
                       r"backend, the run timeout\): remove it"):  # fmt: skip
        ChunkStore(out, "later", resume=True, parts=later)


def test_a_resume_with_nothing_to_resume_says_so(tmp_path: Path) -> None:
    """--resume with no .parts folder (a typo, or a campaign that finished) ran every run
    and replaced the results without a word."""
    from hybrid.errors import Note

    out = tmp_path / "r.csv"
    with pytest.warns(Note, match=r"nothing to resume in .*r\.csv\.parts: every run is run"):
        table = hybrid.sweep(BALL, 1.0, grid={"e": [0.5, 0.6]}, out=out, resume=True,
                             workers=0, backend="scipy")  # fmt: skip
    assert table.complete and len(table) == 2 and out.exists()


def test_a_damaged_chunk_is_named_not_a_traceback(tmp_path: Path) -> None:
    out = tmp_path / "table.csv"
    store = ChunkStore(out, "print", resume=False)
    for run in range(3):
        store.add({"run": run, "cause": "t_end"})
    store.flush()
    (chunk,) = sorted(store.folder.glob("chunk-*.jsonl"))
    assert len(chunk.read_text().splitlines()) == 3
    store.close()  # its campaign is over: another may resume the folder
    assert sorted(ChunkStore(out, "print", resume=True).done) == [0, 1, 2]  # read back whole
    chunk.write_text(chunk.read_text()[:25])  # cut short, as a partial copy of the folder
    with pytest.raises(hybrid.UsageError, match=r"chunk-000000\.jsonl: cannot read it .*remove it"):
        ChunkStore(out, "print", resume=True)
    json.loads((store.folder / "campaign.json").read_text())  # the manifest is intact



def test_a_second_campaign_on_the_same_results_is_refused_while_the_first_writes(
    tmp_path: Path,
) -> None:
    """Two sweeps given one --out wrote chunks of the same numbers over each other."""
    out = tmp_path / "table.csv"
    first = ChunkStore(out, "print", resume=False)
    first.add({"run": 0, "cause": "t_end"})
    first.flush()
    busy = rf"another campaign is writing these results now \(process {os.getpid()}\)"
    for resume in (True, False):
        with pytest.raises(hybrid.UsageError, match=busy):
            ChunkStore(out, "print", resume=resume)
    with pytest.raises(hybrid.UsageError, match=busy):
        hybrid.sweep(BALL, t_end=1.0, grid={"e": [0.5]}, workers=0, out=out, resume=True)
    first.add({"run": 1, "cause": "t_end"})
    first.flush()  # the first campaign's chunks are its own
    first.close()
    again = ChunkStore(out, "print", resume=True)
    assert sorted(again.done) == [0, 1] and again.next_chunk == 2


HOLDER = """import sys
from hybrid.campaigns.resumable import ChunkStore
store = ChunkStore(sys.argv[1], "print", resume=False)
print("holding", flush=True)
sys.stdin.read()
"""


def test_a_campaign_process_holds_its_results_until_it_ends_even_by_kill_9(tmp_path: Path) -> None:
    out = tmp_path / "table.csv"
    holder = subprocess.Popen([sys.executable, "-c", HOLDER, str(out)], stdin=subprocess.PIPE,
                              stdout=subprocess.PIPE, text=True)  # fmt: skip
    try:
        assert holder.stdout is not None and holder.stdout.readline() == "holding\n"
        refused = run_cli("sweep", SPECS / "bouncing_ball.yaml", "--t-end", "1", "--grid",
                          "e=0.5:0.9:2", "--workers", "0", "--out", out, "--resume")  # fmt: skip
        assert refused.returncode == 2, refused.stderr
        assert f"writing these results now (process {holder.pid})" in refused.stderr
        assert "Traceback" not in refused.stderr
        assert not out.exists()
    finally:
        holder.send_signal(signal.SIGKILL)
        holder.wait(timeout=60)
    assert ChunkStore(out, "print", resume=True).done == {}  # the system released the lock


HEATER = """automaton: heater
parameters: {k: 0.1}
state: {x: {initial: 20.0}}
locations: {cooling: {flow: {x: -k*x}}}
requirements: [{name: warm, always: "x >= 20*exp(-0.95)"}]
"""
SLOW = {"t_end": 1.0, "max_step": 2e-5, "run_timeout": 0.01, "backend": "scipy", "workers": 0}
"""50,000 steps a run: none ends within the run timeout, on any machine."""


def test_runs_that_failed_are_not_evidence_of_no_violation(tmp_path: Path) -> None:
    """x(1) = 20 exp(-k) is below 20 exp(-0.95) for every k > 0.95: each point violates, but
    every run times out. Before, each counted as robustness +inf, the falsification said 'no
    violation' (exit 0), and its point was run again without the timeout."""
    heater = hybrid.load_text(HEATER, file="heater.yaml")
    result = hybrid.falsify(heater, "warm", {"k": (0.96, 1.0)}, budget=3, seed=0, **SLOW)
    assert len(result.failed) == result.evaluations == 3
    assert all(h["failed"].startswith("timeout") for h in result.failed)
    assert not result.found and result.run is None  # nothing judged, nothing run again
    assert result.as_dict()["failed"] == 3
    quick = hybrid.falsify(heater, "warm", {"k": (0.96, 1.0)}, budget=3, seed=0, t_end=1.0,
                           backend="scipy", workers=0, rtol=1e-10, atol=1e-12)  # fmt: skip
    k = quick.values["k"]
    assert quick.found and quick.failed == []
    assert quick.robustness == pytest.approx(20 * math.exp(-k) - 20 * math.exp(-0.95), abs=1e-6)


def test_a_search_whose_runs_failed_does_not_exit_0(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Where the requirement holds (k < 0.95) but every run times out: not 'no violation', exit 0."""
    from support import main_in_process

    spec = tmp_path / "heater.yaml"
    spec.write_text(HEATER)
    code = main_in_process("falsify", spec, "--t-end", "1", "--requirement", "warm", "--vary",
                           "k=0.1:0.5", "--budget", "2", "--max-step", "2e-5", "--run-timeout",
                           "0.01", "--backend", "scipy", "--workers", "0", "--quiet")  # fmt: skip
    said = capsys.readouterr().out
    assert code == 1, said
    assert "2 of them failed and were not judged (the first: timeout" in said


def test_a_compiled_campaign_does_not_count_loading_against_the_first_run() -> None:
    """The first compiled run of a process loads its code for about 2 s (a warm cache):
    with a run timeout of 0.5 s run 0 ended 'timeout' in every such campaign."""
    pytest.importorskip("numba")
    import subprocess
    import sys

    from support import REPO

    code = (
        "import hybrid\n"
        "ball = hybrid.load('specs/bouncing_ball.yaml')\n"
        "table = hybrid.sweep(ball, t_end=10.0, grid={'e': [0.5, 0.7, 0.9]}, workers=0,\n"
        "                     backend='compiled', run_timeout=0.5)\n"
        "print([row['cause'] for row in table.rows])\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=REPO, timeout=600, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "timeout" not in done.stdout and done.stdout.count("'") == 6, done.stdout


DRIFT = """automaton: drift
state: {x: {initial: [0, 2]}}
inputs: {u: {range: [1, 3]}}
locations: {go: {flow: {x: u}}}
requirements: [{name: bounded, always: "x <= 20"}]
"""


@pytest.mark.parametrize(
    ("options", "refusal"),
    [
        ({"grid": {"input.u": [1.0, 3.0]}}, r"cannot hold input 'u' at a point's value \(input\.u\)"),
        ({"grid": {"init.x": [0.0, 2.0]}, "inputs": {"u": "sin(t)"}},
         r"cannot drive input 'u' with an expression \(--input, inputs=\)"),
        ({"grid": {"init.x": [0.0, 2.0]}, "method": "RK23"}, r"method 'RK23' needs backend 'scipy'"),
    ],
)  # fmt: skip
def test_a_compiled_campaign_its_runs_would_all_refuse_is_refused_before_it_runs(
    options: dict[str, object], refusal: str
) -> None:
    """Each of these ran the whole campaign, every row an error, and exited 1; the contract
    says a construct the compiled backend lacks is refused (exit 2 on the command line)."""
    drift = hybrid.load_text(DRIFT, file="drift.yaml")
    with pytest.raises(hybrid.UsageError, match=refusal):
        hybrid.sweep(drift, t_end=4.0, workers=0, backend="compiled", **options)  # type: ignore[arg-type]
    with pytest.raises(hybrid.UsageError, match=refusal):
        ranges = {name: (min(values), max(values)) for name, values in options["grid"].items()}  # type: ignore[attr-defined]
        hybrid.falsify(drift, "bounded", ranges, budget=2, workers=0, t_end=4.0,
                       backend="compiled", **{k: v for k, v in options.items() if k != "grid"})  # fmt: skip
    table = hybrid.sweep(drift, t_end=4.0, workers=0, backend="auto", **options)  # type: ignore[arg-type]
    assert [row["cause"] for row in table.rows] == ["t_end", "t_end"]  # auto runs them on scipy


def test_the_command_line_refuses_it_with_exit_2(tmp_path: Path) -> None:
    spec = tmp_path / "drift.yaml"
    spec.write_text(DRIFT)
    out = tmp_path / "table.csv"
    done = run_cli("sweep", spec, "--t-end", "4", "--grid", "input.u=1:3:3", "--backend",
                   "compiled", "--workers", "0", "--out", out)  # fmt: skip
    assert done.returncode == 2, done.stderr
    assert "drift.yaml: the compiled backend cannot hold input 'u'" in done.stderr
    assert not out.exists() and not (tmp_path / "table.csv.parts").exists()


def test_the_table_says_which_backend_ran(tmp_path: Path) -> None:
    """The docs said 'the table's metadata records the backend that ran': there was none."""
    drift = hybrid.load_text(DRIFT, file="drift.yaml")
    asked = {"grid": {"init.x": [0.0, 2.0]}, "workers": 0, "t_end": 4.0}
    assert hybrid.sweep(drift, backend="scipy", **asked).backend == "scipy"  # type: ignore[arg-type]
    held = hybrid.sweep(drift, grid={"input.u": [1.0, 3.0]}, workers=0, t_end=4.0)
    assert held.backend == "scipy"  # auto, the default, chooses scipy for a held input
    pytest.importorskip("pyarrow")
    import pyarrow.parquet as pq

    out = tmp_path / "table.parquet"
    hybrid.sweep(drift, backend="scipy", out=out, **asked)  # type: ignore[arg-type]
    assert pq.read_schema(out).metadata == {b"hybrid.backend": b"scipy"}


def test_a_jump_count_summary_is_a_whole_number() -> None:
    """jumps:EDGE was written 13.0: a count. The ball with e = 0.5 from h = 10 bounces
    4 times by t = 4 (impacts at 1.428, 2.856, 3.570, 3.927 s: the first flight
    sqrt(2 h / g), then 2 e sqrt(2 h / g), each half the last)."""
    table = hybrid.sweep(BALL, 4.0, grid={"e": [0.5]}, summaries=["jumps:bounce"], workers=0,
                         backend="scipy")  # fmt: skip
    (row,) = table.rows
    assert row["jumps:bounce"] == 4 and isinstance(row["jumps:bounce"], int)
    assert table.csv_text().splitlines()[1].split(",")[-1] == "4"
