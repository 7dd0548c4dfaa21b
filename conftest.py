"""Shared fixtures of the whole suite (tests/ and the docstring examples in hybrid/ and uvms_model/).

Every test and docstring example runs from the repository root, so examples
may name ``specs/...`` as a user in a checkout would. Helper functions that
tests import live in ``tests/support.py``.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

import hybrid

REPO = Path(__file__).resolve().parent


@pytest.fixture(autouse=True)
def _run_from_repository_root(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    monkeypatch.chdir(REPO)
    yield


def _automaton(name: str) -> hybrid.Automaton:
    model = hybrid.load(REPO / "specs" / f"{name}.yaml")
    assert isinstance(model, hybrid.Automaton)
    return model


@pytest.fixture(scope="session")
def ball() -> hybrid.Automaton:
    """specs/bouncing_ball.yaml: g = 9.81, e = 0.8, dropped from h = 10 at rest."""
    return _automaton("bouncing_ball")


@pytest.fixture(scope="session")
def thermostat() -> hybrid.Automaton:
    """specs/thermostat.yaml: starts at 20 degC in `off`."""
    return _automaton("thermostat")
