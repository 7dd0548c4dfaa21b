"""Ctrl-C (and kill -9) at any moment of any command: no traceback, no partial file.

Each command runs as a user types it (``python -m hybrid`` in a process of its
own) and receives SIGINT after a random delay drawn over its whole life from the
moment ``main`` runs: the heavy imports, loading the spec, compiling a model for
the compiled backend (with an empty cache, so the compile is under way), the
run, and the writing. Before that (measured here as :func:`interpreter_start`,
twice over, as a loaded machine stretches it): the interpreter's own start-up and
the import of the command line's few light modules; a Ctrl-C there is reported
by Python itself (docs/cli.md). Whatever the moment:

* stderr holds no traceback;
* the exit code is one the docs give for it (0 or 1 when the command finished
  first, 1 for a run or campaign ended early as ``interrupted``, and 130 for an
  interruption the command could not turn into a result: either ``exit(130)`` or,
  as CPython ends a process whose interrupt reached an import's own code, death
  by SIGINT, which a shell reports as the same 130);
* every output named on the command line is absent or complete (it parses and
  ends where the events file says), and no hidden temporary file is left.

``make fuzz`` sends many more signals (``HYBRID_INTERRUPT_ANYWHERE``) and adds
kill -9 at random moments, after which outputs are absent or complete, and a
sweep killed half-way and resumed gives the table of an uninterrupted run.
"""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path
from types import SimpleNamespace

import pytest
from support import REPO, SPECS, assert_no_traceback, read_csv, run_cli

MOMENTS = int(os.environ.get("HYBRID_INTERRUPT_ANYWHERE", "2"))
"""Signals sent per command in the suite (``make fuzz`` sends 25)."""
SEED = int(os.environ.get("HYBRID_FUZZ_SEED", "20261125"))

THERMOSTAT = str(SPECS / "thermostat.yaml")
BALL = str(SPECS / "bouncing_ball.yaml")
SPACEEX = str(REPO / "tests" / "data" / "spaceex" / "bball" / "bball.xml")

# name -> (command words with {out}/{events}/{dir} placeholders, the longest delay in s)
COMMANDS: dict[str, tuple[list[str], float]] = {
    "validate": (["validate", THERMOSTAT, BALL], 1.0),
    "check": (["check", THERMOSTAT, BALL], 1.5),
    "simulate-scipy": (
        ["simulate", BALL, "--t-end", "6", "--max-step", "0.0005", "--out", "{out}",
         "--events", "{events}"],
        3.0,
    ),
    "simulate-compiled-cold": (
        ["simulate", THERMOSTAT, "--t-end", "50", "--backend", "compiled", "--out", "{out}",
         "--events", "{events}"],
        4.0,
    ),
    "sweep": (
        ["sweep", THERMOSTAT, "--t-end", "20", "--grid", "init.T=16:24:6", "--workers", "0",
         "--quiet", "--out", "{out}"],
        3.0,
    ),
    "import": (["import", "spaceex", SPACEEX, "--out", "{dir}"], 1.0),
    "schema": (["schema", "--out", "{json}"], 0.8),
}  # fmt: skip
EXITS = {0, 1, 130, -signal.SIGINT}


def interpreter_start() -> float:
    """Seconds until an interpreter has imported hybrid's entry (the max of 3 tries).

    That is the window before :func:`hybrid.__main__.entry` can catch anything:
    Python's own start-up (``site``), then ``hybrid/__init__`` (the version and the
    table of lazy names) and ``hybrid.interrupted``, 25 to 30 ms on an idle machine.
    """
    times = []
    for _ in range(3):
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", "import hybrid.__main__"], check=True, cwd=REPO)
        times.append(time.perf_counter() - start)
    return max(times)


def _words(template: list[str], folder: Path) -> list[str]:
    names = {
        "out": str(folder / "out.csv"),
        "events": str(folder / "events.json"),
        "dir": str(folder / "imported"),
        "json": str(folder / "schema.json"),
    }
    return [w.format(**names) if "{" in w else w for w in template]


def _start(words: list[str], env: dict[str, str]) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "hybrid", *words],
        cwd=REPO,
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )


def _env(folder: Path) -> dict[str, str]:
    # an empty cache per command: the compiled backend compiles while signals arrive
    return {**os.environ, "PYTHONDONTWRITEBYTECODE": "1",
            "HYBRID_NATIVE_CACHE": str(folder / "cache")}  # fmt: skip


def check_outputs_whole(folder: Path) -> None:
    """Every output is absent or complete; no temporary file is left behind."""
    leftovers = [p for p in folder.rglob(".*.tmp") if "cache" not in p.parts]
    assert not leftovers, leftovers
    out, events = folder / "out.csv", folder / "events.json"
    if events.exists():
        doc = json.loads(events.read_text())
        if out.exists() and "termination" in doc:
            _, rows = read_csv(out)
            assert float(rows[-1]["t"]) == doc["termination"]["t"]
    elif out.exists():
        header, rows = read_csv(out)  # a sweep's table, or a trajectory: whole rows
        assert rows and all(len(r) == len(header) for r in rows)
    schema = folder / "schema.json"
    if schema.exists():
        assert json.loads(schema.read_text())["$schema"].startswith("http")
    imported = folder / "imported"
    if imported.exists():
        for spec in imported.glob("*.yaml"):
            assert run_cli("validate", spec).returncode == 0, spec


@pytest.mark.parametrize("name", list(COMMANDS))
def test_ctrl_c_at_random_moments_prints_no_traceback(name: str, tmp_path: Path) -> None:
    template, longest = COMMANDS[name]
    rng = random.Random(f"{SEED}-{name}")
    floor = 2 * interpreter_start()  # twice its slowest of three: the child may be slower
    for k in range(MOMENTS):
        folder = tmp_path / f"m{k}"
        folder.mkdir()
        delay = rng.uniform(floor, floor + longest)
        process = _start(_words(template, folder), _env(folder))
        time.sleep(delay)
        process.send_signal(signal.SIGINT)
        _, stderr = process.communicate(timeout=300)
        where = f"{name}: SIGINT after {delay:.3f} s"
        assert_no_traceback(stderr)
        assert process.returncode in EXITS, f"{where}: exit {process.returncode}\n{stderr}"
        if process.returncode in (130, -signal.SIGINT):
            assert "interrupted" in stderr, f"{where}: {stderr}"
        check_outputs_whole(folder)


_STOPPED_IMPORT = """
import sys
stop_at = sys.argv.pop(1)
class Stop:  # a Ctrl-C that lands while the module stop_at is being imported
    def find_spec(self, name, path=None, target=None):
        if name == stop_at:
            raise KeyboardInterrupt
sys.meta_path.insert(0, Stop())
from hybrid.__main__ import entry
sys.exit(entry())
"""


@pytest.mark.parametrize(
    "module", ["hybrid.errors", "argparse", "hybrid.cli.main", "hybrid.cli.exits", "pydantic"]
)
def test_a_ctrl_c_while_the_command_line_is_imported_ends_in_one_line(module: str) -> None:
    """The console script and ``python -m hybrid`` call :func:`hybrid.__main__.entry`,
    which imports the command line inside its Ctrl-C handling: a Ctrl-C while any of
    it is imported (the errors, argparse, the command line itself, or pydantic under
    ``validate``) prints one line and exits with 130, never a traceback. The console
    script named ``hybrid.cli.main:entry`` before: the same Ctrl-C printed Python's
    traceback, as the first of these modules is imported before that entry exists."""
    from importlib.metadata import entry_points

    (script,) = entry_points(group="console_scripts", name="hybrid")
    assert script.value == "hybrid.__main__:entry"
    from hybrid.cli.exits import EXIT_ABANDONED

    done = subprocess.run(
        [sys.executable, "-c", _STOPPED_IMPORT, module, "validate", THERMOSTAT],
        cwd=REPO, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert_no_traceback(done.stderr)
    assert (done.returncode, done.stderr) == (EXIT_ABANDONED, "hybrid: interrupted\n")


@pytest.mark.fuzz
@pytest.mark.parametrize("backend", ["scipy", "compiled"])
def test_kill_9_at_random_moments_leaves_outputs_absent_or_whole(
    backend: str, tmp_path: Path
) -> None:
    rng = random.Random(f"{SEED}-kill-{backend}")
    template = ["simulate", BALL, "--t-end", "6", "--max-step", "0.0005", "--backend", backend,
                "--out", "{out}", "--events", "{events}"]  # fmt: skip
    for k in range(max(1, MOMENTS // 2)):
        folder = tmp_path / f"m{k}"
        folder.mkdir()
        process = _start(_words(template, folder), _env(folder))
        time.sleep(rng.uniform(0.0, 4.0))
        process.kill()
        process.communicate(timeout=60)
        # a hard kill may leave the hidden temporary file, never a half-written output
        for target in ("out.csv", "events.json"):
            path = folder / target
            if path.exists() and target == "events.json":
                json.loads(path.read_text())
            elif path.exists():
                header, rows = read_csv(path)
                assert rows and all(len(r) == len(header) for r in rows)


SWEEP = ["sweep", THERMOSTAT, "--t-end", "30", "--grid", "init.T=16:24:12", "--workers", "1",
         "--max-step", "0.01", "--quiet", "--out", "{out}"]  # fmt: skip


@pytest.mark.fuzz
def test_a_sweep_stopped_at_random_moments_resumes_to_the_uninterrupted_table(
    tmp_path: Path,
) -> None:
    """SIGINT or kill -9 at a random moment, then ``--resume``: the same table as one whole run."""
    whole = tmp_path / "whole"
    whole.mkdir()
    done = run_cli(*_words(SWEEP, whole), timeout=300)
    assert done.returncode in (0, 1), done.stderr
    reference = (whole / "out.csv").read_text()
    rng = random.Random(f"{SEED}-sweep-resume")
    floor = 2 * interpreter_start()
    for k in range(max(1, MOMENTS // 2)):
        folder = tmp_path / f"m{k}"
        folder.mkdir()
        words = _words(SWEEP, folder)
        process = _start(words, _env(folder))
        time.sleep(rng.uniform(floor, floor + 4.0))
        if k % 2:
            process.kill()
        else:
            process.send_signal(signal.SIGINT)
        _, stderr = process.communicate(timeout=300)
        assert_no_traceback(stderr)
        out = folder / "out.csv"
        if out.exists():  # it finished before the signal
            assert out.read_text() == reference
            continue
        again = run_cli(*words, "--resume", timeout=300)
        assert_no_traceback(again.stderr)
        assert again.returncode in (0, 1), again.stderr
        assert out.read_text() == reference
        assert not out.with_name("out.csv.parts").exists()


def test_finalizer_errors_are_reported_until_a_ctrl_c_stopped_work(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A compile stopped half-way leaves LLVM handles whose finalizers fail as the process
    ends (make fuzz saw 'Exception ignored in ... PassBuilder'): after a Ctrl-C the command
    keeps quiet about them; before one, Python's report stands."""
    import importlib

    cli_main = importlib.import_module("hybrid.cli.main")  # hybrid.cli.main is also the function

    from hybrid.simulation import interrupts

    reported: list[object] = []
    monkeypatch.setattr(sys, "__unraisablehook__", reported.append)
    monkeypatch.setattr(cli_main, "_STOPPED", [False])
    monkeypatch.setattr(interrupts, "_SEEN", [False])  # other tests here pressed Ctrl-C
    failed = SimpleNamespace(exc_type=RuntimeError, exc_value=RuntimeError("finalizer failed"))
    cli_main._quiet_after_interrupt(failed)
    assert reported == [failed]
    monkeypatch.setattr(cli_main, "_STOPPED", [True])
    cli_main._quiet_after_interrupt(SimpleNamespace(exc_type=RuntimeError))
    assert reported == [failed]


def test_a_ctrl_c_python_drops_in_a_callback_is_delivered_again(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A Ctrl-C raised inside a callback (an import's module lock) is reported by Python
    as 'Exception ignored in ...' with a traceback, and dropped (CI saw it in ``hybrid
    check``). The hook reports nothing and raises SIGINT again, for the command's handler;
    not once the command has stopped on a Ctrl-C."""
    import importlib

    cli_main = importlib.import_module("hybrid.cli.main")
    reported: list[object] = []
    received: list[int] = []
    monkeypatch.setattr(sys, "__unraisablehook__", reported.append)
    monkeypatch.setattr(cli_main, "_STOPPED", [False])
    previous = signal.signal(signal.SIGINT, lambda signum, frame: received.append(signum))
    try:
        dropped = SimpleNamespace(exc_type=KeyboardInterrupt, exc_value=KeyboardInterrupt())
        cli_main._quiet_after_interrupt(dropped)
        time.sleep(0.01)  # the handler runs in this (the main) thread, between lines
        assert received == [signal.SIGINT] and reported == []
        monkeypatch.setattr(cli_main, "_STOPPED", [True])
        cli_main._quiet_after_interrupt(dropped)
        time.sleep(0.01)
        assert received == [signal.SIGINT] and reported == []
    finally:
        signal.signal(signal.SIGINT, previous)


_DROPPED = """
import importlib, signal, sys, time
signal.signal(signal.SIGINT, signal.default_int_handler)  # Python's own, also when started
# by a shell that ignores SIGINT in its background jobs (then inherited ignored)
cli_main = importlib.import_module("hybrid.cli.main")
sys.unraisablehook = cli_main._quiet_after_interrupt  # as the command installs it


class Dropper:
    def __del__(self):
        raise KeyboardInterrupt  # a Ctrl-C landing in a finalizer: Python drops it


Dropper()
try:
    time.sleep(5)
except KeyboardInterrupt:
    print("arrived")
"""


def test_a_ctrl_c_dropped_under_the_default_handler_reaches_the_commands_code() -> None:
    """Under Python's default handler (``hybrid validate``, ``check``) a dropped Ctrl-C
    raised again inside the hook would be reported as "Exception ignored in
    sys.unraisablehook" with a traceback (CI saw it in ``validate``): it arrives as a
    ``KeyboardInterrupt`` in the code that runs after the hook, and nothing is printed."""
    result = subprocess.run([sys.executable, "-c", _DROPPED], capture_output=True, text=True,
                            cwd=REPO, timeout=60)  # fmt: skip
    assert (result.stdout, result.stderr) == ("arrived\n", "")
