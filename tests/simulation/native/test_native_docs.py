"""docs/backends.md: every Python example runs as written, from the repository root."""

from __future__ import annotations

import re

import pytest
from support import DOCS

pytest.importorskip("numba")

PAGE = (DOCS / "backends.md").read_text(encoding="utf-8")
BLOCKS = re.findall(r"```python\n(.*?)```", PAGE, flags=re.S)


@pytest.mark.parametrize("source", BLOCKS, ids=[f"block{i}" for i in range(len(BLOCKS))])
def test_python_examples_run(source: str) -> None:
    exec(compile(source, "docs/backends.md", "exec"), {})  # our own documentation, not user text


def test_the_page_names_the_install_command_of_the_fast_extra() -> None:
    from hybrid.version import install_hint

    assert install_hint("fast") in PAGE
