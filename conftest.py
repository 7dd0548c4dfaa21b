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


def pytest_configure(config: pytest.Config) -> None:
    """Bytecode for ``hybrid`` and ``uvms_model``, written once before any test runs.

    Many tests run ``python -m hybrid`` in a fresh process, as a user types it. A
    process that finds no ``.pyc`` compiles every module it imports from source (0.1
    to 0.3 s of a command here), and where ``PYTHONDONTWRITEBYTECODE`` is set, as
    those processes set it, it writes none for the next. pip compiles an installed
    copy; an editable checkout gets its bytecode here. Only the controller writes
    it (pytest-xdist's workers start after this).
    """
    if hasattr(config, "workerinput"):
        return
    import compileall

    for package in ("hybrid", "uvms_model"):
        compileall.compile_dir(REPO / package, quiet=2)


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
