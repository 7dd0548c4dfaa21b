"""Writing to a link, a device or a pipe: written through or into, never replaced by a file.

The writers used to rename their temporary file over whatever the path named,
so a symbolic link became a file (its target untouched), and a device or a FIFO
became a regular file: as root, ``--out /dev/null`` would have replaced the
system's ``/dev/null``. The devices here are made with ``mknod`` in the test's
own folder (root only), never the system's.
"""

from __future__ import annotations

import errno
import os
import stat
import threading
from pathlib import Path

import pytest
from support import SPECS, main_in_process

import hybrid
from hybrid.errors import CannotWrite
from hybrid.export import write_csv, write_events

BALL = SPECS / "bouncing_ball.yaml"


@pytest.fixture(scope="module")
def run() -> hybrid.Run:
    return hybrid.simulate(hybrid.load(BALL), t_end=2.0)


def _csv_bytes(run: hybrid.Run, folder: Path) -> bytes:
    plain = folder / "plain.csv"
    write_csv(run, plain)
    return plain.read_bytes()


def _device(path: Path, minor: int) -> Path:
    """A character device of the memory driver (major 1): 3 is null, 7 is full."""
    if os.geteuid() != 0:
        pytest.skip("making a device needs root")
    os.mknod(path, 0o666 | stat.S_IFCHR, os.makedev(1, minor))
    return path


def test_a_link_is_written_through_and_stays_a_link(tmp_path: Path, run: hybrid.Run) -> None:
    real = tmp_path / "real.csv"
    real.write_text("old\n")
    link = tmp_path / "link.csv"
    link.symlink_to("real.csv")
    write_csv(run, link)
    assert link.is_symlink() and os.readlink(link) == "real.csv"
    assert real.read_bytes() == _csv_bytes(run, tmp_path)


def test_a_link_to_a_file_not_there_yet_creates_that_file(tmp_path: Path, run: hybrid.Run) -> None:
    link = tmp_path / "link.json"
    link.symlink_to("made.json")
    write_events(run, link)
    assert link.is_symlink() and (tmp_path / "made.json").read_text().startswith("{")


def test_a_fifo_is_written_into_and_stays_a_fifo(tmp_path: Path, run: hybrid.Run) -> None:
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    received: list[bytes] = []
    reader = threading.Thread(target=lambda: received.append(fifo.read_bytes()), daemon=True)
    reader.start()
    write_csv(run, fifo)
    reader.join(timeout=30)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    assert received == [_csv_bytes(run, tmp_path)]


def test_a_device_is_written_into_and_stays_a_device(tmp_path: Path, run: hybrid.Run) -> None:
    null = _device(tmp_path / "null.csv", 3)
    write_csv(run, null)
    assert stat.S_ISCHR(os.lstat(null).st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["null.csv"]  # no temporary left


def test_a_full_device_is_a_cannot_write(tmp_path: Path, run: hybrid.Run) -> None:
    full = _device(tmp_path / "full.csv", 7)
    with pytest.raises(CannotWrite) as caught:
        write_csv(run, full)
    assert caught.value.errno == errno.ENOSPC
    assert stat.S_ISCHR(os.lstat(full).st_mode)


def test_the_command_line_keeps_what_a_full_device_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    full = _device(tmp_path / "full.csv", 7)
    assert main_in_process("simulate", BALL, "--t-end", "2", "--out", full, "--quiet") == 2
    err = capsys.readouterr().err
    assert "No space left on device; kept in " in err, err
    kept = Path(err.rsplit("kept in ", 1)[1].strip())
    assert kept.read_text().startswith("t,j,location,h,v")
    assert stat.S_ISCHR(os.lstat(full).st_mode)


def test_a_link_into_a_missing_folder_is_refused_before_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    link = tmp_path / "out.csv"
    link.symlink_to("nowhere/out.csv")
    assert main_in_process("simulate", BALL, "--t-end", "2", "--out", link) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert "points into a folder that does not exist" in captured.err
