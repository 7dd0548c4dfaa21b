"""The table of a campaign: one row per run, in run order, written as CSV or Parquet.

Columns, in order: ``run`` (the point's number), the varied names, ``cause``,
``t``, ``j``, ``jumps``, ``zeno_time``, ``message`` (empty for a run that
reached ``t_end``; the error for ``error`` and ``timeout``), then
``<requirement>.holds``, ``.robustness``, ``.violated_at`` for each
requirement, then the summaries (``max:x``...). A value that does not exist
(the ``t`` of a run that failed, the ``violated_at`` of a requirement that
holds) is empty in CSV and null in Parquet.

Examples
--------
>>> table = SweepTable(["run", "e", "cause"], [{"run": 0, "e": 0.5, "cause": "t_end"}], ["e"], [])
>>> print(table.csv_text(), end="")
run,e,cause
0,0.5,t_end
>>> table.column("e")
[0.5]
"""

from __future__ import annotations

import csv
import io
import warnings
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

from hybrid.campaigns.resumable import write_whole
from hybrid.errors import UnknownName, UsageError, did_you_mean
from hybrid.version import install_hint

__all__ = ["FAILED", "IncompleteWarning", "SweepTable", "column_type"]


class IncompleteWarning(UserWarning):
    """A campaign's table written with some of its runs only (it was stopped early)."""


FAILED = ("error", "timeout")
"""Causes of a run that did not run to an end of its own."""


def column_type(name: str, varied: Sequence[str]) -> str:
    """``int``, ``float``, ``bool`` or ``str``: what a column holds."""
    if name in ("run", "j", "jumps") or name.startswith("jumps:"):  # counts
        return "int"
    if name in ("cause", "message"):
        return "str"
    if name.endswith(".holds") and name not in varied:
        return "bool"
    return "float"


def _text(value: Any) -> str:
    if value is None:
        return ""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return repr(value)
    return str(value)


class SweepTable:
    """Rows of a campaign (``rows``: one dict per run, by run number).

    ``complete`` is False when the campaign stopped early (Ctrl-C) or lost runs
    to its executor (``lost``: a worker died twice under them); the rows are then
    those finished, and a resumed campaign adds the rest. ``resumed`` counts the
    rows a resumed campaign found done.
    """

    def __init__(
        self,
        columns: Sequence[str],
        rows: Sequence[dict[str, Any]],
        varied: Sequence[str],
        requirements: Sequence[str],
        *,
        complete: bool = True,
        total: int | None = None,
        resumed: int = 0,
        lost: int = 0,
        backend: str | None = None,
    ) -> None:
        self.columns = list(columns)
        self.rows = sorted((dict(r) for r in rows), key=lambda r: int(r["run"]))
        self.varied = list(varied)
        self.requirements = list(requirements)
        self.complete = complete
        self.total = len(self.rows) if total is None else total
        self.resumed = resumed
        """Rows read back from an earlier, interrupted run of the campaign (not run again)."""
        self.lost = lost
        """Rows of runs the executor lost (a worker died) even when tried twice: not done."""
        self.backend = backend
        """The backend of the runs this campaign made, ``"scipy"`` or ``"compiled"`` (``auto``
        resolved; a resumed campaign's earlier rows may have run on the other); also in
        the Parquet file's metadata, key ``hybrid.backend``."""

    def __len__(self) -> int:
        return len(self.rows)

    def __iter__(self) -> Iterator[dict[str, Any]]:
        return iter(self.rows)

    def column(self, name: str) -> list[Any]:
        """The values of one column, in run order."""
        if name not in self.columns:
            raise UnknownName(f"no column '{name}' (columns: {', '.join(self.columns)})")
        return [r.get(name) for r in self.rows]

    def failed(self) -> list[dict[str, Any]]:
        """Rows of runs that raised an error or timed out."""
        return [r for r in self.rows if r.get("cause") in FAILED]

    def violations(self, requirement: str) -> list[dict[str, Any]]:
        """Rows of runs that violate ``requirement`` (an :class:`UnknownName` if the table has
        no such requirement: a misspelt one would otherwise read as none violated)."""
        key = f"{requirement}.holds"
        if key not in self.columns:
            known = [c[: -len(".holds")] for c in self.columns if c.endswith(".holds")]
            raise UnknownName(
                f"no requirement '{requirement}' in the table"
                f"{did_you_mean(requirement, known, 0.5)} (requirements: {', '.join(known) or 'none'})"
            )
        return [r for r in self.rows if r.get(key) is False]

    def csv_text(self) -> str:
        """The table as CSV text (numbers exactly, as Python's shortest repr)."""
        buffer = io.StringIO()
        writer = csv.writer(buffer, lineterminator="\n")
        writer.writerow(self.columns)
        for row in self.rows:
            writer.writerow([_text(row.get(c)) for c in self.columns])
        return buffer.getvalue()

    def to_arrow(self) -> Any:
        """The table as a ``pyarrow.Table`` (needs the ``parquet`` extra)."""
        try:
            import pyarrow as pa
        except ImportError:
            raise UsageError(f"Parquet needs pyarrow: {install_hint('parquet')}") from None
        kinds = {"int": pa.int64(), "float": pa.float64(), "bool": pa.bool_(), "str": pa.string()}
        arrays = {}
        for name in self.columns:
            kind = column_type(name, self.varied)
            values = [_plain(r.get(name), kind) for r in self.rows]
            arrays[name] = pa.array(values, type=kinds[kind])
        table = pa.table(arrays)
        if self.backend is not None:
            table = table.replace_schema_metadata({"hybrid.backend": self.backend})
        return table

    def to_pandas(self) -> Any:
        """The table as a ``pandas.DataFrame`` (nullable integer and boolean columns)."""
        try:
            import pandas as pd
        except ImportError:
            raise UsageError(f"to_pandas needs pandas: {install_hint('pandas')}") from None
        dtypes = {"int": "Int64", "float": "float64", "bool": "boolean", "str": "string"}
        data = {}
        for name in self.columns:
            kind = column_type(name, self.varied)
            values = [_plain(r.get(name), kind) for r in self.rows]
            data[name] = pd.array(values, dtype=dtypes[kind])
        return pd.DataFrame(data, columns=self.columns)

    def write(self, path: str | Path) -> Path:
        """Write the table to ``path`` (``.csv`` or ``.parquet``), whole or not at all.

        A table of a campaign stopped early (``complete`` False: Ctrl-C, runs lost) is
        written with the rows it has, and an :class:`IncompleteWarning` says so.
        """
        target = Path(path)
        if not self.complete:
            warnings.warn(IncompleteWarning(
                f"{target.name} gets {len(self.rows) - self.lost} of the campaign's {self.total} runs: it "
                "stopped early (interrupted, or runs lost); table.complete is False"),
                stacklevel=2)  # fmt: skip
        suffix = target.suffix.lower()
        if suffix == ".csv":
            write_whole(target, self.csv_text().encode("utf-8"))
        elif suffix == ".parquet":
            import pyarrow.parquet as pq

            buffer = io.BytesIO()
            pq.write_table(self.to_arrow(), buffer)
            write_whole(target, buffer.getvalue())
        else:
            raise UsageError(f"results go to a .csv or .parquet file, got '{path}'")
        return target

    def __repr__(self) -> str:
        state = "" if self.complete else f", incomplete: {len(self.rows)} of {self.total}"
        failed = len(self.failed())
        parts = [f"{len(self.rows)} runs", f"{failed} failed"]
        for name in self.requirements:
            parts.append(f"{name} violated in {len(self.violations(name))}")
        return f"<SweepTable {', '.join(parts)}{state}>"


def _plain(value: Any, kind: str) -> Any:
    """``value`` as a column of ``kind`` holds it (None stays None; NaN floats stay NaN)."""
    if value is None:
        return None
    if kind == "float":
        return float(value)
    if kind == "int":
        return int(value)
    if kind == "bool":
        return bool(value)
    return str(value)
