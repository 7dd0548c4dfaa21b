"""The demo where the specs are not: one message saying where to run it, exit 2, nothing written."""

from __future__ import annotations

from pathlib import Path

import pytest
from support import REPO

from uvms_model import demo, missions


def test_the_specs_are_found_beside_the_package_in_a_checkout() -> None:
    assert missions.specs_dir() == REPO / "specs"


def test_without_the_specs_the_demo_says_where_to_run_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(demo, "specs_dir", lambda: tmp_path)
    out = tmp_path / "out"
    assert demo.main([str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert str(tmp_path) in err and "uvms_mission_1.yaml" in err and "make demo" in err
    assert not out.exists()
