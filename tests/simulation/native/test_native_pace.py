"""A compile's notice in this machine's seconds: the last compile's pace, kept in the cache."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from support import SPECS

import hybrid
from hybrid.simulation.native import cache, pace
from hybrid.simulation.native.choice import KERNEL_COMPILE_S, compile_notice

pytest.importorskip("numba")


@pytest.fixture
def empty_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv(cache.CACHE_ENV, str(tmp_path))
    monkeypatch.setattr(cache, "_LOADED", {})  # nothing loaded in this process either
    return tmp_path


def _thermostat_estimate() -> float:
    from hybrid.compose import as_system
    from hybrid.simulation.native.source import generate
    from hybrid.simulation.native.structure import NativeModel

    model = as_system(hybrid.load(SPECS / "thermostat.yaml"))
    return float(generate(NativeModel(model)).compile_estimate)


def test_the_notice_scales_its_estimates_by_the_last_compiles_pace(empty_cache: Path) -> None:
    model = hybrid.load(SPECS / "thermostat.yaml")
    before = compile_notice(model)
    assert before is not None and " here" not in before  # no pace yet: the benchmark's figures
    pace.record(30.0, 10.0, "kernel")  # a compile that waited three times its estimate
    assert pace.pace("kernel") == 3.0
    notice = compile_notice(model)
    assert notice is not None
    kernel_s = 3 * KERNEL_COMPILE_S
    assert _thermostat_estimate() < pace.MIN_ESTIMATE_S  # a short compile: not scaled
    assert f"the compiled loop (once per machine, about {kernel_s:.0f} s here)" in notice
    assert f"the model (about {max(1.0, _thermostat_estimate()):.0f} s)" in notice
    kept = json.loads((empty_cache / pace.PACE_FILE).read_text())
    assert kept == {"kernel": {"pace": 3.0, "waited_s": 30.0, "estimated_s": 10.0}}


def test_a_models_notice_scales_by_the_last_model_compile(empty_cache: Path) -> None:
    """A compile of a model alone is mostly loading: its pace is kept apart from the kernel's."""
    from hybrid.simulation.native.choice import _notice

    pace.record(27.0, 9.0, "kernel")
    assert _notice("missing", "cached", 10.0) == (
        "compiling the model (about 30 s here); later runs load them from the cache"
    )  # no model compile kept yet: the kernel's pace
    assert _notice("missing", "cached", 0.5) == (
        "compiling the model (about 1 s); later runs load them from the cache"
    )  # a short compile, mostly loading: the estimate as it is
    pace.record(1.5, 1.0, "model")  # a small model's compile: not kept either
    assert pace.pace("model") == 3.0
    pace.record(30.0, 15.0, "model")  # a large model's
    assert _notice("missing", "cached", 10.0) == (
        "compiling the model (about 20 s here); later runs load them from the cache"
    )
    assert _notice("missing", "missing", 10.0) == (
        "compiling the compiled loop (once per machine, about 24 s here) and the model "
        "(about 30 s here); later runs load them from the cache"
    )  # a compile with the kernel: the kernel's pace for both
    assert pace.pace("kernel") == 3.0 and pace.pace("model") == 2.0
    assert _notice("missing", "missing", 10.0, waiting=True) == (
        "waiting for another process compiling the compiled loop (once per machine, about "
        "24 s here) and the model (about 30 s here); then loading them"
    )  # another process holds the compile: this one says it waits for it


@pytest.mark.parametrize(
    "text",
    [
        '{"kernel": {"pace": "fast"}}',
        '{"kernel": {"pace": NaN}}',
        '{"kernel": {"pace": 1e9}}',
        '{"kernel": {"pace": true}}',
        '{"kernel": 3.0}',
        '{"pace": 3.0}',
        "[3.0]",
        "{",
        "",
        "\udcff",
    ],
)
def test_a_damaged_pace_is_no_pace(empty_cache: Path, text: str) -> None:
    (empty_cache / pace.PACE_FILE).write_text(text, errors="surrogateescape")
    assert pace.pace("kernel") is None and pace.pace("model") is None
    notice = compile_notice(hybrid.load(SPECS / "thermostat.yaml"))
    assert notice is not None and f"about {KERNEL_COMPILE_S:.0f} s)" in notice
    pace.record(16.0, 8.0, "model")  # a damaged file is replaced whole
    assert pace.pace("model") == 2.0


def test_extreme_waits_are_kept_within_the_range(empty_cache: Path) -> None:
    least, most = pace.PACE_RANGE
    pace.record(1000.0, 10.0, "model")
    assert pace.pace("model") == most
    pace.record(0.001, 8.0, "model")
    assert pace.pace("model") == least
    pace.record(float("nan"), 8.0, "model")  # nothing measured: the last pace stays
    pace.record(5.0, 0.0, "model")  # nothing estimated (nothing compiled): likewise
    pace.record(50.0, pace.MIN_ESTIMATE_S / 2, "model")  # a small compile: likewise
    assert pace.pace("model") == least


def test_a_cache_that_cannot_be_written_keeps_no_pace(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    root = tmp_path / "root"
    root.write_text("a file where the cache directory should be")
    monkeypatch.setenv(cache.CACHE_ENV, str(root))
    # and no private fallback in the temporary directory either (a file in its place)
    monkeypatch.setattr(cache.tempfile, "gettempdir", lambda: str(root))
    monkeypatch.setattr(cache, "_ROOTS", {})
    pace.record(16.0, 8.0, "model")  # no error: the run goes on
    assert pace.pace("model") is None
    assert sorted(p.name for p in tmp_path.iterdir()) == ["root"]  # nothing left beside it


def test_a_missing_cache_root_keeps_no_pace(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv(cache.CACHE_ENV, str(tmp_path / "absent"))
    pace.record(16.0, 8.0, "model")
    assert pace.pace("model") is None and not (tmp_path / "absent").exists()


def test_a_compile_records_what_it_waited_against_what_was_estimated(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A model no cache holds is compiled: its pace is the wait over the estimate of what
    was missing then (the model, and the kernel if this cache has not compiled it yet)."""
    import uuid

    from hybrid.simulation.native import engine
    from hybrid.simulation.native.choice import cached, expected_wait

    rate = 1.0 + uuid.uuid4().int % 10**9 / 1e12  # a structure of its own: not in any cache
    model = hybrid.load_text(
        f"automaton: drift\nstate: {{x: {{initial: 0}}}}\nlocations: {{go: {{flow: {{x: {rate!r}}}}}}}\n"
    )
    states = cached(model)
    assert states[0] == "missing"
    kept: list[tuple[float, float, str]] = []
    monkeypatch.setattr(engine, "record_pace", lambda *args: kept.append(args))
    run = hybrid.simulate(model, t_end=2.0, backend="compiled", handle_sigint=False)
    assert run.states[-1, 0] == pytest.approx(2.0 * rate, rel=1e-12)
    assert len(kept) == 1
    waited, estimated, kind = kept[0]
    # the kernel may have been sealed meanwhile by another process sharing the cache
    assert (estimated, kind) in {
        (expected_wait(*states), "kernel" if states[1] == "missing" else "model"),
        (expected_wait(states[0], "cached", states[2]), "model"),
    }
    assert estimated >= 1.0 and waited > 0.0
    hybrid.simulate(model, t_end=1.0, backend="compiled", handle_sigint=False)
    assert len(kept) == 1  # compiled once: kept once


def test_compiles_ending_together_keep_each_kinds_pace(empty_cache: Path) -> None:
    """The file is read, changed and written by one process at a time: a record waits while
    another holds the lock, then keeps both kinds (unlocked, it wrote over the other's)."""
    import threading

    held = cache.exclusive(empty_cache / pace.PACE_LOCK)
    held.__enter__()
    done = threading.Event()

    def model_compile() -> None:
        pace.record(30.0, 15.0, "model")
        done.set()

    writer = threading.Thread(target=model_compile)
    try:
        writer.start()
        assert not done.wait(0.5)  # it waits for the lock (flock: per open file, so threads too)
        # meanwhile the holder reads, changes and writes the file
        (empty_cache / pace.PACE_FILE).write_text(json.dumps({"kernel": {"pace": 3.0}}))
    finally:
        held.__exit__(None, None, None)
    writer.join(10.0)
    assert done.is_set()
    kept = json.loads((empty_cache / pace.PACE_FILE).read_text())
    assert kept["kernel"] == {"pace": 3.0}
    assert kept["model"] == {"pace": 2.0, "waited_s": 30.0, "estimated_s": 15.0}
