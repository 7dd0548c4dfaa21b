"""The SpaceEx models from the field (tests/data/spaceex), imported as a user would: the
compiled backend runs each as the scipy backend does.

These are models nobody here wrote: the ball template dropped from rest on its
floor (boundaries at the start), nondeterministic inputs held at their nominal
values, equality guards (the circle), product systems (the filtered
oscillator). Each is imported with its configuration and run on both backends
with the same settings: the same edges and locations, jump times within 1e-9,
the same termination. The 16th- and 32nd-order oscillators are left to
``make fuzz`` (their compiles take seconds each).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from support import REPO, assert_backends_agree

import hybrid
from hybrid.errors import SpecError
from hybrid.interchange import import_spaceex

pytest.importorskip("numba")

DATA = REPO / "tests" / "data" / "spaceex"
LARGE = ("filtered_oscillator_16", "filtered_oscillator_32")


def _models() -> list[tuple[Path, Path | None]]:
    found: list[tuple[Path, Path | None]] = []
    for xml in sorted(DATA.glob("*/*.xml")):
        if xml.parent.name in LARGE and not os.environ.get("HYBRID_FUZZ"):
            continue
        cfg = xml.with_suffix(".cfg")
        found.append((xml, cfg if cfg.exists() else None))
    return found


MODELS = _models()


@pytest.mark.parametrize(("xml", "cfg"), MODELS, ids=[x.stem for x, _ in MODELS])
def test_a_field_model_runs_compiled_as_it_runs_on_scipy(
    tmp_path: Path, xml: Path, cfg: Path | None
) -> None:
    try:
        result = import_spaceex(xml, cfg)
    except SpecError:  # refused by the importer (tests/interchange): nothing to run
        pytest.skip("refused by the importer")
    for name, text in result.files.items():
        (tmp_path / name).write_text(text)
    model = hybrid.load(tmp_path / result.top)
    assert_backends_agree(model, t_end=10.0, max_jumps=200)
