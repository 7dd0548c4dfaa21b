"""Two processes about to compile the same code at once: one compiles, the other waits.

Two pytest workers on an empty cache each compiled the kernel at once (55 s of one core
each, in the same minute of a CI run). :func:`~hybrid.simulation.native.cache.compiling`
is held by the process that compiles a key; another waits for it, then loads from the
cache. The order of what each process does is written to one file and read back.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

pytest.importorskip("numba")
pytest.importorskip("fcntl")

HOLDER = """
import sys, time
from pathlib import Path
from hybrid.simulation.native.cache import compiling
from hybrid.simulation.native.kernel_text import Generated
log = Path(sys.argv[1])
with compiling(Generated(source=sys.argv[2])):
    with log.open("a") as f:
        f.write("holder in\\n")
    time.sleep(float(sys.argv[3]))
    with log.open("a") as f:
        f.write("holder out\\n")
"""


def _holder(log: Path, source: str, seconds: float, env: dict[str, str]) -> subprocess.Popen[str]:
    process = subprocess.Popen(
        [sys.executable, "-c", HOLDER, str(log), source, str(seconds)], env=env, text=True
    )
    for _ in range(600):  # until it holds the lock (its first line)
        if log.exists() and "holder in" in log.read_text():
            return process
        if process.poll() is not None:
            raise AssertionError(f"the holder ended first: {process.returncode}")
        time.sleep(0.05)
    raise AssertionError("the holder never took the lock")


def _enter(log: Path, source: str) -> None:
    from hybrid.simulation.native.cache import compiling
    from hybrid.simulation.native.kernel_text import Generated

    with compiling(Generated(source=source)), log.open("a") as f:
        f.write("second in\n")


@pytest.fixture
def cache_env(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> dict[str, str]:
    from hybrid.simulation.native import cache

    monkeypatch.setenv(cache.CACHE_ENV, str(tmp_path / "cache"))
    return {**os.environ, cache.CACHE_ENV: str(tmp_path / "cache")}


def test_a_second_process_waits_for_the_one_compiling_the_same_key(
    tmp_path: Path, cache_env: dict[str, str]
) -> None:
    log = tmp_path / "order"
    holder = _holder(log, "# one source\n", 1.0, cache_env)
    _enter(log, "# one source\n")
    holder.wait(timeout=60)
    assert log.read_text().splitlines() == ["holder in", "holder out", "second in"]


def test_other_code_is_not_held_up(tmp_path: Path, cache_env: dict[str, str]) -> None:
    log = tmp_path / "order"
    holder = _holder(log, "# one source\n", 3.0, cache_env)
    _enter(log, "# another source\n")
    holder.wait(timeout=60)
    assert log.read_text().splitlines() == ["holder in", "second in", "holder out"]


def test_code_sealed_in_the_cache_is_loaded_without_waiting(
    tmp_path: Path, cache_env: dict[str, str]
) -> None:
    import numba

    from hybrid.simulation.native import cache
    from hybrid.simulation.native.kernel_text import Generated

    log = tmp_path / "order"
    holder = _holder(log, "# one source\n", 3.0, cache_env)
    key = cache.cache_key(Generated(source="# one source\n"), numba.__version__)
    (cache.cache_root() / key / cache.MANIFEST).write_text("{}")  # compiled whole meanwhile
    _enter(log, "# one source\n")
    holder.wait(timeout=60)
    assert log.read_text().splitlines() == ["holder in", "second in", "holder out"]


def test_a_holder_killed_mid_compile_holds_nothing(
    tmp_path: Path, cache_env: dict[str, str]
) -> None:
    log = tmp_path / "order"
    holder = _holder(log, "# one source\n", 60.0, cache_env)
    holder.send_signal(signal.SIGKILL)
    holder.wait(timeout=60)
    _enter(log, "# one source\n")  # the lock went with the process
    assert log.read_text().splitlines() == ["holder in", "second in"]
