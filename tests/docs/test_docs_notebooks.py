"""The example notebooks of docs/notebooks/ run, and their stored outputs are what they print.

Each notebook is executed in a fresh Jupyter kernel from its own folder, as a user
opening it would run it; its cells assert their closed forms (the tank's jump times,
a sweep's first jumps against ``0.5 / (inflow - 0.2)``), so an error fails the test.
The outputs stored in the file (which the docs render) must be the text outputs of
this run, so the site never shows what the code no longer gives. Needs ``nbclient``
and ``ipykernel`` (the ``test`` extra); skipped, saying so, without them.

``python tests/docs/test_docs_notebooks.py`` executes the notebooks and writes their
outputs back (after a change to a notebook or to what it shows).
"""

from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path
from typing import Any

import pytest

NOTEBOOKS = Path(__file__).resolve().parents[2] / "docs" / "notebooks"
PAGES = sorted(NOTEBOOKS.glob("*.ipynb"))


def execute(path: Path) -> Any:
    """The notebook at ``path``, executed from its folder (a ``nbformat`` node)."""
    import nbformat
    from nbclient import NotebookClient

    notebook = nbformat.read(path, as_version=4)
    client = NotebookClient(
        notebook,
        timeout=600,
        kernel_name="python3",
        resources={"metadata": {"path": str(path.parent)}},
        coalesce_streams=True,  # one stream per cell, a progress bar's redraws folded
    )
    client.execute()
    return notebook


# a tqdm text bar's closing line, from its count on: the times and the rate differ per run
_BAR_TIMES = re.compile(r"(\|\s*\d+/\d+) \[[^\]\n]*\]")


def bars(notebook: Any) -> list[str]:
    """The progress bars the notebook's cells drew (each a last line of stderr)."""
    return [
        line
        for cell in notebook.cells
        for output in cell.get("outputs", [])
        if output.get("output_type") == "stream" and output.get("name") == "stderr"
        for line in output.text.splitlines()
        if _BAR_TIMES.search(line)
    ]


def _texts(notebook: Any, with_bars: bool = True) -> list[list[str]]:
    """Per code cell, its text outputs (streams and text/plain), figures left out.

    A progress bar is compared up to its count: what comes after (elapsed time,
    rate) is never the same twice. ``with_bars=False`` leaves bars out (where
    tqdm is not installed, the kernel draws none).
    """
    found = []
    for cell in notebook.cells:
        if cell.cell_type != "code":
            continue
        texts = []
        for output in cell.get("outputs", []):
            if output.output_type == "stream":
                lines = output.text.splitlines(keepends=True)
                if not with_bars:
                    lines = [line for line in lines if not _BAR_TIMES.search(line)]
                if lines:
                    texts.append(_BAR_TIMES.sub(r"\1", "".join(lines)))
            elif "text/plain" in output.get("data", {}) and "image/png" not in output["data"]:
                texts.append(output["data"]["text/plain"])
        found.append(texts)
    return found


def test_there_are_notebooks() -> None:
    assert {p.name for p in PAGES} >= {"first-model.ipynb", "campaign.ipynb"}


def test_the_campaign_notebook_shows_its_sweeps_progress_bar() -> None:
    # run by test_a_notebook_runs_and_shows_what_it_prints with tqdm (the test extra),
    # which then compares this stored bar with the one the kernel draws
    import nbformat

    stored = nbformat.read(NOTEBOOKS / "campaign.ipynb", as_version=4)
    (bar,) = bars(stored)
    assert bar.startswith("sweep: 100%|") and "| 9/9 [" in bar and "violations=0" in bar


@pytest.mark.parametrize("path", PAGES, ids=[p.name for p in PAGES])
def test_a_notebook_runs_and_shows_what_it_prints(path: Path) -> None:
    pytest.importorskip("nbclient", reason="the notebooks need nbclient (the test extra)")
    pytest.importorskip("ipykernel", reason="the notebooks need ipykernel (the test extra)")
    import nbformat

    stored = nbformat.read(path, as_version=4)
    ran = execute(path)  # raises CellExecutionError, with the cell, if a cell fails
    with_bars = importlib.util.find_spec("tqdm") is not None
    assert _texts(ran, with_bars) == _texts(stored, with_bars), (
        f"{path.name}: stored outputs are stale; rerun it"
    )
    for cell in stored.cells:
        if cell.cell_type == "code":
            assert cell.get("outputs"), f"{path.name}: a cell without stored output"


if __name__ == "__main__":
    import nbformat

    for page in PAGES if len(sys.argv) < 2 else [Path(a) for a in sys.argv[1:]]:
        nbformat.write(execute(page), page)
        print(f"executed {page}")
