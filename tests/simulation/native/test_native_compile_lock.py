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

    def waiting() -> None:  # said once, before the wait (the notice of a compiled run)
        with log.open("a") as f:
            f.write("second waits\n")

    with compiling(Generated(source=source), waiting=waiting), log.open("a") as f:
        f.write("second in\n")


@pytest.fixture
def cache_env(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> dict[str, str]:
    from hybrid.simulation.native import cache

    monkeypatch.setenv(cache.CACHE_ENV, str(tmp_path / "cache"))
    return {**os.environ, cache.CACHE_ENV: str(tmp_path / "cache")}


ONE = "# one source\n"
CASES = {
    "same-key-waits": (
        "# one source\n",
        None,
        ["holder in", "second waits", "holder out", "second in"],
    ),
    "other-key-goes-on": ("# another source\n", None, ["holder in", "second in", "holder out"]),
    "sealed-meanwhile-goes-on": (
        "# one source\n",
        "seal",
        ["holder in", "second in", "holder out"],
    ),
    "holder-killed-goes-on": ("# one source\n", "kill", ["holder in", "second in"]),
}
"""What the second process compiles, what happens to the first's key meanwhile (its code
sealed on disk, or its process killed with SIGKILL), and the order the file then holds
("second waits": it was told that it waits, only where it does)."""


@pytest.mark.parametrize("case", list(CASES))
def test_a_second_process_waits_only_while_the_same_key_is_compiled(
    case: str, tmp_path: Path, cache_env: dict[str, str]
) -> None:
    import numba

    from hybrid.simulation.native import cache
    from hybrid.simulation.native.kernel_text import Generated

    second, meanwhile, order = CASES[case]
    log = tmp_path / "order"
    holder = _holder(log, ONE, 60.0 if meanwhile == "kill" else 2.0, cache_env)
    if meanwhile == "seal":  # compiled whole meanwhile (by another process, say)
        key = cache.cache_key(Generated(source=ONE), numba.__version__)
        (cache.cache_root() / key / cache.MANIFEST).write_text("{}")
    elif meanwhile == "kill":  # the lock goes with the process
        holder.send_signal(signal.SIGKILL)
        holder.wait(timeout=60)
    _enter(log, second)
    holder.wait(timeout=60)
    assert log.read_text().splitlines() == order


def test_a_key_is_hashed_once_per_module_and_numba_version(monkeypatch: pytest.MonkeyPatch) -> None:
    import hashlib
    import platform
    import sys

    from hybrid.simulation.native import cache
    from hybrid.simulation.native.kernel_text import Generated

    hashed: list[str] = []
    real = cache._cache_key
    monkeypatch.setattr(cache, "_cache_key", lambda g, v: hashed.append(v) or real(g, v))
    generated = Generated(source=ONE)
    keys = {cache.cache_key(generated, "0.1") for _ in range(3)}
    assert len(keys) == 1 and hashed == ["0.1"]
    # by hand: the versions, the machine and the source, each followed by a zero byte
    digest = hashlib.sha256()
    for part in ("0.1", sys.version, platform.machine(), ONE):
        digest.update(part.encode() + b"\0")
    assert keys == {digest.hexdigest()[:24]}
    assert cache.cache_key(generated, "0.2") not in keys  # another numba: another key
    assert cache.cache_key(Generated(source=ONE + "\n"), "0.1") not in keys
    assert hashed == ["0.1", "0.2", "0.1"]
