"""The ``hybrid`` command line: one subcommand per task (``hybrid --help`` lists them all).

Exit codes: 0 success; 1 findings (check) or a run that ended before t-end
(simulate); 2 an invalid spec or invalid usage. Errors go to stderr as
``file:line:column: message``; a user never sees a traceback.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import math
import re
import select
import sys
import warnings
from collections.abc import Callable, Iterator, Sequence
from typing import Any, TextIO

from hybrid.cli.exits import EXIT_ABANDONED, EXIT_FINDINGS, EXIT_INVALID, EXIT_OK, error_line
from hybrid.errors import Note, SimulationError, SpecError, UsageError
from hybrid.interrupted import caused_by_interrupt
from hybrid.version import __version__

__all__ = ["EXIT_FINDINGS", "EXIT_INVALID", "EXIT_OK", "build_parser", "entry", "main"]


class _Parser(argparse.ArgumentParser):
    """argparse that exits with code 2 and one line of error (no usage block).

    The line names a flag the command does not have with the one meant (another
    tool's spelling, a typo, ``_`` for ``-``), also when argparse would only say
    that a required flag is missing (``--tend 5``), and MATLAB's solver names.
    """

    _given: list[str]

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        # no abbreviations: `--initial h=2` would be taken as `--initial-location h=2`,
        # and every new flag could make an abbreviation a user relies on ambiguous
        kwargs.setdefault("allow_abbrev", False)
        super().__init__(*args, **kwargs)

    def parse_known_args(  # type: ignore[override]
        self, args: Sequence[str] | None = None, namespace: argparse.Namespace | None = None
    ) -> tuple[argparse.Namespace, list[str]]:
        self._given = list(sys.argv[1:] if args is None else args)
        parsed, extras = super().parse_known_args(args, namespace)
        unknown = self._unknown_flags(extras)
        if unknown and self._subcommand():
            self.error(f"unrecognized argument {unknown[0]}")
        return parsed, extras

    def error(self, message: str) -> None:  # type: ignore[override]
        if message.startswith("the following arguments are required") and self._subcommand():
            unknown = self._unknown_flags(getattr(self, "_given", []))
            if unknown:  # the likely cause: a flag spelled otherwise
                message = f"unrecognized argument {unknown[0]}"
        if message.startswith("unrecognized argument "):
            message += _flag_hint(message.split()[2], self._flags())
        elif message.startswith("argument --method: invalid choice: "):
            from hybrid.simulation.settings import method_hint

            hint = method_hint(message.split("'")[1])
            message = f"argument --method: {hint}" if hint else message
        elif ": invalid choice: '" in message:  # a command, a format: the closest choice
            from hybrid.errors import did_you_mean

            given, _, listed = message.split(": invalid choice: '", 1)[1].partition("'")
            choices = re.findall(r"'([^']*)'", listed)
            message += did_you_mean(given, choices, aliases=_CHOICE_HABITS)
        sys.stderr.write(f"hybrid: error: {message}\n")
        raise SystemExit(EXIT_INVALID)

    def _subcommand(self) -> bool:
        return " " in self.prog  # "hybrid simulate"; the top parser's is "hybrid"

    def _flags(self) -> list[str]:
        return [o for a in self._actions for o in a.option_strings]

    def _unknown_flags(self, words: Sequence[str]) -> list[str]:
        """The words that look like flags and are none of this command's (not "-1")."""
        flags = set(self._flags())
        return [
            w for w in words
            if w.startswith("-") and w != "-" and not w[1:2].isdigit() and w[1:2] != "."
            and w.split("=", 1)[0] not in flags
        ]  # fmt: skip


_FLAG_HABITS = {
    "-o": "--out", "--output": "--out", "-p": "--param", "--set": "--param",
    "--parameter": "--param", "--params": "--param", "--x0": "--init", "--ic": "--init",
    "--initial": "--init", "--tf": "--t-end", "--tfinal": "--t-end", "--tspan": "--t-end",
    "--tend": "--t-end", "--tmax": "--t-end", "--duration": "--t-end", "--reltol": "--rtol",
    "--abstol": "--atol", "--maxstep": "--max-step", "--solver": "--method",
    "--grid": "--vary",  # falsify searches ranges: it has no grid
}  # fmt: skip
"""Flags of other tools (MATLAB's odeset names, C habits) and ours."""

_CHOICE_HABITS = {"numba": "compiled", "jit": "compiled", "solve_ivp": "scipy"}
"""Values people give for a choice, and ours (``--backend numba`` is ``compiled``)."""


def _flag_hint(word: str, flags: Sequence[str]) -> str:
    """``"; did you mean '--out'?"`` for an unknown flag, or ``""``.

    >>> _flag_hint("--t_end=5", ["--t-end", "--out"]), _flag_hint("-o", ["--out"])
    ("; did you mean '--t-end'?", "; did you mean '--out'?")
    """
    name = word.split("=", 1)[0]
    spelled = name.replace("_", "-").lower()  # `--t_end`, `--RTOL` (no other tool's spelling
    # in _FLAG_HABITS turns into one of our flags so: the order of the two does not matter)
    if spelled in flags:
        return f"; did you mean '{spelled}'?"
    from hybrid.errors import did_you_mean

    return did_you_mean(name, [f for f in flags if f.startswith("--")], aliases=_FLAG_HABITS)


def _param(text: str) -> tuple[str, float]:
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"expected name=value, got '{text}'")
    key, value = text.split("=", 1)
    try:
        number = float(value)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"value of '{key}' must be a number, got '{value}'"
        ) from None
    if not math.isfinite(number):
        raise argparse.ArgumentTypeError(f"value of '{key}' must be a finite number, got '{value}'")
    return key.strip(), number


def _positive(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got '{text}'") from None
    if math.isnan(value) or not value > 0:
        raise argparse.ArgumentTypeError(f"must be > 0, got {text}")
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {text}")
    return value


def _assignment(text: str) -> tuple[str, str]:
    name, sep, expression = text.partition("=")
    if not sep or not name.strip().isidentifier() or not expression.strip():
        raise argparse.ArgumentTypeError(f"expected NAME=EXPR (an expression of t), got '{text}'")
    return name.strip(), expression.strip()


def _count(text: str, least: int = 0) -> int:
    """A whole number ``>= least`` given on the command line."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got '{text}'") from None
    if value < least:
        raise argparse.ArgumentTypeError(f"must be >= {least}, got {text}")
    return value


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``hybrid`` command (the CLI reference is generated from it)."""
    from hybrid.analysis.formats import FORMATS as REPORT_FORMATS
    from hybrid.cli.settings import add_settings_flags
    from hybrid.export.diagrams import DIAGRAM_FORMATS
    from hybrid.export.pictures import RENDERED_FORMATS
    from hybrid.simulation.settings import CHOICES

    parser = _Parser(
        prog="hybrid",
        description="Hybrid automata in YAML: validate, check and simulate specs, sweep "
        "and falsify them, draw their graphs, exchange them with other tools.",
        epilog="Every command is listed above; 'hybrid COMMAND --help' gives its options.",
    )
    parser.add_argument("--version", action="version", version=f"hybrid {__version__}")
    sub = parser.add_subparsers(
        dest="command", required=True, parser_class=_Parser, title="commands", metavar="COMMAND"
    )

    p = sub.add_parser("validate", help="parse and check the spec language only")
    p.add_argument("files", nargs="+", metavar="FILE", help="spec or system files")

    p = sub.add_parser("check", help="graph and property checks")
    p.add_argument("files", nargs="+", metavar="FILE", help="spec or system files")
    p.add_argument("--format", choices=tuple(REPORT_FORMATS), default="text", help="report format")
    p.add_argument("--strict", action="store_true", help="warnings fail too (exit 1)")
    p.add_argument(
        "--ignore",
        action="append",
        default=[],
        metavar="RULE",
        help="do not report this rule (repeatable)",
    )
    p.add_argument(
        "--quiet", action="store_true", help="no progress on stderr (shown only on a terminal)"
    )
    p.add_argument(
        "--reach-t-end",
        type=_positive,
        default=None,
        metavar="T",
        help="decide unproved forbidden entries of affine models with reach over [0, T]",
    )
    p.add_argument(
        "--reach-max-jumps", type=_count, default=None, metavar="J", help="jump bound of reach"
    )

    p = sub.add_parser("simulate", help="simulate a spec")
    p.add_argument("file", metavar="FILE", help="spec or system file")
    add_settings_flags(p, _positive, _count)
    p.add_argument(
        "--backend",
        default=None,
        choices=CHOICES,
        help="scipy (reference, the default), compiled (numba, the 'fast' extra) or auto "
        "(compiled when the model is loaded already, else scipy; docs/backends.md)",
    )
    for flag, meaning in (
        ("--param", "override a parameter (comp.NAME in a system)"),
        ("--init", "start a state variable at VALUE (named as in the --out columns)"),
    ):
        p.add_argument(
            flag, type=_param, action="append", default=[], metavar="NAME=VALUE", help=meaning
        )
    p.add_argument(
        "--initial-location",
        metavar="LOC",
        help="start in location LOC (an automaton; a system's are set per component)",
    )
    p.add_argument(
        "--input",
        type=_assignment,
        action="append",
        default=[],
        metavar="NAME=EXPR",
        help="drive a free input with an expression of t, e.g. u='sin(2*t)'",
    )
    p.add_argument(
        "--input-csv",
        action="append",
        default=[],
        metavar="FILE",
        help="drive free inputs with time series: a CSV with columns t,NAME,...",
    )
    p.add_argument("--out", help="trajectory file (.csv, .npz or .mat)")
    p.add_argument("--events", help="events JSON file")
    p.add_argument("--plot", help="figure file (needs the 'plot' extra)")
    p.add_argument(
        "--quiet", action="store_true",
        help="no progress (shown only on a terminal) and no note of the backend auto chose",
    )  # fmt: skip

    p = sub.add_parser("graph", help="print the location graph")
    p.add_argument("file", metavar="FILE", help="spec or system file")
    p.add_argument(
        "--format",
        choices=(*DIAGRAM_FORMATS, *RENDERED_FORMATS),
        default=None,
        help="dot and mermaid are text; svg and png are drawn by Graphviz (the 'graph' extra);"
        " default: the one --out's name says (.dot .gv .mmd .svg .png), else dot",
    )
    p.add_argument("--out", metavar="FILE", help="write to FILE instead of stdout")

    p = sub.add_parser("schema", help="print the JSON Schema of spec files")
    p.add_argument("--out", metavar="FILE", help="write it to FILE (for the modeline of specs)")

    from hybrid.cli.interchange import add_interchange_commands

    add_interchange_commands(sub)
    from hybrid.cli.campaigns import add_campaign_commands

    types: dict[str, Callable[[str], Any]] = {
        "positive": _positive, "count": _count, "param": _param, "assignment": _assignment,
        "some": functools.partial(_count, least=1),
    }  # fmt: skip
    add_campaign_commands(sub, types)
    from hybrid.cli.reach import add_reach_command

    add_reach_command(sub, types)
    from hybrid.cli.compile import add_compile_command

    add_compile_command(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; returns the exit code.

    Ctrl-C at any moment, from the first import to the last byte written, ends
    in one line and exit 130 (commands that keep what they computed, such as
    ``simulate``, ``sweep`` and ``falsify``, say so themselves first).
    """
    said = "interrupted"
    try:
        return _main(argv)
    except KeyboardInterrupt as exc:
        said = str(exc) or said  # what was stopped, when the code that stopped it knows
    except Exception as exc:
        if not caused_by_interrupt(exc):
            raise
    _STOPPED[0] = True
    with _no_further_interrupts():
        print(f"hybrid: {said}", file=sys.stderr)
    return EXIT_ABANDONED


_STOPPED = [False]
"""Whether main stopped on a Ctrl-C (set without importing anything)."""


def entry() -> int:
    """The ``hybrid`` command: :func:`main`, then exit (called by :func:`hybrid.__main__.entry`,
    the console script and ``python -m hybrid``, once it has imported this module).

    Once :func:`main` has returned, the command's work is done and said: a Ctrl-C
    while the interpreter shuts down would only turn its exit code into death by
    SIGINT, so it is ignored from then on.
    """
    sys.unraisablehook = _quiet_after_interrupt
    code = main()
    import signal
    import threading

    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    return code


def _quiet_after_interrupt(unraisable: Any) -> None:
    """Python's report of an error in a finalizer, unless a Ctrl-C stopped work half-way;
    a Ctrl-C that landed in a finalizer or a callback is delivered again.

    A compile stopped by Ctrl-C leaves LLVM handles half-made; their finalizers fail
    as the process ends ("Exception ignored in ..."), which says nothing to the user.
    A Ctrl-C whose ``KeyboardInterrupt`` is raised inside such code (an import's
    module lock is released by a callback) is reported there and dropped by Python:
    the command would print a traceback and go on. It is delivered again
    (:func:`_deliver_again`), to the command's handler or, under Python's default
    one, as a ``KeyboardInterrupt`` in the command's own code.
    """
    if issubclass(unraisable.exc_type, KeyboardInterrupt):
        if not _STOPPED[0]:
            _deliver_again()
        return
    interrupts = sys.modules.get("hybrid.simulation.interrupts")  # loaded if Ctrl-C was handled
    seen = interrupts is not None and interrupts.interrupted()
    if not (_STOPPED[0] or seen):
        sys.__unraisablehook__(unraisable)


REDELIVERY_DELAY = 0.01
"""Seconds after which a Ctrl-C dropped under Python's default handler is raised again."""


def _deliver_again() -> None:
    """SIGINT again, for a Ctrl-C Python reported as unraisable and dropped.

    A handler of the command's own (one that counts presses) receives it at once.
    Python's default handler would raise ``KeyboardInterrupt`` here, inside the
    hook, where Python reports it as "Exception ignored in sys.unraisablehook" with
    a traceback and drops it again; so the ``KeyboardInterrupt`` is caught and the
    signal sent once more by a thread of its own a moment later
    (:data:`REDELIVERY_DELAY`), when the hook has returned and the command's code
    runs. Once the command is done, SIGINT is ignored (:func:`entry`), and neither
    does anything.
    """
    import signal
    import threading

    try:
        signal.raise_signal(signal.SIGINT)
    except KeyboardInterrupt:
        later = threading.Thread(target=_interrupt_main_later, name="hybrid-sigint-again",
                                 daemon=True)  # fmt: skip
        with contextlib.suppress(RuntimeError):  # no new thread as the interpreter ends
            later.start()


def _interrupt_main_later() -> None:
    import _thread
    import time

    time.sleep(REDELIVERY_DELAY)
    _thread.interrupt_main()  # nothing if SIGINT is ignored by then


@contextlib.contextmanager
def _no_further_interrupts() -> Iterator[None]:
    """A second Ctrl-C while the exit message is printed is ignored (no traceback)."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _show_note(message: Warning | str, category: type[Warning], *rest: Any, **kw: Any) -> None:
    """Every warning as one line: hybrid's notes and warnings by their message, another
    library's with its category (Python's form shows a line of the interpreter's code)."""
    if issubclass(category, Note):
        print(f"hybrid: note: {message}", file=sys.stderr)
    elif category.__module__.split(".")[0] == "hybrid":
        print(f"hybrid: warning: {message}", file=sys.stderr)
    else:
        print(f"hybrid: warning: {category.__name__}: {message}", file=sys.stderr)


def _main(argv: Sequence[str] | None) -> int:
    args = build_parser().parse_args(argv)
    with warnings.catch_warnings():
        warnings.showwarning = _show_note
        return _run(args)


def _run(args: argparse.Namespace) -> int:
    try:
        if args.command == "validate":
            return _validate(args.files)
        if args.command == "schema":
            from hybrid.cli.schema import run_schema

            return run_schema(args.out)
        if args.command == "check":
            from hybrid.cli.check import run_check

            return run_check(
                args.files,
                fmt=args.format,
                strict=args.strict,
                ignore=args.ignore,
                quiet=args.quiet,
                reach_t_end=args.reach_t_end,
                reach_max_jumps=args.reach_max_jumps,
            )
        if args.command == "graph":
            from hybrid.cli.check import run_graph

            return run_graph(args.file, fmt=args.format, path=args.out)
        if args.command == "simulate":
            from hybrid.cli.simulate import run_simulate

            return run_simulate(args)
        if args.command in ("sweep", "falsify"):
            from hybrid.cli.campaigns import run_falsify, run_sweep

            return run_sweep(args) if args.command == "sweep" else run_falsify(args)
        if args.command == "reach":
            from hybrid.cli.reach import run_reach

            return run_reach(args)
        if args.command == "compile":
            from hybrid.cli.compile import run_compile

            return run_compile(args.files)
        if args.command in ("import", "export"):
            from hybrid.cli.interchange import run_export, run_import

            return run_import(args) if args.command == "import" else run_export(args)
    except (SpecError, UsageError, SimulationError) as exc:
        print(error_line(exc, getattr(args, "file", "hybrid")), file=sys.stderr)
        return EXIT_INVALID
    except MemoryError as exc:  # the machine's fault: one line, as for a full disk
        detail = f": {exc}" if str(exc) else ""
        hint = " (fewer points: a larger --dt or a shorter --t-end)" if args.command in (
            "simulate", "sweep", "falsify") else ""  # fmt: skip
        print(f"{getattr(args, 'file', 'hybrid')}: out of memory{detail}; nothing more was "
              f"written{hint}", file=sys.stderr)  # fmt: skip
        return EXIT_INVALID
    except BrokenPipeError as exc:
        if _reader_gone(sys.stdout):  # `hybrid ... | head`: the reader has all it wanted
            return EXIT_OK
        print(f"hybrid: a connection broke (a worker process died?): {exc}", file=sys.stderr)
        return EXIT_FINDINGS
    except OSError as exc:  # an output that failed where it could not be known before
        from hybrid.export.outputs import reason

        where = f" '{exc.filename}'" if exc.filename else ""
        print(f"hybrid: cannot write{where}: {reason(exc)}", file=sys.stderr)
        return EXIT_INVALID
    return EXIT_INVALID


def _reader_gone(stream: TextIO) -> bool:
    """Whether writing to ``stream`` fails because its reader has closed it.

    Its buffer may be empty by now (the write that failed dropped it): then the
    pipe itself says so, an error condition on its writing end.
    """
    try:
        stream.flush()
        fd = stream.fileno()
    except BrokenPipeError:
        return True
    except (OSError, ValueError):
        return False
    if not hasattr(select, "poll"):  # Windows: no pipe to ask
        return False
    poller = select.poll()
    poller.register(fd, select.POLLOUT)
    return any(event & select.POLLERR for _, event in poller.poll(0))


def _validate(files: Sequence[str]) -> int:
    from hybrid.reader.loader import load

    status = EXIT_OK
    for file in files:
        try:
            load(file)
        except SpecError as exc:
            print(str(exc), file=sys.stderr)
            status = EXIT_INVALID
        else:
            print(f"{file}: ok")
    return status


if __name__ == "__main__":
    raise SystemExit(main())
