"""Helpers the tests import: paths, running the CLI (in a process or in-process), reading its files."""

from __future__ import annotations

import csv
import importlib.util
import io
import json
import math
import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

REPO = Path(__file__).resolve().parents[1]
SPECS = REPO / "specs"
DOCS = REPO / "docs"
LEAKY_SPEC = """\
automaton: leaky
state:
  h: {initial: 1.5, bounds: [0, 3], unit: m}
  v: {initial: 0.0, bounds: [-1, 1]}
  c: {initial: 0.0}
locations:
  a:
    flow: {h: 0.5, v: -0.25, c: 1}
  b:
    flow: {h: 0.5, v: -0.25, c: 1}
edges:
  - {from: a, to: b, guard: c >= 2}
"""
"""Climbs at known rates with declared bounds (the bounds tests of simulate and simulate_many)."""

RELAY = """
automaton: relay
inputs: [u]
state: {x: {initial: 0.0}}
locations:
  low: {flow: {x: 0}}
  high: {flow: {x: 0}}
edges:
  - {name: up, from: low, to: high, guard: u >= 0.5}
  - {name: down, from: high, to: low, guard: u <= -0.5}
"""
"""A relay with hysteresis driven by its input ``u``: up when u reaches 1/2, down at -1/2."""

Simulate = Callable[..., Any]
"""The ``simulate`` fixture of tests/simulation: ``hybrid.simulate`` on the test's backend."""

def import_source(path: Path, text: str) -> ModuleType:
    """``text`` written to ``path`` and imported as a module (a generated module's plain
    Python: importing it runs no ``build()``), kept out of ``sys.modules``."""
    path.write_text(text, encoding="utf-8")
    spec = importlib.util.spec_from_file_location(path.stem, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[path.stem] = module
    try:
        spec.loader.exec_module(module)
    finally:
        del sys.modules[path.stem]
    return module


def run_cli(
    *args: str | Path, cwd: Path | None = None, timeout: float = 60.0
) -> subprocess.CompletedProcess[str]:
    """``python -m hybrid ARGS`` in a fresh process (as a user types it)."""
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    return subprocess.run(
        [sys.executable, "-m", "hybrid", *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd or REPO,
        env=env,
        timeout=timeout,
        check=False,
    )


class FakeTerminal(io.StringIO):
    """A stream that says it is a terminal (progress lines are drawn on it)."""

    def isatty(self) -> bool:
        return True


def run_on_a_terminal(*args: str | Path, cwd: Path | None = None) -> tuple[int, str, str]:
    """``python -m hybrid ARGS`` with stderr on a pseudo-terminal: exit code, stdout, what it showed."""
    import pty

    master, slave = pty.openpty()
    proc = subprocess.Popen(
        [sys.executable, "-m", "hybrid", *map(str, args)],
        stdout=subprocess.PIPE,
        stderr=slave,
        cwd=cwd or REPO,
        env={**os.environ, "PYTHONPATH": str(REPO)},
        text=True,
    )
    os.close(slave)
    shown = b""
    while True:
        try:
            chunk = os.read(master, 4096)
        except OSError:  # the child closed the terminal
            break
        if not chunk:
            break
        shown += chunk
    os.close(master)
    stdout = proc.stdout.read() if proc.stdout else ""
    proc.wait(timeout=120)
    return proc.returncode, stdout, shown.decode("utf-8", "replace")


def spaceex_pairs(folder: Path) -> list[tuple[Path, Path | None]]:
    """Each ``folder/*/*.xml`` with each ``.cfg`` beside it named after it (``None`` without one)."""
    found: list[tuple[Path, Path | None]] = []
    for xml in sorted(folder.glob("*/*.xml")):
        cfgs = [
            c
            for c in sorted(xml.parent.glob("*.cfg"))
            if c.stem == xml.stem or c.stem.startswith(xml.stem + ".")
        ]
        found.extend((xml, c) for c in cfgs) if cfgs else found.append((xml, None))
    return found


def mutate(draw: Any, text: str, alphabet: Any, edits: Any) -> str:
    """``text`` with ``edits`` (a strategy of counts) random inserts, deletions or replacements."""
    from hypothesis import strategies as st

    for _ in range(draw(edits)):
        at = draw(st.integers(0, len(text)))
        piece = draw(st.text(alphabet, min_size=1, max_size=4))
        kind = draw(st.sampled_from(["insert", "delete", "replace"]))
        if kind == "insert":
            text = text[:at] + piece + text[at:]
        elif kind == "delete":
            text = text[:at] + text[at + len(piece) :]
        else:
            text = text[:at] + piece + text[at + len(piece) :]
    return text


def read_csv(path: Path) -> tuple[list[str], list[dict[str, str]]]:
    """Header and rows of a trajectory CSV."""
    with path.open(newline="") as handle:
        reader = csv.reader(handle)
        header = next(reader)
        rows = [dict(zip(header, row, strict=True)) for row in reader]
    return header, rows


def read_json(path: Path) -> Any:
    return json.loads(path.read_text())


def assert_no_traceback(stderr: str) -> None:
    assert "Traceback" not in stderr, stderr
    assert 'File "' not in stderr, stderr


def in_the_frame_room() -> bool:
    """Whether the caller runs under :mod:`hybrid.frames`' room (its frame is on the stack)."""
    from hybrid import frames

    frame: Any = sys._getframe()
    while frame is not None and frame.f_code is not frames._call.__code__:
        frame = frame.f_back
    return frame is not None


def main_in_process(*args: str | Path) -> int:
    """``hybrid ARGS`` in this process (same code path as the console script); the exit code."""
    from hybrid.cli import main

    try:
        return main([str(a) for a in args])
    except SystemExit as exc:  # argparse usage errors
        return int(exc.code) if isinstance(exc.code, int) else 2


# --- a function library with compiled forms (tests/simulation/native) -----------------


def polar(x: float, y: float) -> tuple[float, float]:
    """Radius and angle of (x, y): the Python form of a two-output library function."""
    return math.hypot(x, y), math.atan2(y, x)


def polar_compiled(x: float, y: float) -> tuple[float, float]:
    """The same, written for numba's nopython mode."""
    return math.sqrt(x * x + y * y), math.atan2(y, x)


def spin(r: float) -> float:
    """A one-output function: the angular speed wanted at radius r."""
    return 1.0 / (1.0 + r * r)


def spin_compiled(r: float) -> float:
    return 1.0 / (1.0 + r * r)


polar.hybrid_outputs = 2  # type: ignore[attr-defined]
polar.hybrid_arity = (2, 2)  # type: ignore[attr-defined]
polar.hybrid_compiled = polar_compiled  # type: ignore[attr-defined]
spin.hybrid_arity = (1, 1)  # type: ignore[attr-defined]
spin.hybrid_compiled = spin_compiled  # type: ignore[attr-defined]


def plain(r: float) -> float:
    """A library function without a compiled form."""
    return 2.0 * r


def limited(r: float) -> float:
    """Defined up to 1.5 only: beyond, its Python form raises, and so does its compiled form."""
    if r > 1.5:
        raise ValueError("defined up to 1.5")
    return 1.0


def limited_compiled(r: float) -> float:
    if r > 1.5:
        raise ValueError("defined up to 1.5")
    return 1.0


limited.hybrid_arity = (1, 1)  # type: ignore[attr-defined]
limited.hybrid_compiled = limited_compiled  # type: ignore[attr-defined]


def native_library() -> dict[str, object]:
    """The function table a package would register under ``hybrid.functions``."""
    return {"polar": polar, "spin": spin, "plain": plain, "limited": limited}


# --- the same run on both backends (tests/simulation/native, tests/interchange) ------------

BACKEND_TOL = {"rtol": 1e-10, "atol": 1e-12, "handle_sigint": False}
"""Solver tolerances under which the compiled and scipy backends are compared."""


def assert_backends_agree(model: Any, **settings: Any) -> tuple[Any, Any]:
    """Simulate ``model`` on scipy and on the compiled backend; assert the same run.

    The same edges and targets in the same order, jump times within 1e-9, the
    same termination (cause and location) and start. Returns both runs
    (scipy's first). ``settings`` go to both (``t_end``, ``max_jumps``...), over
    :data:`BACKEND_TOL`.
    """
    import numpy as np

    import hybrid

    common = {**BACKEND_TOL, **settings}
    reference = hybrid.simulate(model, **common)
    compiled = hybrid.simulate(model, backend="compiled", **common)
    assert [(j.edge, j.target) for j in compiled.jumps] == [
        (j.edge, j.target) for j in reference.jumps
    ]
    np.testing.assert_allclose(compiled.jump_times, reference.jump_times, rtol=1e-10, atol=1e-9)
    assert compiled.termination.cause == reference.termination.cause
    assert compiled.termination.location == reference.termination.location
    assert compiled.settings["start"] == reference.settings["start"]
    return reference, compiled
