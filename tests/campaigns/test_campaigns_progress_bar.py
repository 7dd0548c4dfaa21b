"""Sweeps and falsification draw a progress bar (tqdm) in a notebook, and need no tqdm.

A fake bar class stands in for tqdm's (``hybrid.progress._tqdm`` is where the
campaigns find it), so what the bar was told is known exactly: its total and its
final count must be the number of runs the campaign made (counted independently,
from the table's rows and the falsification's evaluations). With tqdm itself the
text bar ends at ``N/N``. Without tqdm nothing breaks, and ``import hybrid`` never
imports it.
"""

from __future__ import annotations

import io
import subprocess
import sys
from typing import Any, ClassVar

import pytest
from support import REPO

import hybrid
from hybrid import progress as progress_module
from hybrid.progress import Bar, TerminalLine

HEATER = """\
automaton: heater
parameters: {k: 0.1}
state: {x: {initial: 20.0}}
locations: {cooling: {flow: {x: -k*x}}}
requirements: [{name: warm, always: "x >= 15"}]
"""


class FakeBar:
    """Records what a tqdm bar is told (the calls the campaigns make of it)."""

    made: ClassVar[list[FakeBar]] = []

    def __init__(self, total: float | None = None, desc: str = "", unit: str = "") -> None:
        self.total, self.desc, self.unit = total, desc, unit
        self.n: float = 0
        self.postfix: dict[str, Any] = {}
        self.closed = False
        FakeBar.made.append(self)

    def update(self, k: float) -> None:
        assert not self.closed
        self.n += k

    def set_postfix(self, values: dict[str, Any], refresh: bool = True) -> None:
        self.postfix = dict(values)

    def close(self) -> None:
        self.closed = True


@pytest.fixture
def fake_tqdm(monkeypatch: pytest.MonkeyPatch) -> list[FakeBar]:
    FakeBar.made = []
    monkeypatch.setattr(progress_module, "_tqdm", lambda: FakeBar)
    return FakeBar.made


def _sweep(progress: Any) -> hybrid.SweepTable:
    ball = hybrid.load(REPO / "specs" / "bouncing_ball.yaml")
    return hybrid.sweep(
        ball, t_end=2.0, grid={"e": [0.5, 0.7, 0.9]}, workers=0, progress=progress
    )


def test_a_sweeps_bar_counts_its_runs(fake_tqdm: list[FakeBar]) -> None:
    table = _sweep(True)
    (bar,) = fake_tqdm
    assert (bar.desc, bar.unit, bar.closed) == ("sweep", "runs", True)
    assert bar.total == bar.n == len(table.rows) == 3
    assert bar.postfix == {"violations": 0, "failed": 0}


def test_a_falsifications_bar_counts_its_runs(fake_tqdm: list[FakeBar]) -> None:
    heater = hybrid.load_text(HEATER)
    # k <= 0.05 keeps x = 20 exp(-k t) above 15 until t = 5: the whole budget is spent
    held = hybrid.falsify(heater, "warm", {"k": (0.0, 0.05)}, t_end=5.0, budget=8, seed=1,
                          workers=0, progress=True)  # fmt: skip
    # k up to 0.1 violates (k > 0.0575): found early, the bar ends full at the runs made
    found = hybrid.falsify(heater, "warm", {"k": (0.0, 0.1)}, t_end=5.0, budget=8, seed=1,
                           workers=0, progress=True)  # fmt: skip
    assert not held.found and found.found and found.evaluations < 8
    first, second = fake_tqdm
    assert first.total == first.n == held.evaluations == 8 and first.closed
    assert second.total == second.n == found.evaluations and second.closed
    assert first.postfix == {"violations": 0} and second.postfix["violations"] >= 1


def test_the_bar_is_on_in_a_notebook_and_off_elsewhere_by_default(
    fake_tqdm: list[FakeBar], monkeypatch: pytest.MonkeyPatch
) -> None:
    _sweep(None)
    assert fake_tqdm == []  # not a Jupyter kernel
    monkeypatch.setattr(progress_module, "in_notebook", lambda: True)
    _sweep(None)
    assert len(fake_tqdm) == 1 and fake_tqdm[0].n == 3
    _sweep(False)  # asked for none
    assert len(fake_tqdm) == 1


def test_tqdms_text_bar_ends_at_the_number_of_runs() -> None:
    tqdm = pytest.importorskip("tqdm").tqdm
    out = io.StringIO()
    _sweep(Bar(tqdm, file=out, ascii=True))
    final = out.getvalue().rsplit("\r", 1)[-1]
    assert final.startswith("sweep: 100%|##########| 3/3 [") and final.endswith("\n")


def test_without_tqdm_nothing_breaks(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "tqdm", None)  # `import tqdm` raises ImportError
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)
    monkeypatch.setattr(progress_module, "in_notebook", lambda: True)
    assert progress_module._tqdm() is None
    assert [row["jumps"] for row in _sweep(None).rows] == [1, 1, 1]
    stream = io.StringIO()
    monkeypatch.setattr(sys, "stderr", stream)
    assert progress_module.reporter(True) is None  # stderr is no terminal: no line either
    assert [row["jumps"] for row in _sweep(True).rows] == [1, 1, 1]
    assert stream.getvalue() == ""
    assert isinstance(progress_module.reporter(TerminalLine(stream)), TerminalLine)


def test_import_hybrid_does_not_import_tqdm() -> None:
    code = "import sys, hybrid, hybrid.progress; print('tqdm' in sys.modules)"
    result = subprocess.run([sys.executable, "-c", code], cwd=REPO, capture_output=True,
                            text=True, timeout=60, check=True)  # fmt: skip
    assert result.stdout.strip() == "False"
