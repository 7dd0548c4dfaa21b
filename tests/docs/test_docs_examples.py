"""Every code example of every page under docs/ runs, as a reader would run it.

The pages are found by a glob (a new page is covered without touching this
file). A page's ``python`` and ``{hybrid-plot}`` blocks run in file order in one
namespace, like the cells of a notebook, from a copy of the repository root (its
top-level entries linked into a temporary folder), so that ``specs/...`` and
``docs/examples/...`` resolve and files the examples write land in the temporary
folder. A block after ``<!-- docs: no-run: REASON -->`` is skipped; the reason is
required. Blocks of other languages (``console``, ``yaml``, ``text``) are not run.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from doc_pages import NO_RUN, RUNNABLE, code_blocks, outside_fences, pages
from support import DOCS, REPO

PAGES = pages()
WITH_EXAMPLES = [p for p in PAGES if any(b.runs for b in code_blocks(p.read_text("utf-8")))]


def _id(path: Path) -> str:
    return str(path.relative_to(DOCS))


def test_the_glob_finds_the_guide_pages() -> None:
    names = {_id(p) for p in PAGES}
    assert {"index.md", "getting-started.md", "composition.md", "export.md", "plots.md"} <= names
    assert not any(name.startswith(("api/", "_build/")) for name in names)


@pytest.fixture
def repository_copy(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    for entry in REPO.iterdir():
        if not entry.name.startswith("."):
            (tmp_path / entry.name).symlink_to(entry)
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize("page", WITH_EXAMPLES, ids=_id)
def test_page_examples_run(page: Path, repository_copy: Path) -> None:
    blocks = [b for b in code_blocks(page.read_text(encoding="utf-8")) if b.runs]
    namespace: dict[str, object] = {"__name__": "__docs__"}
    for block in blocks:
        # Line numbers of the page in tracebacks: pad the code to its first line.
        source = "\n" * (block.line - 1) + block.code
        try:
            exec(compile(source, str(page), "exec"), namespace)  # our own pages
        except Exception as exc:
            raise AssertionError(
                f"{_id(page)}:{block.line}: the example fails: {type(exc).__name__}: {exc}"
            ) from exc
    assert os.getcwd() == str(repository_copy), "an example changed the working directory"


@pytest.mark.parametrize("page", PAGES, ids=_id)
def test_skipped_blocks_say_why(page: Path) -> None:
    text = page.read_text(encoding="utf-8")
    for block in code_blocks(text):
        if block.no_run is not None:
            assert block.no_run, f"{_id(page)}:{block.line}: give a reason after 'docs: no-run:'"
    markers = [line for _, line in outside_fences(text) if NO_RUN.match(line.strip())]
    marked = [b for b in code_blocks(text) if b.no_run is not None]
    assert len(markers) == len(marked), f"{_id(page)}: a no-run marker is not right before a block"


def test_the_parser_sees_what_runs_and_what_does_not() -> None:
    text = (
        "# t\n\n```python\nx = 1\n```\n\n<!-- docs: no-run: needs a cluster -->\n"
        "```python\nconnect()\n```\n\n```console\n$ hybrid\n```\n\n"
        "````md\n```python\nnested = 1\n```\n````\n\n```{hybrid-plot}\n:alt: a\nfig = 2\n```\n"
    )
    blocks = code_blocks(text)
    assert [(b.language, b.runs) for b in blocks] == [
        ("python", True),
        ("python", False),
        ("console", False),
        ("md", False),
        ("{hybrid-plot}", True),
    ]
    assert blocks[1].no_run == "needs a cluster"
    assert blocks[0].code == "x = 1\n" and blocks[4].code == "fig = 2\n"
    assert blocks[0].line == 4
    assert {"python", "{hybrid-plot}"} <= RUNNABLE
