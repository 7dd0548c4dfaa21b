"""A run and a check report in a notebook: ``run.to_pandas()``, readable reprs, HTML views.

The DataFrame is checked against the CSV writer's file read back (the contract's
columns); the HTML against an HTML parser (well formed, user text escaped).
"""

from __future__ import annotations

import builtins
from html.parser import HTMLParser
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import pytest
from support import REPO

import hybrid
from hybrid.export import write_csv


class _Html(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.open: list[str] = []
        self.rows = 0
        self.text: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        self.open.append(tag)
        self.rows += tag == "tr"

    def handle_endtag(self, tag: str) -> None:
        assert self.open and self.open.pop() == tag, f"</{tag}> closes nothing"

    def handle_data(self, data: str) -> None:
        self.text.append(data)


def _parse(html: str) -> _Html:
    parser = _Html()
    parser.feed(html)
    parser.close()
    assert parser.open == [], f"unclosed: {parser.open}"
    return parser


@pytest.mark.parametrize("spec", ["specs/bouncing_ball.yaml", "specs/uvms_mission_1.yaml"])
def test_to_pandas_is_the_csv_file(spec: str, tmp_path: Path) -> None:
    run = hybrid.simulate(hybrid.load(REPO / spec), t_end=3.0)
    frame = run.to_pandas()
    write_csv(run, tmp_path / "run.csv")
    csv = pd.read_csv(tmp_path / "run.csv")
    assert list(frame.columns) == list(csv.columns)
    assert list(frame.columns[:3]) == ["t", "j", "location"]
    assert list(frame["location"]) == list(csv["location"])
    assert np.array_equal(frame["j"].to_numpy(), csv["j"].to_numpy())
    numbers = [c for c in frame.columns if c not in ("location",)]
    assert np.array_equal(frame[numbers].to_numpy(dtype=float), csv[numbers].to_numpy(dtype=float))


def test_to_pandas_keeps_both_rows_of_a_jump(ball: hybrid.Automaton) -> None:
    run = hybrid.simulate(ball, t_end=2.0)
    frame = run.to_pandas()
    at_jump = frame[frame["t"] == run.jumps[0].t]
    assert list(at_jump["j"]) == [0, 1]
    assert list(at_jump["v"]) == [run.jumps[0].before["v"], run.jumps[0].after["v"]]


def test_without_pandas_the_error_says_what_to_install(
    ball: hybrid.Automaton, monkeypatch: pytest.MonkeyPatch
) -> None:
    run = hybrid.simulate(ball, t_end=1.0)
    real_import = builtins.__import__

    def no_pandas(name: str, *args: Any, **kwargs: Any) -> Any:
        if name == "pandas":
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_pandas)
    with pytest.raises(
        hybrid.UsageError, match=r"pip install 'pandas>=2.0' \(the 'pandas' extra\)"
    ):
        run.to_pandas()


def test_a_run_prints_in_a_few_lines_whatever_its_size(ball: hybrid.Automaton) -> None:
    run = hybrid.simulate(ball, t_end=20.0)  # ends zeno, 33 jumps
    text = repr(run)
    assert text.startswith("<Run bouncing_ball: zeno at t=12.8415 j=33 (33 jumps, ")
    assert "states: h [m], v [m/s]; signals: energy; locations: falling" in text
    assert run.termination.message in text
    assert len(text.splitlines()) == 3 and "array(" not in text
    model = hybrid.load(REPO / "specs/uvms_mission_1.yaml")
    mission = hybrid.simulate(model, t_end=2.0)
    text = repr(mission)
    assert len(text.splitlines()) == 2 and len(text) < 600  # many states and columns, cut
    n_states, n_columns = len(mission.state_names), len(mission.signal_names)
    assert n_states > 10 and n_columns > 40
    assert f"({n_columns} in all)" in text and f"({n_states} in all)" in text


def test_a_run_displays_as_html(ball: hybrid.Automaton) -> None:
    run = hybrid.simulate(ball, t_end=20.0)
    page = _parse(run._repr_html_())
    text = " ".join(page.text)
    assert "zeno" in text and "12.8505881" in text  # the cause and the Zeno time
    assert page.rows == 8 + 1 + 10  # the summary, the jump table's header, its first 10 jumps
    assert "23 more jumps" in text


def test_a_report_prints_its_findings_and_escapes_them_in_html() -> None:
    tank = hybrid.load("docs/examples/tank.yaml").with_parameters({"high": 4.0})
    report = hybrid.check(tank)
    text = repr(report)
    assert text.startswith(
        "<Report tank (docs/examples/tank.yaml): failed, 1 error, 1 warning, 0 notes"
    )
    for finding in report.findings:
        assert finding.text() in text
    html = report._repr_html_()
    page = _parse(html)
    assert page.rows == 1 + len(report.findings)
    assert "h &gt;= high" in html and "h >= high" not in html  # user text is escaped
    ok = hybrid.check(hybrid.load("docs/examples/tank.yaml"))
    assert repr(ok) == "<Report tank (docs/examples/tank.yaml): ok, 0 errors, 0 warnings, 0 notes>"
