"""A guard true only in a short window: missed by default steps, caught with ``max_step``.

The automaton is the worked example of docs/semantics.md, read from the page
between its markers, so the documentation and the behaviour cannot drift apart.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from support import DOCS, main_in_process, read_json

import hybrid

START = "<!-- semantics-example:narrow-guard:start -->"
END = "<!-- semantics-example:narrow-guard:end -->"


def doc_example() -> str:
    page = (DOCS / "semantics.md").read_text()
    assert page.count(START) == 1 and page.count(END) == 1
    block = page.split(START, 1)[1].split(END, 1)[0]
    match = re.fullmatch(r"\s*```yaml\n(.*?)```\s*", block, flags=re.DOTALL)
    assert match, "the example is one ```yaml block between the markers"
    return match.group(1)


@pytest.fixture(scope="module")
def model() -> hybrid.Automaton:
    automaton = hybrid.load_text(doc_example())
    assert isinstance(automaton, hybrid.Automaton)
    return automaton


def test_default_steps_miss_the_window(model: hybrid.Automaton) -> None:
    run = hybrid.simulate(model, t_end=10.0)
    assert run.termination.cause == "t_end"
    assert run.jumps == [] and set(run.location) == {"moving"}
    # the window lies inside one step: no stored point has the guard true
    assert not any(5.0 <= x <= 5.001 for x in run["x"])


def test_max_step_catches_it_at_the_closed_form_time(model: hybrid.Automaton) -> None:
    run = hybrid.simulate(model, t_end=10.0, max_step=0.0005)
    assert run.termination.cause == "t_end"
    (jump,) = run.jumps
    assert (jump.edge, jump.source, jump.target) == ("window", "moving", "caught")
    assert abs(jump.t - 5.0) < 1e-9, jump.t
    assert jump.before["x"] == pytest.approx(5.0, abs=1e-9)


def test_the_cli_flags_of_the_doc(model: hybrid.Automaton, tmp_path: Path) -> None:
    page = (DOCS / "semantics.md").read_text()
    assert "hybrid simulate narrow.yaml --t-end 10 --events ev.json" in page
    assert "hybrid simulate narrow.yaml --t-end 10 --max-step 0.0005 --events ev.json" in page
    spec = tmp_path / "narrow.yaml"
    spec.write_text(doc_example())
    events = tmp_path / "ev.json"
    assert main_in_process("simulate", spec, "--t-end", "10", "--events", events) == 0
    assert read_json(events)["jumps"] == []
    code = main_in_process(
        "simulate", spec, "--t-end", "10", "--max-step", "0.0005", "--events", events
    )
    assert code == 0
    (jump,) = read_json(events)["jumps"]
    assert jump["edge"] == "window" and abs(jump["t"] - 5.0) < 1e-9
