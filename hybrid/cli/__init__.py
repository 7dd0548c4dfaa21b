"""The ``hybrid`` command line (also ``python -m hybrid``).

:mod:`~hybrid.cli.main` parses the arguments and maps errors to exit codes;
each command group has a module: :mod:`~hybrid.cli.simulate`,
:mod:`~hybrid.cli.check` (``check`` and ``graph``).
"""

from hybrid.cli.main import EXIT_FINDINGS, EXIT_INVALID, EXIT_OK, build_parser, main

__all__ = ["EXIT_FINDINGS", "EXIT_INVALID", "EXIT_OK", "build_parser", "main"]
