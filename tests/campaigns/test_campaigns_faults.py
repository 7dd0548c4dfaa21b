"""Campaign faults met as users meet them: sizes, resumes, damaged chunks, dead workers.

Each once ended in a traceback, an out-of-memory kill, a mixed table or a
silent exit 0 (found by trying campaigns as a user would).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from support import SPECS

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


def test_a_different_run_timeout_is_another_campaign() -> None:
    """Resuming with another timeout mixed rows run with and without it into one table."""
    points = [{"e": 0.5}, {"e": 0.9}]
    base = _fingerprint("m", RunPlan(t_end=1.0), ["run", "e"], points)
    assert _fingerprint("m", RunPlan(t_end=1.0), ["run", "e"], points) == base
    assert _fingerprint("m", RunPlan(t_end=1.0, timeout=0.5), ["run", "e"], points) != base


def test_a_damaged_chunk_is_named_not_a_traceback(tmp_path: Path) -> None:
    out = tmp_path / "table.csv"
    store = ChunkStore(out, "print", resume=False)
    for run in range(3):
        store.add({"run": run, "cause": "t_end"})
    store.flush()
    (chunk,) = sorted(store.folder.glob("chunk-*.jsonl"))
    assert len(chunk.read_text().splitlines()) == 3
    assert sorted(ChunkStore(out, "print", resume=True).done) == [0, 1, 2]  # read back whole
    chunk.write_text(chunk.read_text()[:25])  # cut short, as a partial copy of the folder
    with pytest.raises(hybrid.UsageError, match=r"chunk-000000\.jsonl: cannot read it .*remove it"):
        ChunkStore(out, "print", resume=True)
    json.loads((store.folder / "campaign.json").read_text())  # the manifest is intact
