"""Trajectory files (CSV, NPZ, MATLAB's MAT) and the events JSON of the contract.

CSV columns are ``t,j,location,<state...>,<signals...>``; a jump gives two
rows with the same ``t`` (pre-jump with ``j``, post-jump with ``j + 1``).
Numbers are written as Python's shortest exact representation (at most 17
significant digits), so they read back exactly.

Every writer takes ``progress``, a :mod:`hybrid.progress` reporter that sees
the rows written of the rows to write: a large CSV takes seconds.
"""

from __future__ import annotations

import json
import math
import re
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from hybrid.errors import Note, UsageError
from hybrid.files import atomic_write, writable_target
from hybrid.progress import Reporter, Tracker
from hybrid.simulation.result import Run

__all__ = [
    "TRAJECTORY_SUFFIXES",
    "events_document",
    "write_csv",
    "write_events",
    "write_mat",
    "write_npz",
    "write_trajectory",
]


CHUNK_ROWS = 20_000
"""Rows formatted and written at a time (and between two progress reports)."""


def write_csv(run: Run, path: str | Path, progress: Reporter | None = None) -> None:
    """Write the trajectory as CSV (atomically).

    Columns are formatted whole with ``repr`` (``nan``, ``inf`` and ``-inf`` for
    non-finite values), a chunk of rows at a time.
    """
    _expect_run(run, "write_csv")
    path = writable_target(path)  # a directory, a missing folder: refused first
    rows = len(run)
    tracker = Tracker(f"writing {Path(path).name}", total=rows, unit="rows", report=progress)
    header = ",".join(["t", "j", "location", *run.state_names, *run.signal_names]) + "\n"
    # a set, not np.unique: the names are str objects, which numpy would sort (seconds for
    # a million points), where a set only hashes them (each hash kept by its shared str)
    quoted = {name: _csv_text(str(name)) for name in set(run.location.tolist())}
    with atomic_write(path) as handle:
        handle.write(header.encode("utf-8"))
        for start in range(0, rows, CHUNK_ROWS):
            stop = min(rows, start + CHUNK_ROWS)
            columns = [
                list(map(repr, run.t[start:stop].tolist())),
                list(map(str, run.j[start:stop].tolist())),
                [quoted[name] for name in run.location[start:stop].tolist()],
            ]
            columns.extend(list(map(repr, col)) for col in run.states[start:stop].T.tolist())
            columns.extend(list(map(repr, col)) for col in run.signals[start:stop].T.tolist())
            text = "\n".join(map(",".join, zip(*columns, strict=True))) + "\n"
            handle.write(text.encode("utf-8"))
            tracker.update(stop)
    tracker.finish(rows)


def _csv_text(text: str) -> str:
    return f'"{text}"' if any(c in text for c in ',"\n') else text


def write_npz(run: Run, path: str | Path, progress: Reporter | None = None) -> None:
    """Write the trajectory as a NumPy ``.npz`` archive (atomically)."""
    _expect_run(run, "write_npz")
    path = writable_target(path)  # a directory, a missing folder: refused first
    arrays: dict[str, Any] = {
        "t": run.t,
        "j": run.j,
        "location": run.location.astype(str),
        "state_names": np.array(run.state_names, dtype=str),
        "signal_names": np.array(run.signal_names, dtype=str),
        "states": run.states,
        "signals": run.signals,
    }
    tracker = Tracker(f"writing {Path(path).name}", total=len(run), unit="rows", report=progress)
    with atomic_write(path) as handle:
        np.savez(handle, **arrays)
    tracker.finish(len(run))


MATLAB_KEYWORDS = frozenset([
    "break", "case", "catch", "classdef", "continue", "else", "elseif", "end", "for",
    "function", "global", "if", "otherwise", "parfor", "persistent", "return", "spmd",
    "switch", "try", "while",
])  # fmt: skip
"""MATLAB's keywords (``iskeyword``): no variable may be named one."""
MATLAB_NAME_LENGTH = 63
"""The longest variable name MATLAB takes (``namelengthmax``)."""


def matlab_name(name: str, taken: Mapping[str, object] | set[str]) -> str:
    """``name`` as a MATLAB variable name not in ``taken``: itself when it can be.

    A letter first, then letters, digits and ``_``; no keyword; at most 63 characters.

    >>> matlab_name("h", {}), matlab_name("states", {"states": 0}), matlab_name("_u", {})
    ('h', 'states_', 'x_u')
    >>> matlab_name("end", {}), matlab_name("plant.x", {}), len(matlab_name("v" * 100, {}))
    ('end_', 'plant_x', 63)
    """
    base = re.sub(r"[^A-Za-z0-9_]", "_", name)
    base = base if base[:1].isalpha() else f"x{base}"
    base = (base + "_" if base in MATLAB_KEYWORDS else base)[:MATLAB_NAME_LENGTH]
    if base not in taken:
        return base
    found, k = (base + "_")[:MATLAB_NAME_LENGTH], 1
    while found in taken:
        k += 1
        tail = f"_{k}"
        found = base[: MATLAB_NAME_LENGTH - len(tail)] + tail
    return found


def write_mat(run: Run, path: str | Path, progress: Reporter | None = None) -> None:
    """Write the trajectory as a MATLAB ``.mat`` file (version 5, atomically).

    The arrays of :func:`write_npz`, as MATLAB reads them: ``t`` and ``j`` are
    columns (as ``ode45`` returns ``t``), ``states`` and ``signals`` one row per
    point, ``location``, ``state_names`` and ``signal_names`` character matrices
    (``cellstr(location)`` in MATLAB); and each state variable and signal under
    its own name, a column. A name MATLAB cannot take as it is (one of those
    arrays' names, a keyword, one starting with ``_`` or longer than 63
    characters) is written under a name it can (:func:`matlab_name`), and a
    :class:`~hybrid.errors.Note` says which.

    Examples
    --------
    >>> import hybrid, scipy.io, tempfile, pathlib
    >>> run = hybrid.simulate(hybrid.load("specs/bouncing_ball.yaml"), t_end=2.0)
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "ball.mat"
    >>> write_mat(run, path)
    >>> back = scipy.io.loadmat(path)
    >>> back["h"].shape == (len(run), 1), bool((back["h"][:, 0] == run["h"]).all())
    (True, True)
    """
    _expect_run(run, "write_mat")
    path = writable_target(path)  # a directory, a missing folder: refused first
    from scipy.io import savemat

    arrays: dict[str, Any] = {
        "t": run.t,
        "j": run.j.astype(np.float64),
        "location": run.location.astype(str),
        "state_names": np.array(run.state_names, dtype=str),
        "signal_names": np.array(run.signal_names, dtype=str),
        "states": run.states,
        "signals": run.signals,
    }
    renamed = []
    for name in (*run.state_names, *run.signal_names):
        written = matlab_name(name, arrays)
        arrays[written] = run[name]
        if written != name:
            renamed.append(f"'{name}' is {written}")
    if renamed:  # savemat would drop or overwrite them without a word
        warnings.warn(Note(f"{Path(path).name}: {', '.join(renamed)} (MATLAB cannot take "
                           "the name as it is)"), stacklevel=2)  # fmt: skip
    tracker = Tracker(f"writing {Path(path).name}", total=len(run), unit="rows", report=progress)
    with atomic_write(path) as handle:
        savemat(handle, arrays, oned_as="column", do_compression=True)
    tracker.finish(len(run))


TRAJECTORY_SUFFIXES = (".csv", ".npz", ".mat")
"""The trajectory files ``hybrid simulate --out`` writes, by suffix."""


def write_trajectory(run: Run, path: str | Path, progress: Reporter | None = None) -> None:
    """Write the trajectory in the format its suffix names (:data:`TRAJECTORY_SUFFIXES`)."""
    writer = {".npz": write_npz, ".mat": write_mat}.get(Path(path).suffix.lower(), write_csv)
    writer(run, path, progress)


def events_document(run: Run) -> dict[str, Any]:
    """The events JSON document: termination, every jump, each requirement's result, and
    where the run left the declared bounds of a state variable."""
    return {
        "model": run.model,
        "termination": run.termination.as_dict(),
        "jumps": [jump.as_dict() for jump in run.jumps],
        "requirements": {name: r.as_dict() for name, r in run.requirements.items()},
        "out_of_bounds": [excursion.as_dict() for excursion in run.out_of_bounds],
        "settings": run.settings,
    }


def write_events(run: Run, path: str | Path, progress: Reporter | None = None) -> None:
    """Write the events JSON (atomically); non-finite numbers become null."""
    _expect_run(run, "write_events")
    path = writable_target(path)  # a directory, a missing folder: refused first
    tracker = Tracker(
        f"writing {Path(path).name}", total=len(run.jumps), unit="jumps", report=progress
    )
    text = json.dumps(_finite(events_document(run)), indent=2) + "\n"
    with atomic_write(path) as handle:
        handle.write(text.encode("utf-8"))
    tracker.finish(len(run.jumps))


def _finite(value: Any) -> Any:
    """``value`` as JSON takes it: non-finite numbers null, numpy's numbers Python's
    (``t_end=np.int64(3)`` is kept in ``run.settings`` as given)."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    return value


def _expect_run(run: object, writer: str) -> None:
    """A :class:`UsageError` unless ``run`` is what :func:`hybrid.simulate` returns."""
    if not isinstance(run, Run):
        raise UsageError(f"{writer}() writes a run from hybrid.simulate, got {type(run).__name__}")
