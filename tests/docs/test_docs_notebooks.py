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
    )
    client.execute()
    return notebook


def _texts(notebook: Any) -> list[list[str]]:
    """Per code cell, its text outputs (streams and text/plain), figures left out."""
    found = []
    for cell in notebook.cells:
        if cell.cell_type != "code":
            continue
        texts = []
        for output in cell.get("outputs", []):
            if output.output_type == "stream":
                texts.append(output.text)
            elif "text/plain" in output.get("data", {}) and "image/png" not in output["data"]:
                texts.append(output["data"]["text/plain"])
        found.append(texts)
    return found


def test_there_are_notebooks() -> None:
    assert {p.name for p in PAGES} >= {"first-model.ipynb", "campaign.ipynb"}


@pytest.mark.parametrize("path", PAGES, ids=[p.name for p in PAGES])
def test_a_notebook_runs_and_shows_what_it_prints(path: Path) -> None:
    pytest.importorskip("nbclient", reason="the notebooks need nbclient (the test extra)")
    pytest.importorskip("ipykernel", reason="the notebooks need ipykernel (the test extra)")
    import nbformat

    stored = nbformat.read(path, as_version=4)
    ran = execute(path)  # raises CellExecutionError, with the cell, if a cell fails
    assert _texts(ran) == _texts(stored), f"{path.name}: stored outputs are stale; rerun it"
    for cell in stored.cells:
        if cell.cell_type == "code":
            assert cell.get("outputs"), f"{path.name}: a cell without stored output"


if __name__ == "__main__":
    import nbformat

    for page in PAGES if len(sys.argv) < 2 else [Path(a) for a in sys.argv[1:]]:
        nbformat.write(execute(page), page)
        print(f"executed {page}")
