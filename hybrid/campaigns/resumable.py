"""Results written as they come, in chunks, so that a campaign stopped anywhere resumes.

A campaign writing ``results.csv`` keeps its finished rows in the folder
``results.csv.parts/``: ``campaign.json`` names the campaign (a fingerprint of
the model, the settings and every point) and each ``chunk-NNNNNN.jsonl`` holds
some finished rows, one JSON object per line (numbers exactly as computed).
Every file there is written whole or not at all (a temporary file, then a
rename), so a campaign killed at any moment (``kill -9`` included) leaves only
complete chunks. Run again with ``resume``, it reads them and runs only the
points that have no row; a folder from another campaign (a different model,
settings or points) is refused, and so is a folder found without ``resume``
(nothing is overwritten by accident). When the campaign is complete, the
results file is written and the folder removed.

A row the executor made for a run it lost (a worker process that died, a Dask
task that failed: :data:`LOST` is set in it) is kept in the chunks, so the
campaign's record is whole, but it is not *done*: a resumed campaign runs that
point again.

Examples
--------
>>> import tempfile, pathlib
>>> out = pathlib.Path(tempfile.mkdtemp()) / "results.csv"
>>> store = ChunkStore(out, "abc", resume=False)
>>> store.add({"run": 0, "x": 0.1})
>>> store.flush()
>>> sorted(ChunkStore(out, "abc", resume=True).done)
[0]
"""

from __future__ import annotations

import json
import shutil
import time
from pathlib import Path
from typing import Any

from hybrid.errors import CannotWrite, UsageError
from hybrid.files import atomic_write

__all__ = ["CHUNK_ROWS", "CHUNK_SECONDS", "LOST", "ChunkStore", "parts_dir", "write_whole"]

LOST = "lost"
"""Key set (to True) in a row the executor made for a run lost to it, not run to an end."""

CHUNK_ROWS = 64
"""A chunk is written when this many rows are waiting..."""
CHUNK_SECONDS = 1.0
"""... or when the oldest waiting row is this old."""


def write_whole(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` whole or not at all (:func:`hybrid.files.atomic_write`)."""
    with atomic_write(path) as handle:
        handle.write(data)


def parts_dir(out: Path) -> Path:
    """The folder of the chunks of a campaign writing ``out``."""
    return out.with_name(out.name + ".parts")


class ChunkStore:
    """The finished rows of one campaign, on disk (see the module docstring)."""

    def __init__(self, out: str | Path, fingerprint: str, *, resume: bool) -> None:
        self.out = Path(out)
        self.folder = parts_dir(self.out)
        self.fingerprint = fingerprint
        self.done: dict[int, dict[str, Any]] = {}
        self.waiting: list[dict[str, Any]] = []
        self.oldest = 0.0
        self.next_chunk = 0
        if self.folder.exists():
            if not resume:
                raise UsageError(
                    f"{self.folder} holds the results of an unfinished campaign: add --resume "
                    "to finish it (only the missing runs are run), or remove the folder"
                )
            self._read()
        else:
            try:
                self.folder.mkdir()
            except OSError as exc:  # a read-only place, /proc
                raise CannotWrite.of(self.folder, exc) from None
            manifest = {"fingerprint": fingerprint, "created": time.time()}
            write_whole(self.folder / "campaign.json", json.dumps(manifest).encode())

    def _read(self) -> None:
        try:
            manifest = json.loads((self.folder / "campaign.json").read_text())
        except (OSError, ValueError) as exc:
            raise UsageError(f"{self.folder}: cannot read campaign.json ({exc})") from None
        if manifest.get("fingerprint") != self.fingerprint:
            raise UsageError(
                f"{self.folder} holds the results of another campaign (a different model, "
                "settings or points): remove it, or write the results elsewhere"
            )
        for chunk in sorted(self.folder.glob("chunk-*.jsonl")):
            try:
                rows = [json.loads(line) for line in chunk.read_text().splitlines()]
            except (OSError, ValueError) as exc:  # written whole, so damaged since
                raise UsageError(
                    f"{chunk}: cannot read it ({exc}): remove it, and --resume runs its runs again"
                ) from None
            for row in rows:
                if row.get(LOST):
                    self.done.pop(int(row["run"]), None)  # run again (a later chunk may hold it)
                else:
                    self.done[int(row["run"])] = row
            self.next_chunk = max(self.next_chunk, int(chunk.stem.split("-")[1]) + 1)

    def add(self, row: dict[str, Any]) -> None:
        """Keep ``row``; write a chunk when enough rows wait, or long enough."""
        if not self.waiting:
            self.oldest = time.monotonic()
        self.waiting.append(row)
        self.done[int(row["run"])] = row
        if len(self.waiting) >= CHUNK_ROWS or time.monotonic() - self.oldest >= CHUNK_SECONDS:
            self.flush()

    def flush(self) -> None:
        """Write the waiting rows as one chunk."""
        if not self.waiting:
            return
        text = "".join(json.dumps(row) + "\n" for row in self.waiting)
        path = self.folder / f"chunk-{self.next_chunk:06d}.jsonl"
        write_whole(path, text.encode())
        self.next_chunk += 1
        self.waiting = []

    def remove(self) -> None:
        """Delete the folder (the results file has been written)."""
        shutil.rmtree(self.folder, ignore_errors=True)
