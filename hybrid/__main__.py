"""The ``hybrid`` command (console script) and ``python -m hybrid``.

:func:`entry` imports the command line inside its own Ctrl-C handling: before
it runs, only Python's start-up and ``hybrid/__init__`` (no third-party module,
no ``typing``) have run, so a Ctrl-C while the command line and what it needs
are imported ends in one line and exit 130, as it does later
(:func:`hybrid.cli.main.main`). This module imports nothing but :mod:`sys` and
:mod:`hybrid.interrupted` at its top.
"""

import sys

from hybrid.interrupted import EXIT_ABANDONED, caused_by_interrupt


def entry() -> int:
    """Import the command line and run it; Ctrl-C during the import ends with one line, 130."""
    try:
        from hybrid.cli.main import entry as command
    except BaseException as exc:  # KeyboardInterrupt, or an ImportError it caused
        if not caused_by_interrupt(exc):
            raise
        import signal

        signal.signal(signal.SIGINT, signal.SIG_IGN)  # a second Ctrl-C while we say so
        print("hybrid: interrupted", file=sys.stderr)
        return EXIT_ABANDONED
    return command()


if __name__ == "__main__":
    raise SystemExit(entry())
