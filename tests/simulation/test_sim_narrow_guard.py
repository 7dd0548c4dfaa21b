"""A guard true only in a short window: missed between default samples, caught with ``max_step``.

The automaton is the worked example of docs/semantics.md, read from the page
between its markers, so the documentation and the behaviour cannot drift apart.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest
from support import DOCS, Simulate, main_in_process, read_json

import hybrid
from hybrid.simulation.crossing import HORIZON_SAMPLES, parts

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


def test_default_steps_miss_the_window(simulate: Simulate, model: hybrid.Automaton) -> None:
    run = simulate(model, t_end=2.0)
    assert run.termination.cause == "t_end"
    assert run.jumps == [] and set(run.location) == {"moving"}
    # the step ends the page lists, and the window lies inside one step
    np.testing.assert_allclose(run.t, [0, 1e-4, 0.0011, 0.0111, 0.1111, 1.1111, 2.0])
    assert not any(1.0 <= x <= 1.0001 for x in run["x"])


def test_the_samples_around_the_window_show_no_dip(model: hybrid.Automaton) -> None:
    # the page's account: 500 samples 2 ms apart in the step [0.1111, 1.1111]; the two
    # around the window are at 0.9991 and 1.0011, where rho is positive
    t0, t1 = 0.1111, 1.1111
    m = parts(t1 - t0, 2.0 / HORIZON_SAMPLES)
    samples = t0 + (t1 - t0) * np.arange(1, m + 1) / m
    assert m == 500
    before = samples[samples < 1.0][-1]
    after = samples[samples > 1.0001][0]
    assert (round(before, 4), round(after, 4)) == (0.9991, 1.0011)
    assert not np.any((samples >= 1.0) & (samples <= 1.0001))


def test_max_step_catches_it_at_the_closed_form_time(simulate: Simulate, model: hybrid.Automaton) -> None:
    run = simulate(model, t_end=2.0, max_step=0.0004)
    assert run.termination.cause == "t_end"
    (jump,) = run.jumps
    assert (jump.edge, jump.source, jump.target) == ("window", "moving", "caught")
    assert abs(jump.t - 1.0) < 1e-9, jump.t
    assert jump.before["x"] == pytest.approx(1.0, abs=1e-9)


def test_the_cli_flags_of_the_doc(model: hybrid.Automaton, tmp_path: Path) -> None:
    page = (DOCS / "semantics.md").read_text()
    assert "hybrid simulate narrow.yaml --t-end 2 --events ev.json" in page
    assert "hybrid simulate narrow.yaml --t-end 2 --max-step 0.0004 --events ev.json" in page
    spec = tmp_path / "narrow.yaml"
    spec.write_text(doc_example())
    events = tmp_path / "ev.json"
    assert main_in_process("simulate", spec, "--t-end", "2", "--events", events) == 0
    assert read_json(events)["jumps"] == []
    code = main_in_process(
        "simulate", spec, "--t-end", "2", "--max-step", "0.0004", "--events", events
    )
    assert code == 0
    (jump,) = read_json(events)["jumps"]
    assert jump["edge"] == "window" and abs(jump["t"] - 1.0) < 1e-9
