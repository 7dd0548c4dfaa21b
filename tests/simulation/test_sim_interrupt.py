"""Ctrl-C during ``hybrid simulate``: a clean end, cause ``interrupted``, output kept."""

from __future__ import annotations

import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from support import REPO, assert_no_traceback, read_csv, read_json

# A fast oscillator, x = cos(10 t); with a tiny max step it would run for hours.
OSCILLATOR = """
automaton: oscillator
state: {x: {initial: 1.0}, v: {initial: 0.0}}
locations:
  spin: {flow: {x: v, v: -100*x}}
"""

# Imports first, then "ready", then the command line exactly as the console script runs it.
LAUNCHER = """
import sys
import hybrid.cli.main, hybrid.cli.simulate, hybrid.simulation.engine, hybrid.export.trajectory, hybrid.reader.loader
import hybrid.simulation.reference  # the scipy engine, which simulate imports on its first run
print("ready", flush=True)
sys.exit(hybrid.cli.main(sys.argv[1:]))
"""


@pytest.mark.skipif(sys.platform == "win32", reason="SIGINT to a child process is POSIX")
def test_ctrl_c_ends_the_run_and_keeps_the_output(tmp_path: Path) -> None:
    spec = tmp_path / "oscillator.yaml"
    spec.write_text(OSCILLATOR)
    out, events = tmp_path / "osc.csv", tmp_path / "osc.json"
    args = ["simulate", str(spec), "--t-end", "1e6", "--max-step", "1e-4"]
    args += ["--out", str(out), "--events", str(events)]
    proc = subprocess.Popen(
        [sys.executable, "-c", LAUNCHER, *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=REPO,
    )
    try:
        assert proc.stdout is not None
        assert proc.stdout.readline().strip() == "ready"
        time.sleep(1.0)
        assert proc.poll() is None, "the simulation should still be running"
        proc.send_signal(signal.SIGINT)
        _, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 1, stderr
    assert_no_traceback(stderr)
    assert "KeyboardInterrupt" not in stderr
    assert ": interrupted: interrupted by the user" in stderr
    term = read_json(events)["termination"]
    assert term["cause"] == "interrupted"
    header, rows = read_csv(out)
    assert header == ["t", "j", "location", "x", "v"]
    t = np.array([float(r["t"]) for r in rows])
    x = np.array([float(r["x"]) for r in rows])
    assert len(rows) > 10 and t[0] == 0.0 and np.all(np.diff(t) > 0)
    assert 0.0 < t[-1] == term["t"] < 1e6
    np.testing.assert_allclose(x, np.cos(10 * t), atol=1e-4)


@pytest.mark.skipif(sys.platform == "win32", reason="raise_signal(SIGINT) is POSIX here")
def test_sigint_in_process_ends_at_the_step_in_progress() -> None:
    import hybrid

    model = hybrid.load_text(
        """
automaton: driven
inputs: [u]
state: {x: {initial: 0.0}}
locations:
  A: {flow: {x: u}}
"""
    )
    sent: list[float] = []

    def u(t: float) -> float:
        if t >= 1.0 and not sent:
            sent.append(t)
            signal.raise_signal(signal.SIGINT)  # the first Ctrl-C: only a flag
        return 1.0

    previous = signal.getsignal(signal.SIGINT)
    run = hybrid.simulate(model, t_end=100.0, max_step=0.01, inputs={"u": u})
    assert signal.getsignal(signal.SIGINT) is previous, "the handler is restored"
    term = run.termination
    assert term.cause == "interrupted" and term.message == "interrupted by the user"
    # stopped at the end of the step during which the signal came (steps <= 0.01)
    assert sent and abs(term.t - sent[0]) <= 0.01
    assert run.t[-1] == term.t and run["x"][-1] == pytest.approx(term.t, abs=1e-9)


def test_a_ctrl_c_before_a_compile_stops_the_command_before_it_compiles() -> None:
    """A Ctrl-C requested just before the compile starts (numba's import takes a second) was
    seen only by the run's loop, after the compile: a cold compile of the kernel held the
    user for 31 s, then wrote a run of one point. Now the compile does not start."""
    import uuid

    import hybrid
    from hybrid.simulation.interrupts import Interrupts

    pytest.importorskip("numba")
    from hybrid.simulation.native.choice import cached

    rate = 1.0 + uuid.uuid4().int % 10**9 / 1e12  # a structure of its own: in no cache
    model = hybrid.load_text(
        f"automaton: drift\nstate: {{x: {{initial: 0}}}}\nlocations: {{go: {{flow: {{x: {rate!r}}}}}}}\n"
    )
    stop = Interrupts()
    with stop.installed():
        stop.press()  # the command's handler, as a Ctrl-C runs it
        with pytest.raises(KeyboardInterrupt, match="interrupted while compiling the model"):
            hybrid.simulate(model, t_end=1.0, backend="compiled")
    assert cached(model)[0] == "missing"  # nothing was compiled
    run = hybrid.simulate(model, t_end=1.0, backend="compiled", handle_sigint=False)
    assert run.states[-1, 0] == pytest.approx(rate, rel=1e-12)  # and the next command compiles
