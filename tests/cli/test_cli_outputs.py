"""Outputs that cannot be written: one message, exit 2, before the work, never a traceback.

Every command that writes is run as a user types it (``python -m hybrid`` in a
subprocess) with three kinds of bad output: a path in ``/proc`` (where no file
can be created, even by root), a directory given as the output file, and a
missing parent directory. Each must end with exit 2, one line naming the flag
and the path, and nothing created. A write that fails only at the end (a disk
that filled during the run) keeps what was computed in a folder the message
names.
"""

from __future__ import annotations

import errno
import subprocess
import sys
from pathlib import Path

import pytest
from support import REPO, SPECS, assert_no_traceback, main_in_process, read_csv, run_cli

THERMOSTAT = str(SPECS / "thermostat.yaml")
BALL = str(SPECS / "bouncing_ball.yaml")

# (command words before the output, the flag, how the output is named)
COMMANDS = [
    (["simulate", THERMOSTAT, "--t-end", "1"], "--out", ".csv"),
    (["simulate", THERMOSTAT, "--t-end", "1"], "--events", ".json"),
    (["simulate", THERMOSTAT, "--t-end", "1"], "--plot", ".png"),
    (["sweep", THERMOSTAT, "--t-end", "1", "--grid", "init.T=18:20:2", "--quiet"], "--out", ".csv"),
    (["schema"], "--out", ".json"),
    (["graph", THERMOSTAT], "--out", ".dot"),
    (["export", "spaceex", THERMOSTAT], "--out", ".xml"),
    (["reach", BALL, "--t-end", "1"], "--sets", ".json"),
    (["reach", BALL, "--t-end", "1", "--plot", "h,v"], "--out", ".svg"),
]
IDS = [f"{words[0]}-{flag}" for words, flag, _ in COMMANDS]


def _bad_outputs(tmp_path: Path, suffix: str) -> dict[str, Path]:
    folder = tmp_path / f"folder{suffix}"
    folder.mkdir()
    return {
        "proc": Path(f"/proc/hybrid-test{suffix}"),
        "directory": folder,
        "missing-parent": tmp_path / "missing" / f"out{suffix}",
    }


@pytest.mark.parametrize(("words", "flag", "suffix"), COMMANDS, ids=IDS)
def test_an_output_that_cannot_be_written_is_refused_before_the_work(
    tmp_path: Path, words: list[str], flag: str, suffix: str
) -> None:
    for kind, bad in _bad_outputs(tmp_path, suffix).items():
        before = sorted(tmp_path.rglob("*"))
        done = run_cli(*words, flag, bad)
        assert_no_traceback(done.stderr)
        assert done.returncode == 2, (kind, done.stderr)
        lines = done.stderr.strip().splitlines()
        assert len(lines) == 1, (kind, done.stderr)
        assert flag in lines[0] and str(bad) in lines[0], (kind, lines[0])
        expected = {
            "proc": "cannot write",
            "directory": "is a directory",
            "missing-parent": "does not exist",
        }[kind]
        assert expected in lines[0], (kind, lines[0])
        assert sorted(tmp_path.rglob("*")) == before, f"{kind}: something was created"
        assert done.stdout == "", (kind, done.stdout)


@pytest.mark.parametrize(
    "words",
    [
        ["falsify", THERMOSTAT, "--requirement", "r", "--vary", "init.T=18:20", "--budget", "2",
         "--t-end", "1"],
        ["import", "spaceex", str(Path(__file__).parents[1] / "data" / "spaceex" / "bball" / "bball.xml")],
    ],
    ids=["falsify", "import"],
)  # fmt: skip
def test_an_output_directory_that_cannot_be_made_is_refused(
    tmp_path: Path, words: list[str]
) -> None:
    a_file = tmp_path / "a-file"
    a_file.write_text("")
    for bad, says in [
        (Path("/proc/hybrid-test-dir"), "cannot write"),
        (a_file, "exists and is not a directory"),
        (a_file / "below", "is not a directory"),
    ]:
        done = run_cli(*words, "--out", bad)
        assert_no_traceback(done.stderr)
        assert done.returncode == 2, done.stderr
        assert says in done.stderr and "--out" in done.stderr, done.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a-file"]


def test_a_missing_output_directory_is_created_only_when_written(tmp_path: Path) -> None:
    target = tmp_path / "new" / "deeper"
    xml = Path(__file__).parents[1] / "data" / "spaceex" / "bball" / "bball.xml"
    done = run_cli("import", "spaceex", xml, "--out", target)
    assert done.returncode == 0, done.stderr
    assert Path(done.stdout.strip()).is_file()
    refused = run_cli("falsify", THERMOSTAT, "--requirement", "nope", "--vary", "init.T=18:20",
                      "--budget", "2", "--t-end", "1", "--out", tmp_path / "never")  # fmt: skip
    assert refused.returncode == 2
    assert not (tmp_path / "never").exists()  # refused before anything was created


def test_a_write_that_fails_at_the_end_keeps_the_output_elsewhere(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """The disk fills during the run: --out is kept in a folder the message names, exit 2."""
    import hybrid.export.trajectory as trajectory

    out, events = tmp_path / "ball.csv", tmp_path / "ball.json"
    real = trajectory.write_csv

    def full_disk(run: object, path: str | Path, *args: object, **kwargs: object) -> None:
        if Path(path) == out:
            raise OSError(errno.ENOSPC, "No space left on device", str(path))
        real(run, path, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(trajectory, "write_csv", full_disk)
    code = main_in_process("simulate", BALL, "--t-end", "3", "--out", out, "--events", events)
    err = capsys.readouterr().err
    assert code == 2, err
    assert "No space left on device" in err and "kept in " in err
    kept = Path(err.split("kept in ")[1].split()[0].rstrip(";"))
    assert kept.name == "ball.csv" and not out.exists()
    assert events.is_file()  # the other output was written all the same
    header, rows = read_csv(kept)
    assert header[:2] == ["t", "j"]
    # the ball falls from 10 m: the first bounce at sqrt(2 h / g), kept like any other point
    first_bounce = (2 * 10 / 9.81) ** 0.5
    assert any(abs(float(r["t"]) - first_bounce) < 1e-6 for r in rows)
    assert float(rows[-1]["t"]) == pytest.approx(3.0)


def test_a_reader_that_stops_early_is_not_a_broken_worker() -> None:
    """``hybrid check --format junit specs/*.yaml | head -1`` said 'a connection broke (a
    worker process died?)' and exited 1: the reader had all it wanted, no worker is involved."""
    import subprocess
    import sys

    from support import REPO

    specs = sorted(str(p) for p in SPECS.glob("*.yaml"))
    writer = subprocess.Popen([sys.executable, "-m", "hybrid", "check", "--format", "junit", *specs],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=REPO)  # fmt: skip
    assert writer.stdout is not None and writer.stderr is not None
    writer.stdout.close()  # before the report is written: every write of it fails
    said = writer.stderr.read().decode()
    assert writer.wait(timeout=300) == 0, said
    assert said == ""


# A process given HEADROOM bytes of address space more than it holds once the command
# line's module is imported (scipy's import fits in it; the run's points do not).
MEMORY_BOUND = """
import resource, sys
from hybrid.cli.main import entry
with open("/proc/self/statm") as f:
    held = int(f.read().split()[0]) * resource.getpagesize()
limit = held + int(sys.argv.pop(1))
resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
sys.argv[0] = "hybrid"
sys.exit(entry())
"""


@pytest.mark.skipif(not Path("/proc/self/statm").exists(), reason="reads /proc (Linux)")
@pytest.mark.parametrize(
    ("headroom", "t_end", "dt"),
    [
        (2**30, "9.99", "1e-7"),  # steps of a million points each: a large array fails
        (400 * 2**20, "9999", "1e-4"),  # steps of a few thousand: memory fills to the last byte
    ],
)
def test_a_run_out_of_memory_ends_in_one_line(
    tmp_path: Path, headroom: int, t_end: str, dt: str
) -> None:
    """A machine fault, as a full disk is: one line naming the file, exit 2, no traceback.

    Memory filled to the last byte used to end in "SystemError: error return without
    exception set": the frame stack's room (:mod:`hybrid.frames`) made its frame's
    object, half a megabyte, only as the MemoryError left it, and that failed too.
    """
    out = tmp_path / "run.npz"
    argv = [str(headroom), "simulate", THERMOSTAT, "--t-end", t_end, "--dt", dt, "--out", str(out)]
    done = subprocess.run([sys.executable, "-c", MEMORY_BOUND, *argv], capture_output=True,
                          text=True, cwd=REPO, timeout=300, check=False)  # fmt: skip
    assert_no_traceback(done.stderr)
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert lines[-1].startswith(f"{THERMOSTAT}: out of memory"), done.stderr
    assert "a larger --dt" in lines[-1]
    assert not out.exists()


def test_graph_takes_its_format_from_the_out_name_and_refuses_a_contradiction(
    tmp_path: Path,
) -> None:
    """Before: `hybrid graph --out g.svg` wrote DOT text into g.svg, and `--format png --out
    g.svg` PNG data, both with exit 0 (simulate, sweep and export refuse such names)."""
    thermostat = SPECS / "thermostat.yaml"
    for name, starts in (("g.mmd", "stateDiagram-v2"), ("g.gv", "digraph"), ("g.txt", "digraph")):
        done = run_cli("graph", thermostat, "--out", tmp_path / name)
        assert done.returncode == 0, done.stderr
        assert (tmp_path / name).read_text().lstrip().startswith(starts)
    out = tmp_path / "g.svg"
    done = run_cli("graph", thermostat, "--format", "png", "--out", out)
    assert done.returncode == 2 and not out.exists()
    assert_no_traceback(done.stderr)
    assert done.stderr.strip() == (
        f"{thermostat}: --out {out}: the name says svg, --format says png; leave out "
        "--format (the name decides), or name the file .png"
    )


@pytest.mark.parametrize("words", [
    ["simulate", THERMOSTAT, "--t-end", "1", "--out"],
    ["sweep", THERMOSTAT, "--t-end", "1", "--grid", "init.T=18:20:2", "--quiet", "--out"],
])  # fmt: skip
def test_an_empty_output_name_is_said_to_be_empty(words: list[str]) -> None:
    """--out "" said "'' is a directory" (an empty path is the current directory)."""
    done = run_cli(*words, "")
    assert done.returncode == 2 and done.stderr.strip().endswith("--out: the file name is empty")
    assert_no_traceback(done.stderr)
