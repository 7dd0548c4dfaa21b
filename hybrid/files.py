"""Whole-or-nothing file writes: write a temporary file beside the target, then rename.

What is renamed over is always a regular file: a symbolic link is written
through (its target replaced, the link kept), and a device, a pipe or a socket
(``/dev/null``, ``/dev/stdout``, a FIFO) is written into directly, since it
cannot be replaced whole and must not be replaced by a file.

The temporary file is created with mode ``0o666`` filtered by the process umask,
as the operating system does for any new file (``mkstemp`` would make it
``0o600``), so the result has the permissions a user expects: ``0o644`` under
the usual umask ``022``. Replacing an existing file keeps that file's
permission bits, as writing into it would.

Examples
--------
>>> import tempfile, pathlib
>>> target = pathlib.Path(tempfile.mkdtemp()) / "out.txt"
>>> with atomic_write(target) as f:
...     _ = f.write(b"done")
>>> target.read_bytes()
b'done'
"""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

from hybrid.errors import CannotWrite, UsageError

__all__ = ["atomic_write", "temporary_name", "writable_target", "write_through"]

_ATTEMPTS = 100


def temporary_name(target: Path) -> Path:
    """A fresh hidden name ``.NAME.XXXXXXXX.tmp`` beside ``target`` (not created)."""
    return target.with_name(f".{target.name}.{secrets.token_hex(4)}.tmp")


def _create(target: Path) -> tuple[int, Path]:
    """Create a new temporary file beside ``target``: its descriptor and path.

    ``os.open`` with ``O_CREAT | O_EXCL`` and mode ``0o666`` lets the kernel apply
    the umask, with no window in which another process could see the file with
    other permissions; a name already taken is retried with another.
    """
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_BINARY", 0)
    for _ in range(_ATTEMPTS):
        candidate = temporary_name(target)
        try:
            return os.open(candidate, flags, 0o666), candidate
        except FileExistsError:
            continue
    raise FileExistsError(f"no free temporary name beside {target}")


@contextlib.contextmanager
def atomic_write(path: str | Path) -> Iterator[BinaryIO]:
    """Open a temporary file for writing; on success it replaces ``path`` in one rename.

    If the block raises (or the process dies), ``path`` is left as it was and
    the temporary file is removed (or, on a hard kill, left as a hidden
    ``.name.*.tmp`` file, never as a half-written ``path``). A new file gets
    the permissions of the umask; a replaced one keeps its own. A path that
    cannot be written (a directory, a missing folder, no permission, a full
    disk) is a :class:`~hybrid.errors.CannotWrite`, an ``OSError`` too.
    """
    given = writable_target(path)
    target = write_through(given)
    if target is None:  # a device, a pipe: written into, in place
        with _in_place(given) as handle:
            yield handle
        return
    try:
        fd, tmp = _create(target)
    except OSError as exc:
        raise CannotWrite.of(target, exc) from None
    try:
        with os.fdopen(fd, "wb") as handle:
            with contextlib.suppress(FileNotFoundError):
                mode = stat.S_IMODE(os.stat(target).st_mode)
                os.chmod(handle.fileno() if os.chmod in os.supports_fd else tmp, mode)
            yield handle
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, target)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        if isinstance(exc, OSError) and not isinstance(exc, CannotWrite):
            raise CannotWrite.of(target, exc) from exc  # a full disk, a folder gone
        raise


def write_through(target: Path) -> Path | None:
    """The regular file a write to ``target`` replaces, or None for a device, pipe or socket.

    A symbolic link gives the file it names (made absolute), so that the link
    stays a link; anything else gives ``target`` itself.

    Examples
    --------
    >>> write_through(Path("/dev/null")) is None
    True
    >>> write_through(Path("results.csv"))
    PosixPath('results.csv')
    """
    try:
        kind = os.stat(target).st_mode  # follows links
    except OSError:
        kind = None  # not there yet (or a link to a file not there yet)
    if kind is not None and not stat.S_ISREG(kind):
        return None
    if target.is_symlink():
        return Path(os.path.realpath(target))
    return target


@contextlib.contextmanager
def _in_place(target: Path) -> Iterator[BinaryIO]:
    """Write into a device or pipe as it is (no temporary, no rename, no ``fsync``)."""
    opened = False
    try:
        with open(target, "wb") as handle:
            opened = True
            yield handle
            handle.flush()
    except OSError as exc:
        if not opened:
            raise CannotWrite.of(target, exc) from None
        if isinstance(exc, CannotWrite):
            raise
        raise CannotWrite.of(target, exc) from exc  # /dev/full: no space left


def writable_target(path: object) -> Path:
    """``path`` as a :class:`~pathlib.Path` a file can be written to, else a :class:`CannotWrite`
    (a directory, a missing folder) or a :class:`~hybrid.errors.UsageError` (not a path)."""
    if isinstance(path, bytes):
        path = os.fsdecode(path)
    if not isinstance(path, str | os.PathLike):
        raise UsageError(f"a file to write is named by a str or Path, got {type(path).__name__}")
    target = Path(path)
    if target.is_dir():
        raise CannotWrite.of(target, IsADirectoryError(errno.EISDIR, "it is a directory"),
                             ": give a file name inside it")  # fmt: skip
    if not target.parent.is_dir():
        raise CannotWrite.of(target, FileNotFoundError(errno.ENOENT, "its folder does not exist"))
    return target
