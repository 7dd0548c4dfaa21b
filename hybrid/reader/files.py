"""Reading files from users safely: regular files only, bounded reads, errors with a place.

A spec path comes from anyone (a command line, a ``spec:`` of a system file in
CI), so reading one must never block, never run away and never escape as a
traceback: :func:`read_bytes` opens without blocking (a FIFO would otherwise
wait for a writer), refuses anything but a regular file (FIFOs, devices such
as ``/dev/zero`` whose size reads as 0, directories), reads at most
``max_bytes + 1`` bytes whatever the file's size claims, and turns every OS
error on the path (missing, no permission, a NUL byte in the name, a name
longer than the file system allows) into a :class:`~hybrid.errors.SpecError`
at the position given: the file itself, or the ``spec:`` naming it.

Examples
--------
>>> read_bytes("specs/thermostat.yaml")[:10]
b'# yaml-lan'
>>> read_bytes("/dev/zero")
Traceback (most recent call last):
...
hybrid.errors.SpecError: /dev/zero:1:1: cannot read file: not a regular file (a character device)
>>> read_bytes("no\\x00where", where=Position("plant.yaml", 4, 12))
Traceback (most recent call last):
...
hybrid.errors.SpecError: plant.yaml:4:12: cannot read 'no\\x00where': the name holds a NUL byte
"""

from __future__ import annotations

import errno
import os
import stat
from pathlib import Path

from hybrid.errors import Position, SpecError

__all__ = ["MAX_FILE_BYTES", "read_bytes"]

MAX_FILE_BYTES = 16 * 1024 * 1024
"""Largest spec file accepted (16 MiB): beyond it, a spec is refused unread."""

_FLAGS = (
    os.O_RDONLY
    | getattr(os, "O_NONBLOCK", 0)
    | getattr(os, "O_NOCTTY", 0)
    | getattr(os, "O_CLOEXEC", 0)
    | getattr(os, "O_BINARY", 0)
)
_KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)
_REASONS = {
    errno.ENOENT: "not found",
    errno.ENOTDIR: "a part of the path is not a directory",
    errno.EACCES: "permission denied",
    errno.EPERM: "permission denied",
    errno.ENAMETOOLONG: "the name is longer than the file system allows",
    errno.ELOOP: "too many levels of symbolic links",
    errno.EISDIR: "not a regular file (a directory)",
}


def read_bytes(
    path: str | Path, *, max_bytes: int = MAX_FILE_BYTES, where: Position | None = None
) -> bytes:
    """The bytes of the regular file ``path`` (at most ``max_bytes``), or a :class:`SpecError`.

    ``where`` is the position the error points at (default: the file itself).
    """
    name = str(path)
    place = where or Position(name)

    def refuse(reason: str) -> SpecError:
        shown = name if len(name) <= 80 else f"{name[:60]}...{name[-16:]}"
        what = "file" if where is None else repr(shown)
        return SpecError(f"cannot read {what}: {reason}", place)

    if "\0" in name:
        raise refuse("the name holds a NUL byte")
    try:
        fd = os.open(name, _FLAGS)
    except (OSError, ValueError) as exc:
        raise refuse(_reason(exc)) from None
    try:
        info = os.fstat(fd)
        if not stat.S_ISREG(info.st_mode):
            kind = next((k for test, k in _KINDS if test(info.st_mode)), "a special file")
            raise refuse(f"not a regular file ({kind})")
        os.set_blocking(fd, True)
        chunks: list[bytes] = []
        total = 0
        while total <= max_bytes:
            chunk = os.read(fd, min(1 << 20, max_bytes + 1 - total))
            if not chunk:
                break
            chunks.append(chunk)
            total += len(chunk)
        if total > max_bytes:
            raise refuse(f"over the limit of {max_bytes} bytes for a spec")
        return b"".join(chunks)
    except OSError as exc:
        raise refuse(_reason(exc)) from None
    finally:
        os.close(fd)


def _reason(exc: OSError | ValueError) -> str:
    if isinstance(exc, ValueError):
        return str(exc)
    return _REASONS.get(exc.errno or 0, exc.strerror or str(exc))
