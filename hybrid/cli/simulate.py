"""``hybrid simulate``: run a spec, write what was computed, exit 0 only at t-end.

Ctrl-C is handled for the whole command (:mod:`hybrid.simulation.interrupts`):
while the run goes on, Ctrl-C ends it cleanly at the step in progress (cause
``interrupted``) and the outputs are written as for any other end; while the
outputs are written, a Ctrl-C after an interrupted run, or a second one, abandons
them (exit 130; the files already complete are kept, the one being written is
not created). Progress goes to stderr when it is a terminal, unless ``--quiet``.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from collections.abc import Callable
from pathlib import Path

from hybrid.cli.compile import compile_notes
from hybrid.cli.exits import EXIT_ABANDONED, EXIT_FINDINGS, EXIT_OK
from hybrid.cli.settings import given_once, settings_from
from hybrid.compose import System, as_system
from hybrid.errors import UsageError, did_you_mean
from hybrid.model import Automaton
from hybrid.progress import TerminalLine, terminal_reporter
from hybrid.simulation.bounds import BoundsWarning
from hybrid.simulation.engine import simulate
from hybrid.simulation.interrupts import ABANDON_HINT, Interrupts
from hybrid.simulation.result import RequirementResult, Run

__all__ = ["run_simulate", "violation_text"]

OUTPUT_FLAGS = ("out", "events", "plot")


def run_simulate(args: argparse.Namespace) -> int:
    """The ``simulate`` command; returns the exit code (0, 1, 2 or 130)."""
    from hybrid.export.outputs import writable_file
    from hybrid.reader.loader import load

    outputs = [(flag, getattr(args, flag)) for flag in OUTPUT_FLAGS]
    for flag, path in outputs:
        if path is not None:
            writable_file(path, f"--{flag}")
    from hybrid.export.trajectory import TRAJECTORY_SUFFIXES

    if args.out is not None and Path(args.out).suffix.lower() not in TRAJECTORY_SUFFIXES:
        raise UsageError(f"--out: use a .csv, .npz or .mat file name, got '{args.out}'")
    _refuse_other_formats(args)
    parameters = given_once(args.param, "--param")
    initial = given_once(args.init, "--init")
    warnings.simplefilter("ignore", BoundsWarning)  # the command says them, below
    line = terminal_reporter(args.quiet)
    interrupts = Interrupts(notify=_notifier(line))
    with interrupts.installed():
        model = load(args.file)
        if args.initial_location is not None and isinstance(model, System):
            raise UsageError(
                "--initial-location applies to an automaton; in a system each component's "
                "initial location is set in the system file (initial: {location: ...})"
            )
        if parameters:
            model = model.with_parameters(parameters)
        inputs = _inputs(args, model)
        backend = args.backend
        if backend == "auto":  # one run: compiled only if nothing is to be compiled first
            from hybrid.simulation.native.choice import choose

            chosen = choose(model, 1, method=args.method, inputs=bool(inputs))
            if not args.quiet:
                print(f"{args.file}: note: backend auto: {chosen.backend} ({chosen.reason})",
                      file=sys.stderr)  # fmt: skip
            backend = chosen.backend
        with compile_notes(args.file, line):  # a first compiled run: what, and how long
            run = simulate(
                model,
                settings=settings_from(args),
                dense=args.plot is not None,
                inputs=inputs or None,
                initial=initial or None,
                initial_location=args.initial_location,
                progress=line,
                backend=backend,
            )
        for note in run.settings.get("start", {}).get("notes", ()):
            print(f"{args.file}: note: {note}", file=sys.stderr)
        for excursion in run.out_of_bounds:
            print(f"{args.file}: warning: {excursion.message}", file=sys.stderr)
        term = run.termination
        pending = [path for _, path in outputs if path is not None]
        if term.cause == "interrupted" and pending:
            print(
                f"{args.file}: interrupted at t={term.t:.9g}; writing the outputs ({ABANDON_HINT})",
                file=sys.stderr,
                flush=True,
            )
        written: list[str] = []
        try:
            with interrupts.writing():
                _write_outputs(run, args, written, line)
        except KeyboardInterrupt:
            if line is not None:
                line.clear()
            left = [p for p in pending if p not in written]
            kept = f"; complete: {', '.join(written)}" if written else ""
            print(
                f"hybrid: interrupted again while writing: abandoned {', '.join(left)}{kept}",
                file=sys.stderr,
            )
            return EXIT_ABANDONED
    summary = (
        f"{args.file}: {term.cause} at t={term.t:.9g} j={term.j}"
        f" ({len(run.jumps)} jumps, {len(run)} points)"
    )
    violated = [r for r in run.requirements.values() if not r.holds]
    if term.cause == "t_end" and not violated:
        print(summary)
        return EXIT_OK
    print(summary, file=sys.stderr)
    if term.cause != "t_end":
        print(
            f"{args.file}: t={term.t:.9g} j={term.j}: {term.cause}: {term.message}",
            file=sys.stderr,
        )
    for r in violated:
        print(f"{args.file}: {violation_text(r)}", file=sys.stderr)
    return EXIT_FINDINGS


FIGURE_SUFFIXES = (".png", ".pdf", ".svg", ".jpg", ".jpeg", ".eps", ".ps", ".tif", ".tiff")


def _refuse_other_formats(args: argparse.Namespace) -> None:
    """Refuse, before the run, an events file named as another format and a figure
    format matplotlib cannot write.

    ``--events traj.csv`` used to write JSON into ``traj.csv`` (exit 0), and
    ``--plot fig.csv`` ran the whole simulation before it was refused.
    """
    from hybrid.export.trajectory import TRAJECTORY_SUFFIXES

    if args.events is not None:
        events = Path(args.events)
        if events.suffix.lower() in (*TRAJECTORY_SUFFIXES, *FIGURE_SUFFIXES):
            raise UsageError(
                f"--events writes JSON, not {events.suffix}: name it "
                f"'{events.with_suffix('.json')}' (the trajectory goes to --out, figures to --plot)"
            )
    if args.plot is not None:
        from hybrid.export.plot import figure_format

        figure_format(args.plot, "--plot")


def violation_text(result: RequirementResult) -> str:
    """One line on a requirement a run violates: where, by how much, or why it is unknown."""
    if result.message:
        return f"requirement '{result.name}' {result.message}"
    at = "" if result.violated_at is None else f" at t={result.violated_at:.9g}"
    return f"requirement '{result.name}' violated{at} (robustness {result.robustness:.6g})"


def _notifier(line: TerminalLine | None) -> Callable[[str], None]:
    def notify(text: str) -> None:
        if line is not None:
            line.message(f"hybrid: {text}")
        else:
            print(f"hybrid: {text}", file=sys.stderr, flush=True)

    return notify


def _inputs(
    args: argparse.Namespace, model: Automaton | System
) -> dict[str, Callable[[float], float]]:
    """The free inputs of ``model`` from ``--input NAME=EXPR`` and ``--input-csv FILE``."""
    from hybrid.simulation.inputs import ExpressionInput, read_series

    system = as_system(model)
    declared = list(system.free_inputs)
    ranged = system.input_ranges()
    given: dict[str, Callable[[float], float]] = {}
    origin: dict[str, str] = {}

    def add(name: str, fn: Callable[[float], float], where: str) -> None:
        if name not in declared:
            names = ", ".join(declared) or "none"
            raise UsageError(
                f"{where}: '{name}' is not a free input of {model.name} (inputs: {names})"
                f"{did_you_mean(name, declared)}"
            )
        if name in given:
            raise UsageError(f"input '{name}' is given twice ({origin[name]} and {where})")
        given[name] = fn
        origin[name] = where

    for name, source in args.input:
        add(name, ExpressionInput(name, source), f"--input {name}")
    for file in args.input_csv:
        for name, series in read_series(file).items():
            add(name, series, file)  # that it spans the run: simulate checks, as from Python
    missing = [name for name in declared if name not in given and name not in ranged]
    if missing:
        raise UsageError(
            f"input '{missing[0]}' needs a value: give --input {missing[0]}=EXPR (an expression "
            f"of t) or --input-csv FILE (columns t,{missing[0]})",
            at=system.input_position(missing[0]),
        )
    return given


def _write_outputs(
    run: Run, args: argparse.Namespace, written: list[str], line: TerminalLine | None
) -> None:
    """Write each output asked for; one that fails at the end is kept elsewhere and named.

    The paths were found writable before the run; a write can still fail (a disk
    that filled during the run): the others are written all the same, the failed
    one is written into a fresh temporary folder, and the error names it.
    """
    from hybrid.export.outputs import keep_elsewhere
    from hybrid.export.trajectory import write_events, write_trajectory

    writers: list[tuple[str, str, Callable[[Path], object]]] = []
    if args.out is not None:
        writers.append(("out", args.out, lambda p: write_trajectory(run, p, progress=line)))
    if args.events is not None:
        writers.append(("events", args.events, lambda p: write_events(run, p, progress=line)))
    if args.plot is not None:
        from hybrid.export.plot import plot_run

        writers.append(("plot", args.plot, lambda p: plot_run(run, p)))
    failed: list[UsageError] = []
    for flag, path, write in writers:
        try:
            write(Path(path))
        except OSError as exc:
            failed.append(keep_elsewhere(path, write, exc, f"--{flag}"))
        else:
            written.append(path)
    if failed:
        raise UsageError("; ".join(str(e) for e in failed))
