"""Progress of ``hybrid check`` on stderr: on a terminal only, for a large product, ``--quiet`` silences it.

The system: thermostats whose ``heat`` edges share a label, so they form one
group of interacting components and the explorer walks their product. The test
that must see progress uses 20 of them, 2**20 = 1,048,576 modes (about 3 s of
exploration on a 2025 laptop core), so the reporter (every 0.2 s) shows it on any
machine that is not more than ten times faster; 16 (65,536 modes, a third of a
second, too close to the interval to count on) serve the tests that must not.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from support import REPO, run_on_a_terminal

COMPONENTS = 16
LARGE = 20


def write_system(folder: Path, components: int = COMPONENTS) -> Path:
    for i in range(components):
        (folder / f"th{i}.yaml").write_text(
            f"""automaton: th{i}
state: {{T{i}: {{initial: 20, bounds: [0, 40]}}}}
labels: [sync]
locations:
  off: {{flow: {{T{i}: -0.1*(T{i} - 10)}}, invariant: T{i} >= 18}}
  on: {{flow: {{T{i}: 0.1*(30 - T{i})}}, invariant: T{i} <= 22}}
edges:
  - {{name: heat, from: off, to: on, guard: T{i} <= 18, label: sync}}
  - {{name: rest, from: on, to: off, guard: T{i} >= 22}}
"""
        )
    spec = folder / "many.yaml"
    components = "".join(f"  - spec: th{i}.yaml\n" for i in range(components))
    spec.write_text(f"system: many\ncomponents:\n{components}")
    return spec


@pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals are POSIX")
def test_progress_of_a_large_product_is_shown_on_a_terminal_and_erased(tmp_path: Path) -> None:
    write_system(tmp_path, LARGE)
    code, stdout, shown = run_on_a_terminal("check", "many.yaml", cwd=tmp_path)
    assert code == 0, shown
    assert "check many.yaml: " in shown and " modes" in shown and "frontier" in shown
    assert "modes per second" in shown
    counts = [
        int(part.split(": ")[1].split(" ")[0].replace(",", ""))
        for part in shown.split("\r")
        if part.startswith("check many.yaml: ")
    ]
    assert counts and all(0 < c <= 2**LARGE for c in counts)
    assert counts == sorted(counts)  # modes explored only grow
    assert shown.endswith("\r") and shown.split("\r")[-2].strip() == ""  # the line is erased
    assert stdout == "many.yaml: ok\n"


@pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals are POSIX")
def test_quiet_silences_it(tmp_path: Path) -> None:
    write_system(tmp_path)
    code, stdout, shown = run_on_a_terminal("check", "many.yaml", "--quiet", cwd=tmp_path)
    assert code == 0
    assert shown == "" and stdout == "many.yaml: ok\n"


def test_nothing_is_shown_when_stderr_is_not_a_terminal(tmp_path: Path) -> None:
    write_system(tmp_path)
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    result = subprocess.run(
        [sys.executable, "-m", "hybrid", "check", "many.yaml"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env=env,
        timeout=120,
        check=False,
    )
    assert result.returncode == 0 and result.stderr == ""
    assert result.stdout == "many.yaml: ok\n"


@pytest.mark.skipif(sys.platform == "win32", reason="pseudo-terminals are POSIX")
def test_a_small_product_shows_nothing() -> None:
    # the thermostat spec is checked well within the reporter's interval
    code, stdout, shown = run_on_a_terminal("check", "thermostat.yaml", cwd=REPO / "specs")
    assert code == 0 and stdout == "thermostat.yaml: ok\n"
    assert shown == ""
