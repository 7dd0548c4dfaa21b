"""Whether a Ctrl-C is behind an exception, and the command's exit code then: imported
before anything else of the command (``hybrid/__main__.py``).

Examples
--------
>>> try:
...     try:
...         raise KeyboardInterrupt
...     except KeyboardInterrupt as stop:
...         raise ImportError("initialization failed") from stop
... except ImportError as exc:
...     caused_by_interrupt(exc), caused_by_interrupt(ImportError("no module"))
(True, False)
"""

from __future__ import annotations

__all__ = ["EXIT_ABANDONED", "caused_by_interrupt"]

EXIT_ABANDONED = 130
"""The exit code of a command stopped by Ctrl-C before it computed anything, or whose
outputs a Ctrl-C abandoned (:mod:`hybrid.cli.exits` lists it with the others)."""


def caused_by_interrupt(exc: BaseException) -> bool:
    """Whether a Ctrl-C is behind ``exc``: an extension module whose initialisation was
    interrupted raises ``ImportError: initialization failed`` from it."""
    seen: set[int] = set()
    cause: BaseException | None = exc
    while cause is not None and id(cause) not in seen:
        if isinstance(cause, KeyboardInterrupt):
            return True
        seen.add(id(cause))
        cause = cause.__cause__ or cause.__context__
    return False
