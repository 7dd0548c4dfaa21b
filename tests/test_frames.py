"""Room on the frame stack for compiles: calls that go back and forth across a chunk's end.

CPython keeps a thread's frames in chunks of 16 KiB; on the Pythons without
gh-142183's fix, a call tree crossing a chunk's end maps a chunk and faults it in
every time it crosses. The sweep below calls down to every depth from 0 to 399
and, there, makes 1,000 calls one frame deeper: some depth puts those calls on
the far side of a chunk's end, which costs a page fault each.
"""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
from support import in_the_frame_room

import hybrid
from hybrid import frames
from hybrid.frames import in_frame_room, with_frame_room
from hybrid.simulation.native import cache, shares

resource = pytest.importorskip("resource")  # page-fault counts: not on Windows

CALLS_AT_EACH_DEPTH = 1_000


def _leaf() -> int:
    return 1


def _down(depth: int) -> int:
    if depth:
        return _down(depth - 1)
    return sum(_leaf() for _ in range(CALLS_AT_EACH_DEPTH))


def _faults_of_a_sweep() -> int:
    before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
    for depth in range(400):  # about 4,000 slots of frames: two chunks' ends at least
        assert _down(depth) == CALLS_AT_EACH_DEPTH
    return int(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)


def test_calls_in_the_room_cross_no_chunk_end() -> None:
    _faults_of_a_sweep()  # the sweep's own first allocations
    assert with_frame_room(_faults_of_a_sweep) < CALLS_AT_EACH_DEPTH


def test_a_room_inside_a_room_is_a_plain_call() -> None:
    """``check`` runs ``reach``, an import loads the spec it wrote: each in the room. A
    second room's frame would fit in what the first chunk has left and leave its callees a
    few hundred slots (2,969 faults for this sweep, measured without the rule)."""

    def thirty_frames_down(depth: int = 30) -> int:
        return thirty_frames_down(depth - 1) if depth else with_frame_room(_faults_of_a_sweep)

    _faults_of_a_sweep()
    assert with_frame_room(with_frame_room, _faults_of_a_sweep) < CALLS_AT_EACH_DEPTH
    assert with_frame_room(thirty_frames_down) < CALLS_AT_EACH_DEPTH
    assert in_frame_room(in_frame_room(_faults_of_a_sweep))() < CALLS_AT_EACH_DEPTH


def test_the_room_is_left_when_its_call_raises() -> None:
    with pytest.raises(ZeroDivisionError):
        with_frame_room(divmod, 1, 0)
    _faults_of_a_sweep()
    assert with_frame_room(_faults_of_a_sweep) < CALLS_AT_EACH_DEPTH  # a room again, not plain
    assert not frames._INSIDE.inside


@pytest.mark.skipif(sys.version_info >= (3, 13), reason="3.13 and later may keep a chunk back")
def test_the_same_calls_without_it_fault_at_every_crossing() -> None:
    """What the room is for, measured the same way: the sweep can see it."""
    _faults_of_a_sweep()
    assert _faults_of_a_sweep() >= CALLS_AT_EACH_DEPTH


def test_it_returns_and_raises_what_the_call_does() -> None:
    assert with_frame_room(divmod, 7, 2) == (3, 1)
    assert with_frame_room(int, "ff", base=16) == 255
    with pytest.raises(ZeroDivisionError):
        with_frame_room(divmod, 1, 0)
    roomy = in_frame_room(divmod)
    assert roomy(7, 2) == (3, 1) and roomy.__wrapped__ is divmod


ROOT = Path(__file__).resolve().parent.parent


def _at(depth: int, fn: Callable[[], int]) -> int:
    return _at(depth - 1, fn) if depth else fn()


def _worst_faults_of_a_run(simulate: Callable[[], object]) -> int:
    """The most page faults a run cost, called from each depth 0 to 239 of this test's."""

    def faults() -> int:
        before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        simulate()
        return int(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)

    simulate()
    return max(_at(depth, faults) for depth in range(240))  # a chunk's frames of _at and more


def test_a_scipy_run_costs_no_page_faults_from_any_depth() -> None:
    model = hybrid.load(ROOT / "specs" / "thermostat.yaml")
    worst = _worst_faults_of_a_run(lambda: hybrid.simulate(model, t_end=50.0, handle_sigint=False))
    assert worst < 200


@pytest.mark.skipif(sys.version_info >= (3, 13), reason="3.13 and later may keep a chunk back")
def test_the_same_run_outside_the_room_faults_at_some_depth() -> None:
    """What the room is for: the scipy backend's run itself, called without it."""
    from hybrid.compose import as_system
    from hybrid.simulation.reference import simulate_reference
    from hybrid.simulation.settings import Settings

    model = as_system(hybrid.load(ROOT / "specs" / "thermostat.yaml"))
    settings = Settings(t_end=50.0)
    plain = simulate_reference.__wrapped__  # type: ignore[attr-defined]
    assert _worst_faults_of_a_run(lambda: plain(model, settings, None, None, False, None)) >= 500


def test_load_check_reach_and_import_do_their_work_in_the_room(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from hybrid.interchange import importer
    from hybrid.reach import api as reach_api
    from hybrid.reach import check as reach_check
    from hybrid.reader import loader

    seen: list[tuple[str, bool]] = []

    def spy(module: object, name: str) -> None:
        inner = getattr(module, name)

        def spied(*args: object, **kwargs: object) -> object:
            seen.append((name, in_the_frame_room()))
            return inner(*args, **kwargs)

        monkeypatch.setattr(module, name, spied)

    spy(loader, "read_yaml_file")
    spy(reach_check, "analysis_check")
    spy(reach_api, "explore")
    spy(importer, "read_model")
    model = hybrid.load(ROOT / "specs" / "thermostat.yaml")
    hybrid.check(model)
    hybrid.reach(model, t_end=1.0)
    importer.import_spaceex(ROOT / "tests" / "data" / "spaceex" / "bball" / "bball.xml")
    assert {name for name, _ in seen} == {"read_yaml_file", "analysis_check", "explore", "read_model"}
    assert all(in_room for _, in_room in seen)


# a generated module in miniature: its build() writes down who called it
BUILD = """
import sys

def build():
    caller = sys._getframe(1).f_code
    with open(OUT, "w") as f:
        f.write(caller.co_filename + " " + caller.co_name)
"""


def _module(tmp_path: Path) -> tuple[Path, Path]:
    path, out = tmp_path / "hybrid_native_framestest.py", tmp_path / "caller.txt"
    path.write_text(BUILD.replace("OUT", repr(str(out))))
    return path, out


def test_a_generated_module_is_built_in_the_room(tmp_path: Path) -> None:
    path, out = _module(tmp_path)
    try:
        cache._import("hybrid_native_framestest", path)
    finally:
        sys.modules.pop("hybrid_native_framestest", None)
    assert out.read_text() == f"{frames.__file__} {frames._call.__name__}"


def test_a_worker_builds_its_share_in_the_room(tmp_path: Path) -> None:
    path, out = _module(tmp_path)
    argv = [str(path), "hybrid_native_framestest", json.dumps(sys.path)]
    subprocess.run([sys.executable, "-c", shares._WORKER, *argv], check=True, timeout=120)
    assert out.read_text() == f"{frames.__file__} {frames._call.__name__}"
