"""``hybrid graph --format svg|png``: pictures of the automaton drawn by Graphviz.

The SVG of the UVMS automaton is checked against the spec file itself: one node
per location, one edge per edge, each labelled with its name. Where Graphviz's
``dot`` program is not installed the drawing tests are skipped, saying so; the
message a user gets without it is tested everywhere.
"""

from __future__ import annotations

import builtins
import shutil
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Any

import pytest
import yaml
from support import REPO, assert_no_traceback, main_in_process, run_cli

import hybrid
from hybrid.analysis import location_graph
from hybrid.export import render

DOT = shutil.which("dot")
needs_dot = pytest.mark.skipif(
    DOT is None, reason="Graphviz's dot program is not installed (Debian: apt-get install graphviz)"
)
SVG = "{http://www.w3.org/2000/svg}"


@needs_dot
def test_svg_of_the_uvms_automaton(tmp_path: Path) -> None:
    spec = yaml.safe_load((REPO / "specs/uvms_singularity.yaml").read_text(encoding="utf-8"))
    out = tmp_path / "uvms.svg"
    result = run_cli("graph", REPO / "specs/uvms_singularity.yaml", "--format", "svg", "--out", out)
    assert result.returncode == 0, result.stderr
    assert result.stdout == ""
    root = ET.parse(out).getroot()
    assert root.tag == f"{SVG}svg"
    groups = {g.get("class"): [] for g in root.iter(f"{SVG}g")}
    for g in root.iter(f"{SVG}g"):
        title = g.find(f"{SVG}title")
        text = " ".join(t.text or "" for t in g.iter(f"{SVG}text"))
        groups.setdefault(g.get("class"), []).append(
            (title.text if title is not None else "", text)
        )
    nodes = {title for title, _ in groups["node"] if title != "__start__"}
    assert nodes == set(spec["locations"])
    edges = [text for title, text in groups["edge"] if not title.startswith("__start__")]
    assert len(edges) == len(spec["edges"])
    for edge in spec["edges"]:
        assert any(text.startswith(edge["name"]) for text in edges), edge["name"]


@needs_dot
def test_png_of_a_system_product(tmp_path: Path) -> None:
    out = tmp_path / "mission.png"
    assert (
        main_in_process(
            "graph", REPO / "specs/uvms_mission_1.yaml", "--format", "png", "--out", out
        )
        == 0
    )
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    svg = render(location_graph(hybrid.load(REPO / "specs/thermostat.yaml")), "svg")
    assert b"turn_on" in svg and b"turn_off" in svg


def test_without_dot_the_message_says_how_to_install_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))  # no dot here
    assert main_in_process("graph", REPO / "specs/thermostat.yaml", "--format", "svg") == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert_no_traceback(err)
    assert "dot program is not on PATH" in err
    assert "apt-get install graphviz" in err
    assert "--format dot" in err  # what works without it


def test_without_the_graphviz_package_the_message_names_the_extra(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    real_import = builtins.__import__

    def no_graphviz(name: str, *args: Any, **kwargs: Any) -> Any:
        if name == "graphviz":
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    graph = location_graph(hybrid.load(REPO / "specs/thermostat.yaml"))
    monkeypatch.setattr(builtins, "__import__", no_graphviz)
    with pytest.raises(
        hybrid.UsageError, match=r"pip install 'graphviz>=0.20' \(the 'graph' extra\)"
    ):
        render(graph, "png")


def test_text_formats_need_nothing_and_unknown_formats_are_refused(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main_in_process("graph", REPO / "specs/thermostat.yaml", "--format", "mermaid") == 0
    assert capsys.readouterr().out.startswith("stateDiagram-v2")
    assert main_in_process("graph", REPO / "specs/thermostat.yaml", "--format", "gif") == 2
    assert "invalid choice: 'gif'" in capsys.readouterr().err
