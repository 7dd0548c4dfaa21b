"""docs/simulation-api.md: every ```python block runs as it is, from the repository root."""

from __future__ import annotations

import contextlib
import io
import re

import pytest
from support import DOCS

PAGE = (DOCS / "simulation-api.md").read_text(encoding="utf-8")
BLOCKS = re.findall(r"```python\n(.*?)```", PAGE, flags=re.DOTALL)


def test_the_page_has_examples() -> None:
    assert len(BLOCKS) >= 6


@pytest.mark.parametrize("block", BLOCKS, ids=[f"block{k}" for k in range(len(BLOCKS))])
def test_each_block_runs_as_it_is(block: str) -> None:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(block, "docs/simulation-api.md", "exec"), {"__name__": "__doc__"})


def test_the_printed_errors_are_the_ones_the_page_shows() -> None:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(BLOCKS[-1], "docs/simulation-api.md", "exec"), {})
    printed = out.getvalue().splitlines()
    assert printed == [
        "rtol must be a finite number, got inf",
        "max_step=1e-300 is below the resolution of time near t_end=10 (8.88e-15): a step "
        "that short cannot advance t",
        "parameter 'g' must be a finite number, got nan",
    ]
    flowing = " ".join(PAGE.split())
    for line in printed:
        assert f"`{line}`" in flowing
