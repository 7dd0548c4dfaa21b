"""Runs lost to the executor (a worker that dies) are run again, never counted as done.

* On a Dask ``LocalCluster`` of worker processes, one worker is killed (SIGKILL)
  while the sweep is under way: the scheduler hands its tasks to the others and
  the table is the one a sweep in this process gives, with no error row.
* An executor that loses runs (as a local worker that dies does: an ``error``
  row made by the executor, not by the run) has them run again once; runs lost
  twice leave the campaign incomplete with its folder of finished rows kept, and
  ``resume`` runs exactly those, giving the uninterrupted table.
* A row recorded as lost is in the chunks but is not done for ``resume``.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import pytest

import hybrid
from hybrid.campaigns.executors import Failed, InProcess, OnResult, Stop
from hybrid.campaigns.resumable import LOST, ChunkStore
from hybrid.campaigns.sweep import sweep
from hybrid.campaigns.table import IncompleteWarning

WAVE = """
automaton: wave
parameters: {w: 1.0}
state: {x: {initial: 0.0}}
locations: {on: {flow: {x: cos(w*t)}}}
"""
# x = sin(w t) / w: the last value of x is a closed form to hold each row to
T_END = 3.0
W = [float(w) for w in range(1, 17)]
SUMMARIES = ["last:x"]


def _reference() -> hybrid.SweepTable:
    return hybrid.sweep(hybrid.load_text(WAVE), t_end=T_END, grid={"w": W}, workers=0,
                        summaries=SUMMARIES, max_step=0.002, backend="scipy")  # fmt: skip


def _check_closed_form(table: hybrid.SweepTable) -> None:
    import math

    for row in table.rows:
        assert row["cause"] == "t_end", row
        assert row["last:x"] == pytest.approx(math.sin(row["w"] * T_END) / row["w"], abs=1e-6)


def test_a_dask_worker_killed_mid_sweep_loses_no_run() -> None:
    distributed = pytest.importorskip("distributed", reason="dask[distributed] is in the test extra")
    reference = _reference()
    _check_closed_form(reference)
    killed: list[int] = []
    with (
        distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                 dashboard_address=None) as cluster,
        distributed.Client(cluster) as client,
    ):  # fmt: skip
        pids = sorted(client.run(os.getpid).values())

        def progress(status: Any) -> None:
            if not killed and status.done >= 2:  # some rows in: the others are under way
                os.kill(pids[0], signal.SIGKILL)
                killed.append(pids[0])

        table = hybrid.sweep(hybrid.load_text(WAVE), t_end=T_END, grid={"w": W},
                             scheduler=client, batch=1, summaries=SUMMARIES, max_step=0.002,
                             progress=progress, backend="scipy")  # slow: killed mid-sweep  # fmt: skip
    assert killed, "the sweep ended before a worker could be killed"
    assert table.complete and not table.failed()
    assert table.rows == reference.rows


class Losing(InProcess):
    """Runs jobs here, but loses the runs named in ``lose`` (each as many times as listed)."""

    def __init__(self, lose: list[int]) -> None:
        super().__init__()
        self.lose = list(lose)
        self.calls: list[list[int]] = []

    def run(self, jobs: Sequence[Any], on_result: OnResult, failed: Failed = lambda j, c, m: {},
            should_stop: Stop = lambda: False, limit: float | None = None) -> bool:  # fmt: skip
        self.calls.append([job[0] for job in jobs])
        kept = []
        for job in jobs:
            if job[0] in self.lose:
                self.lose.remove(job[0])
                on_result(job[0], failed(job, "error", "the worker process died (exit code -9)"))
            else:
                kept.append(job)
        return super().run(kept, on_result, failed, should_stop, limit)


def _losing_sweep(monkeypatch: pytest.MonkeyPatch, lose: list[int], **kwargs: Any) -> Any:
    executor = Losing(lose)
    monkeypatch.setattr("hybrid.campaigns.sweep.executor_for", lambda *a, **k: executor)
    table = sweep(hybrid.load_text(WAVE), T_END, grid={"w": W}, summaries=SUMMARIES,
                  max_step=0.002, backend="scipy", **kwargs)  # fmt: skip
    return table, executor


def test_runs_lost_once_are_run_again(monkeypatch: pytest.MonkeyPatch) -> None:
    table, executor = _losing_sweep(monkeypatch, [3, 7])
    assert executor.calls == [list(range(len(W))), [3, 7]]  # the lost ones, once more
    assert table.complete and table.lost == 0
    assert table.rows == _reference().rows


def test_runs_lost_twice_are_not_done_and_resume_runs_them(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    out = tmp_path / "results.csv"
    table, _ = _losing_sweep(monkeypatch, [5, 5], out=out)
    assert not table.complete and table.lost == 1
    assert not out.exists() and (tmp_path / "results.csv.parts").is_dir()
    # written by hand, the rows it has, and a warning that they are not all (a script
    # that went on after a Ctrl-C wrote 7 of 20 rows without a word)
    with pytest.warns(IncompleteWarning, match=f"gets {len(W) - 1} of the campaign's {len(W)}"):
        table.write(tmp_path / "by_hand.csv")
    assert (tmp_path / "by_hand.csv").read_text() == table.csv_text()
    assert sorted(ChunkStore(out, _fingerprint(tmp_path), resume=True).done) == [
        k for k in range(len(W)) if k != 5
    ]
    again, executor = _losing_sweep(monkeypatch, [], out=out, resume=True)
    assert executor.calls == [[5]]  # only the lost run
    assert again.complete and again.resumed == len(W) - 1
    reference = _reference()
    assert out.read_text() == reference.csv_text()


def _fingerprint(folder: Path) -> str:
    import json

    return str(json.loads((folder / "results.csv.parts" / "campaign.json").read_text())["fingerprint"])


def test_a_lost_row_is_kept_but_not_done(tmp_path: Path) -> None:
    out = tmp_path / "t.csv"
    store = ChunkStore(out, "fp", resume=False)
    store.add({"run": 0, "cause": "t_end"})
    store.add({"run": 1, "cause": "error", "message": "worker died", LOST: True})
    store.add({"run": 2, "cause": "error", "message": "a run's own error"})
    store.flush()
    store.close()
    resumed = ChunkStore(out, "fp", resume=True)
    assert sorted(resumed.done) == [0, 2]
    resumed.add({"run": 1, "cause": "t_end"})  # run again when resumed: done from then on
    resumed.flush()
    resumed.close()
    assert sorted(ChunkStore(out, "fp", resume=True).done) == [0, 1, 2]
