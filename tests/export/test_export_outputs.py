"""Output files: atomic (whole or absent), the CSV layout, ``--dt`` grids and ``.npz``."""

from __future__ import annotations

import math
import os
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from support import REPO, SPECS, main_in_process, read_csv, read_json

import hybrid
from hybrid.export import atomic_write, write_csv, write_events, write_npz

H0, G, E = 10.0, 9.81, 0.8
T1 = math.sqrt(2 * H0 / G)


def leftovers(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.iterdir() if p.name.endswith(".tmp"))


@pytest.fixture(scope="module")
def ball_run() -> hybrid.Run:
    return hybrid.simulate(hybrid.load(SPECS / "bouncing_ball.yaml"), t_end=4.0)


class _FailingHalfway:
    """A binary file that writes half of what it is given, then fails like a full disk."""

    def __init__(self, handle: Any) -> None:
        self.handle = handle

    def write(self, data: bytes) -> int:
        self.handle.write(bytes(data)[: max(1, len(data) // 2)])
        self.handle.flush()
        raise OSError(28, "No space left on device")

    def __getattr__(self, name: str) -> Any:
        return getattr(self.handle, name)

    def __enter__(self) -> _FailingHalfway:
        return self

    def __exit__(self, *exc: object) -> None:
        self.handle.close()


@pytest.mark.parametrize(
    ("writer", "name"),
    [(write_csv, "traj.csv"), (write_npz, "traj.npz"), (write_events, "events.json")],
)
@pytest.mark.parametrize("existing", [False, True])
def test_a_write_failing_midway_leaves_no_half_file(
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    ball_run: hybrid.Run,
    writer: Any,
    name: str,
    existing: bool,
) -> None:
    target = tmp_path / name
    if existing:
        target.write_bytes(b"previous complete content\n")
    real_fdopen = os.fdopen
    monkeypatch.setattr(
        "hybrid.files.os.fdopen", lambda *a, **k: _FailingHalfway(real_fdopen(*a, **k))
    )
    with pytest.raises(OSError, match="No space left"):
        writer(ball_run, target)
    if existing:
        assert target.read_bytes() == b"previous complete content\n"
    else:
        assert not target.exists()
    assert leftovers(tmp_path) == []
    assert sorted(p.name for p in tmp_path.iterdir()) == ([name] if existing else [])


def test_the_target_appears_only_when_complete(tmp_path: Path) -> None:
    target = tmp_path / "out.txt"
    target.write_bytes(b"old\n")
    with atomic_write(target) as handle:
        handle.write(b"new, part 1\n")
        assert target.read_bytes() == b"old\n"  # still the old file while writing
        (tmp,) = leftovers(tmp_path)
        assert tmp.startswith(".out.txt.")
        handle.write(b"new, part 2\n")
    assert target.read_bytes() == b"new, part 1\nnew, part 2\n"
    assert leftovers(tmp_path) == []


def test_a_process_killed_mid_write_leaves_the_target_untouched(tmp_path: Path) -> None:
    target = tmp_path / "traj.csv"
    target.write_text("t,j\n0.0,0\n")
    script = textwrap.dedent(
        f"""
        import sys, time
        from hybrid.export import atomic_write
        with atomic_write({str(target)!r}) as handle:
            handle.write(b"t,j\\n0.0,0\\n0.5,")
            handle.flush()
            print("half written", flush=True)
            time.sleep(60)
        """
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, text=True, cwd=REPO
    )
    try:
        assert proc.stdout is not None
        assert proc.stdout.readline().strip() == "half written"
        (tmp,) = leftovers(tmp_path)
        assert (tmp_path / tmp).read_bytes() == b"t,j\n0.0,0\n0.5,"
        assert target.read_text() == "t,j\n0.0,0\n"
    finally:
        proc.kill()
        proc.wait(timeout=30)
        if proc.stdout is not None:
            proc.stdout.close()
    assert proc.returncode != 0
    # the old file is intact; the half-written data is only in the hidden temporary file
    assert target.read_text() == "t,j\n0.0,0\n"
    assert all(name.startswith(".traj.csv.") for name in leftovers(tmp_path))


def test_csv_columns_and_dt_grid(tmp_path: Path) -> None:
    out, events = tmp_path / "ball.csv", tmp_path / "ball.json"
    dt = 0.25
    code = main_in_process(
        "simulate", SPECS / "bouncing_ball.yaml", "--t-end", "5", "--dt", str(dt),
        "--rtol", "1e-10", "--atol", "1e-12", "--out", out, "--events", events,
    )  # fmt: skip
    assert code == 0
    header, rows = read_csv(out)
    assert header == ["t", "j", "location", "h", "v", "energy"]
    jumps = read_json(events)["jumps"]
    jump_times = {e["t"] for e in jumps}
    assert len(jumps) == 2  # impacts at 1.43 and 3.71 (the third is at 5.54)
    assert len(rows) == 21 + 2 * 2  # the grid 0, 0.25, ..., 5 and two rows per jump
    t = np.array([float(r["t"]) for r in rows])
    j = np.array([int(r["j"]) for r in rows])
    on_grid = np.abs(t / dt - np.round(t / dt)) < 1e-9
    off_grid = t[~on_grid]
    assert set(off_grid) <= jump_times, "off the grid only at jumps"
    grid_points = np.round(t[on_grid] / dt).astype(int)
    assert list(grid_points) == list(range(0, 21)), "every grid point, once, in order"
    for jump in jumps:  # pre- and post-jump rows
        (rows_at,) = np.nonzero(t == jump["t"])
        assert list(j[rows_at]) == [jump["j"], jump["j"] + 1]
    # values on the grid follow the closed form of the first flight and bounce
    h = np.array([float(r["h"]) for r in rows])
    first = on_grid & (t < T1)
    np.testing.assert_allclose(h[first], H0 - G * t[first] ** 2 / 2, atol=1e-8)
    v1 = E * math.sqrt(2 * G * H0)
    second = on_grid & (t > T1) & (t < T1 + 2 * v1 / G)
    s = t[second] - T1
    np.testing.assert_allclose(h[second], v1 * s - G * s**2 / 2, atol=1e-8)


def test_npz_round_trips(tmp_path: Path, ball_run: hybrid.Run) -> None:
    path = tmp_path / "ball.npz"
    write_npz(ball_run, path)
    with np.load(path, allow_pickle=False) as data:
        assert list(data["state_names"]) == ["h", "v"]
        assert list(data["signal_names"]) == ["energy"]
        np.testing.assert_array_equal(data["t"], ball_run.t)
        np.testing.assert_array_equal(data["j"], ball_run.j)
        np.testing.assert_array_equal(data["location"], ball_run.location)
        np.testing.assert_array_equal(data["states"], ball_run.states)
        np.testing.assert_array_equal(data["signals"], ball_run.signals)


def test_npz_and_csv_from_the_cli_agree(tmp_path: Path) -> None:
    base = ("simulate", SPECS / "thermostat.yaml", "--t-end", "30", "--dt", "0.5")
    assert main_in_process(*base, "--out", tmp_path / "th.npz") == 0
    assert main_in_process(*base, "--out", tmp_path / "th.csv") == 0
    header, rows = read_csv(tmp_path / "th.csv")
    with np.load(tmp_path / "th.npz", allow_pickle=False) as data:
        assert header == ["t", "j", "location", *data["state_names"], *data["signal_names"]]
        assert [float(r["t"]) for r in rows] == list(data["t"])  # 17 digits: exact
        assert [r["location"] for r in rows] == list(data["location"])
        assert [float(r["T"]) for r in rows] == list(data["states"][:, 0])


def test_bad_output_name_is_a_usage_error(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    code = main_in_process(
        "simulate", SPECS / "bouncing_ball.yaml", "--t-end", "1", "--out", tmp_path / "x.txt"
    )
    assert code == 2
    assert "--out: use a .csv, .npz or .mat" in capsys.readouterr().err
    missing = tmp_path / "no" / "such" / "dir" / "x.csv"
    assert (
        main_in_process("simulate", SPECS / "bouncing_ball.yaml", "--t-end", "1", "--out", missing)
        == 2
    )
    assert "does not exist" in capsys.readouterr().err


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX permissions")
@pytest.mark.parametrize(("umask", "mode"), [(0o022, 0o644), (0o077, 0o600), (0o002, 0o664)])
def test_new_files_get_the_permissions_of_the_umask(
    tmp_path: Path, ball_run: hybrid.Run, umask: int, mode: int
) -> None:
    previous = os.umask(umask)
    try:
        write_csv(ball_run, tmp_path / "traj.csv")
        write_npz(ball_run, tmp_path / "traj.npz")
        write_events(ball_run, tmp_path / "events.json")
        code = main_in_process(
            "simulate", SPECS / "bouncing_ball.yaml", "--t-end", "1",
            "--out", tmp_path / "cli.csv", "--events", tmp_path / "cli.json",
        )  # fmt: skip
    finally:
        os.umask(previous)
    assert code == 0
    for name in ("traj.csv", "traj.npz", "events.json", "cli.csv", "cli.json"):
        assert (tmp_path / name).stat().st_mode & 0o777 == mode, name


@pytest.mark.skipif(sys.platform == "win32", reason="POSIX permissions")
def test_replacing_a_file_keeps_its_permissions(tmp_path: Path, ball_run: hybrid.Run) -> None:
    target = tmp_path / "traj.csv"
    target.write_text("old\n")
    target.chmod(0o640)
    write_csv(ball_run, target)
    assert target.stat().st_mode & 0o777 == 0o640
    assert target.read_text().startswith("t,j,location,h,v,energy\n")
