"""The examples in the docstrings of the analysis modules run and give what they show."""

from __future__ import annotations

import doctest
import importlib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
MODULES = [
    "hybrid.expr.interval",
    "hybrid.analysis",
    "hybrid.analysis.checks",
    "hybrid.analysis.command",
    "hybrid.analysis.diagrams",
    "hybrid.analysis.findings",
    "hybrid.analysis.flows",
    "hybrid.analysis.formats",
    "hybrid.analysis.graph",
    "hybrid.analysis.linear",
    "hybrid.analysis.product",
    "hybrid.analysis.solve",
    "hybrid.analysis.static",
]


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name, monkeypatch):
    monkeypatch.chdir(ROOT)  # examples load specs/... relative to the repository
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.failed == 0
    assert result.attempted > 0
