"""Exit codes of the ``hybrid`` command (CONTRACT.md).

- 0: success (``simulate`` reached t-end; ``check`` found no error);
- 1: findings (``check``), a run that ended otherwise or violated a requirement;
- 2: an invalid spec or invalid usage;
- 130: stopped by Ctrl-C before anything was computed, or outputs abandoned by a
  deliberate Ctrl-C while they were written (a Ctrl-C during a run ends it cleanly,
  exit 1, outputs written).
"""

from hybrid.interrupted import EXIT_ABANDONED  # defined where `hybrid/__main__` reads it

__all__ = ["EXIT_ABANDONED", "EXIT_FINDINGS", "EXIT_INVALID", "EXIT_OK", "error_line"]

EXIT_OK = 0
EXIT_FINDINGS = 1
EXIT_INVALID = 2


def error_line(exc: Exception, file: str) -> str:
    """The one line a command prints for a refusal (exit 2): the error's own place
    (``file:line:column``) first when it has one, else ``file``, the command's spec."""
    from hybrid.errors import SpecError, UsageError  # at a refusal only: not at start-up

    placed = isinstance(exc, SpecError) or (isinstance(exc, UsageError) and exc.at is not None)
    return str(exc) if placed else f"{file}: {exc}"
