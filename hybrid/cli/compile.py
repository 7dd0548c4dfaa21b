"""The ``hybrid compile`` command: compile models for the compiled backend ahead of their runs.

For CI caches and installs: each FILE's compiled form (and, the first time on a
machine, the kernel and its ensemble loop) is compiled into the compiled-model
cache (``$HYBRID_NATIVE_CACHE``, see :mod:`hybrid.simulation.native.cache`), so
that a later ``--backend compiled`` (or ``auto``) run finds it there. One line
per file says whether it was compiled or found and how long that took; exit 0,
or 2 for a file that is not a valid model, that the compiled backend cannot
compile, or without numba installed.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from hybrid.cli.exits import EXIT_INVALID, EXIT_OK, error_line

__all__ = ["add_compile_command", "compile_notes", "run_compile"]


def add_compile_command(sub: Any) -> None:
    """Add ``hybrid compile`` to the subcommands."""
    p = sub.add_parser("compile", help="compile models for the compiled backend ahead of runs")
    p.add_argument("files", nargs="+", metavar="FILE", help="spec or system files")


@contextmanager
def compile_notes(file: str, line: Any = None) -> Iterator[None]:
    """Within it, a compiled run about to compile prints ``FILE: note: compiling ...``
    (what, and about how long: :func:`~hybrid.simulation.native.choice.compile_notices`),
    after every check that may still refuse the run; ``line``: the progress line, if any."""
    from hybrid.simulation.native.choice import compile_notices

    def say(notice: str) -> None:
        text = f"{file}: note: {notice}"
        if line is not None:
            line.message(text)
        else:
            print(text, file=sys.stderr, flush=True)

    with compile_notices(say):
        yield


def run_compile(files: list[str]) -> int:
    """Compile (or load from the cache) each file's model, the kernels once; say which."""
    from hybrid.compose import as_system
    from hybrid.errors import SimulationError, SpecError, UsageError
    from hybrid.reader.loader import load
    from hybrid.simulation.interrupts import immediate
    from hybrid.simulation.native.cache import require_numba
    from hybrid.simulation.native.choice import cached
    from hybrid.simulation.native.engine import compiled_native, kernel

    require_numba()
    status = EXIT_OK
    for path in files:  # one line each: a file that cannot be compiled does not stop the rest
        try:
            model = as_system(load(path))
            model_state, kernel_state, _ = cached(model)
            start = time.perf_counter()
            with immediate("compiling the model (nothing was kept)"):
                compiled_native(model)
                kernel(parallel=True)  # the ensemble loop, for simulate_many and compiled sweeps
        except (SpecError, UsageError, SimulationError) as exc:
            print(error_line(exc, path), file=sys.stderr)
            status = EXIT_INVALID
            continue
        took = time.perf_counter() - start
        if model_state == "missing" or kernel_state == "missing":
            what = "compiled" if kernel_state != "missing" else "compiled with the kernel"
        else:
            what = "found in the cache"
        print(f"{path}: {what} ({took:.1f} s)", file=sys.stderr)
    return status
