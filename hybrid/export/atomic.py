"""Whole-or-nothing file writes: write a temporary file beside the target, then rename.

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
import os
import secrets
import stat
from collections.abc import Iterator
from pathlib import Path
from typing import BinaryIO

__all__ = ["atomic_write", "temporary_name"]

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
    the permissions of the umask; a replaced one keeps its own.
    """
    target = Path(path)
    fd, tmp = _create(target)
    try:
        with os.fdopen(fd, "wb") as handle:
            with contextlib.suppress(FileNotFoundError):
                mode = stat.S_IMODE(os.stat(target).st_mode)
                os.chmod(handle.fileno() if os.chmod in os.supports_fd else tmp, mode)
            yield handle
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, target)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise
