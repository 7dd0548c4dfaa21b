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
from pathlib import Path

import pytest

from hybrid.simulation.native import cache, frames, shares
from hybrid.simulation.native.frames import with_frame_room

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


@pytest.mark.skipif(sys.version_info >= (3, 13), reason="3.13 and later may keep a chunk back")
def test_the_same_calls_without_it_fault_at_every_crossing() -> None:
    """What the room is for, measured the same way: the sweep can see it."""
    _faults_of_a_sweep()
    assert _faults_of_a_sweep() >= CALLS_AT_EACH_DEPTH


def test_it_returns_and_raises_what_the_call_does() -> None:
    assert with_frame_room(divmod, 7, 2) == (3, 1)
    with pytest.raises(ZeroDivisionError):
        with_frame_room(divmod, 1, 0)


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
