"""Outputs decided before the work: a path that cannot be written is refused up front.

Every command that writes asks :func:`writable_file` (or :func:`writable_directory`)
about each output before it loads, simulates or sweeps anything, so no work is
lost to a bad path. The question is answered by doing what the write will do:
creating (and removing) the hidden temporary file that
:func:`~hybrid.files.atomic_write` renames over the target, in the
target's folder. That catches what a look at permission bits cannot: a path in
``/proc``, a read-only mount, a folder of another user, a name that is a folder.

A write can still fail at the end (a disk that fills during the run): then
:func:`keep_elsewhere` writes what was computed into a fresh folder of the
temporary directory, and the message names it.

Examples
--------
>>> import tempfile, pathlib
>>> folder = pathlib.Path(tempfile.mkdtemp())
>>> writable_file(folder / "run.csv", "--out") == folder / "run.csv"
True
>>> writable_file(folder, "--out")
Traceback (most recent call last):
...
hybrid.errors.UsageError: --out: '...' is a directory: give a file name inside it
"""

from __future__ import annotations

import contextlib
import errno
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

from hybrid.errors import UsageError

__all__ = ["keep_elsewhere", "make_directory", "reason", "writable_directory", "writable_file"]


def reason(exc: OSError) -> str:
    """The operating system's words for ``exc`` (``Permission denied``, ...)."""
    return exc.strerror or (errno.errorcode.get(exc.errno or 0) or str(exc))


def writable_file(path: str | Path, flag: str) -> Path:
    """``path`` if a file can be created or replaced there, else a :class:`UsageError`.

    ``flag`` names the option in the message (``--out``). The folder must exist
    (it is not created: a typo in it would otherwise scatter folders), ``path``
    must not be a folder, and a temporary file must be creatable beside it.
    """
    if not str(path).strip():  # Path("") is '.', a directory: said as what it is
        raise UsageError(f"{flag}: the file name is empty")
    target = Path(path)
    if target.is_dir():
        raise UsageError(f"{flag}: '{path}' is a directory: give a file name inside it")
    if not target.parent.is_dir():  # a bare name's parent is '.'

        raise UsageError(f"{flag}: directory of '{path}' does not exist")
    _probe(target, flag, path)
    return target


def writable_directory(path: str | Path, flag: str) -> Path:
    """``path`` as a folder that files can be written into (created later, by the writer).

    Nothing is created now: the nearest folder that exists on the way to ``path``
    must accept new entries. A :class:`UsageError` names ``flag`` when ``path`` is
    a file or its nearest existing ancestor refuses new files.
    """
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise UsageError(f"{flag}: '{path}' exists and is not a directory")
    existing = folder
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        raise UsageError(f"{flag}: '{existing}' on the way to '{path}' is not a directory")
    _probe(existing / "probe", flag, path)
    return folder


def make_directory(folder: Path, flag: str) -> Path:
    """Create ``folder`` and its parents (a :class:`UsageError` naming ``flag`` if it cannot)."""
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise UsageError(f"{flag}: cannot create the directory '{folder}': {reason(exc)}") from None
    return folder


def _probe(target: Path, flag: str, shown: str | Path) -> None:
    from hybrid.files import temporary_name, write_through

    replaced = write_through(target)
    if replaced is None:  # a device or a pipe, written into in place
        if not os.access(target, os.W_OK):
            raise UsageError(f"{flag}: cannot write '{shown}': Permission denied")
        return
    if not replaced.parent.is_dir():  # a link to a file in a folder that is not there
        raise UsageError(f"{flag}: the link '{shown}' points into a folder that does not exist")
    probe = temporary_name(replaced)
    try:
        fd = os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except OSError as exc:
        raise UsageError(f"{flag}: cannot write '{shown}': {reason(exc)}") from None
    os.close(fd)
    with contextlib.suppress(OSError):
        os.unlink(probe)


def keep_elsewhere(
    target: str | Path, write: Callable[[Path], object], exc: OSError, flag: str
) -> UsageError:
    """After ``write(target)`` failed with ``exc``: write to a fresh temporary folder instead.

    Returns the error to raise, naming where the output was kept (or that it
    could not be kept either), so what a run computed is not lost to a full disk
    or a folder that went away.
    """
    name = Path(target).name or "output"
    try:
        folder = Path(tempfile.mkdtemp(prefix="hybrid-kept-"))
        write(folder / name)
    except OSError:
        return UsageError(f"{flag}: cannot write '{target}': {reason(exc)} (nor keep it elsewhere)")
    return UsageError(f"{flag}: cannot write '{target}': {reason(exc)}; kept in {folder / name}")
