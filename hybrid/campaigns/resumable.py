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

While a campaign writes the folder it holds a lock on its ``lock`` file (an
advisory ``flock``, released by the system when the process ends, ``kill -9``
included), so a second campaign given the same results file is refused instead
of writing over the first one's chunks.

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
>>> ChunkStore(out, "abc", resume=True)  # doctest: +ELLIPSIS
Traceback (most recent call last):
hybrid.errors.UsageError: ...: another campaign is writing these results now (process ...)...
>>> store.close()  # the campaign ends (or its process does)
>>> sorted(ChunkStore(out, "abc", resume=True).done)
[0]
"""

from __future__ import annotations

import json
import os
import shutil
import time
import warnings
from pathlib import Path
from typing import Any, BinaryIO

from hybrid.errors import CannotWrite, Note, UsageError
from hybrid.files import atomic_write

try:
    import fcntl
except ImportError:  # Windows: no advisory locks; campaigns there are not guarded
    fcntl = None  # type: ignore[assignment]

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


_PART_WORDS = {
    "model": "the model",
    "t_end": "t_end",
    "solver": "the solver's settings",
    "inputs": "the inputs",
    "backend": "the backend",
    "timeout": "the run timeout",
    "columns": "the columns (summaries, requirements)",
    "points": "the points",
}
"""How a refused resume names each part of the campaign that differs."""


class ChunkStore:
    """The finished rows of one campaign, on disk (see the module docstring)."""

    def __init__(self, out: str | Path, fingerprint: str, *, resume: bool,
                 parts: dict[str, str] | None = None) -> None:  # fmt: skip
        self.out = Path(out)
        self.folder = parts_dir(self.out)
        self.fingerprint = fingerprint
        self.parts = parts or {}
        """A digest of each part of the campaign (model, settings, points...), by name."""
        self.done: dict[int, dict[str, Any]] = {}
        self.waiting: list[dict[str, Any]] = []
        self.oldest = 0.0
        self.next_chunk = 0
        self._lock: BinaryIO | None = None
        try:
            self.folder.mkdir()
            created = True
        except FileExistsError:
            created = False
        except OSError as exc:  # a read-only place, /proc
            raise CannotWrite.of(self.folder, exc) from None
        self._lock = _hold(self.folder)
        try:
            if created:
                manifest = {"fingerprint": fingerprint, "created": time.time(),
                            "parts": self.parts}  # fmt: skip
                write_whole(self.folder / "campaign.json", json.dumps(manifest).encode())
                if resume:  # a typo in --out, or a campaign that finished: say what runs
                    warnings.warn(Note(f"nothing to resume in {self.folder}: every run is run"),
                                  stacklevel=2)  # fmt: skip
            elif not resume:
                raise UsageError(
                    f"{self.folder} holds the results of an unfinished campaign: add --resume "
                    "to finish it (only the missing runs are run), or remove the folder"
                )
            else:
                self._read()
        except BaseException:
            self.close()
            raise

    def _read(self) -> None:
        try:
            manifest = json.loads((self.folder / "campaign.json").read_text())
        except (OSError, ValueError) as exc:
            raise UsageError(f"{self.folder}: cannot read campaign.json ({exc})") from None
        if manifest.get("fingerprint") != self.fingerprint:
            theirs = manifest.get("parts")
            differ = sorted(k for k, v in self.parts.items()
                            if isinstance(theirs, dict) and theirs.get(k) != v)  # fmt: skip
            what = (f"it differs in {', '.join(_PART_WORDS.get(k, k) for k in differ)}" if differ
                    else "a different model, settings or points")  # fmt: skip
            raise UsageError(
                f"{self.folder} holds the results of another campaign ({what}): remove it, "
                "or write the results elsewhere"
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
        self.close()

    def close(self) -> None:
        """Let another campaign write the folder (the lock is released)."""
        if self._lock is not None:
            self._lock.close()
            self._lock = None


def _hold(folder: Path) -> BinaryIO | None:
    """Lock ``folder`` for this campaign: the open lock file (closing it, or dropping it,
    releases the lock), or a UsageError if another campaign holds it; None where the
    system has no advisory locks."""
    if fcntl is None:
        return None
    path = folder / "lock"
    try:
        handle = open(path, "a+b")  # noqa: SIM115 (held open for the campaign)
    except OSError as exc:
        raise CannotWrite.of(path, exc) from None
    try:
        fcntl.flock(handle.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        handle.seek(0)
        holder = handle.read(32).decode(errors="replace").strip()
        handle.close()
        who = f" (process {holder})" if holder.isdigit() else ""
        raise UsageError(
            f"{folder}: another campaign is writing these results now{who}: wait for it to "
            "end, or write the results elsewhere"
        ) from None
    handle.truncate(0)
    handle.write(str(os.getpid()).encode())
    handle.flush()
    return handle
