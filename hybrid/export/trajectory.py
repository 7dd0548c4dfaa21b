"""Trajectory files (CSV, NPZ) and the events JSON of the contract.

CSV columns are ``t,j,location,<state...>,<signals...>``; a jump gives two
rows with the same ``t`` (pre-jump with ``j``, post-jump with ``j + 1``).
Numbers are written with 17 significant digits, so they read back exactly.
"""

from __future__ import annotations

import io
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from hybrid.export.atomic import atomic_write
from hybrid.simulation.result import Run

__all__ = ["events_document", "write_csv", "write_events", "write_npz"]


def _number(value: float) -> str:
    return (
        repr(float(value))
        if math.isfinite(value)
        else ("nan" if math.isnan(value) else ("inf" if value > 0 else "-inf"))
    )


def write_csv(run: Run, path: str | Path) -> None:
    """Write the trajectory as CSV (atomically)."""
    buffer = io.StringIO()
    buffer.write(",".join(["t", "j", "location", *run.state_names, *run.signal_names]) + "\n")
    for i in range(len(run)):
        values = [*run.states[i], *run.signals[i]]
        row = [_number(run.t[i]), str(int(run.j[i])), _csv_text(str(run.location[i]))]
        row.extend(_number(v) for v in values)
        buffer.write(",".join(row) + "\n")
    with atomic_write(path) as handle:
        handle.write(buffer.getvalue().encode("utf-8"))


def _csv_text(text: str) -> str:
    return f'"{text}"' if any(c in text for c in ',"\n') else text


def write_npz(run: Run, path: str | Path) -> None:
    """Write the trajectory as a NumPy ``.npz`` archive (atomically)."""
    arrays: dict[str, Any] = {
        "t": run.t,
        "j": run.j,
        "location": run.location.astype(str),
        "state_names": np.array(run.state_names, dtype=str),
        "signal_names": np.array(run.signal_names, dtype=str),
        "states": run.states,
        "signals": run.signals,
    }
    with atomic_write(path) as handle:
        np.savez(handle, **arrays)


def events_document(run: Run) -> dict[str, Any]:
    """The events JSON document: termination and every jump."""
    return {
        "model": run.model,
        "termination": run.termination.as_dict(),
        "jumps": [jump.as_dict() for jump in run.jumps],
        "settings": run.settings,
    }


def write_events(run: Run, path: str | Path) -> None:
    """Write the events JSON (atomically); non-finite numbers become null."""
    text = json.dumps(_finite(events_document(run)), indent=2) + "\n"
    with atomic_write(path) as handle:
        handle.write(text.encode("utf-8"))


def _finite(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    return value
