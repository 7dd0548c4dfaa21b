"""``hybrid simulate``: run a spec, write what was computed, exit 0 only at t-end."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from hybrid.cli.exits import EXIT_FINDINGS, EXIT_OK
from hybrid.errors import UsageError
from hybrid.simulation.engine import simulate
from hybrid.simulation.result import Run

__all__ = ["run_simulate"]


def run_simulate(args: argparse.Namespace) -> int:
    """The ``simulate`` command; returns the exit code (0, 1 or 2)."""
    from hybrid.reader.loader import load

    outputs = [(flag, getattr(args, flag)) for flag in ("out", "events", "plot")]
    for flag, path in outputs:
        if path is not None and not Path(path).resolve().parent.is_dir():
            raise UsageError(f"--{flag}: directory of '{path}' does not exist")
    if args.out is not None and Path(args.out).suffix.lower() not in (".csv", ".npz"):
        raise UsageError(f"--out: use a .csv or .npz file name, got '{args.out}'")
    model = load(args.file)
    parameters = dict(args.param)
    if parameters:
        model = model.with_parameters(parameters)
    run = simulate(
        model,
        t_end=args.t_end,
        max_jumps=args.max_jumps,
        rtol=args.rtol,
        atol=args.atol,
        max_step=args.max_step,
        method=args.method,
        dt=args.dt,
        dense=args.plot is not None,
        backend=args.backend,
    )
    _write_outputs(run, args)
    term = run.termination
    summary = (
        f"{args.file}: {term.cause} at t={term.t:.9g} j={term.j}"
        f" ({len(run.jumps)} jumps, {len(run)} points)"
    )
    if term.cause == "t_end":
        print(summary)
        return EXIT_OK
    print(summary, file=sys.stderr)
    print(f"{args.file}: t={term.t:.9g} j={term.j}: {term.cause}: {term.message}", file=sys.stderr)
    return EXIT_FINDINGS


def _write_outputs(run: Run, args: argparse.Namespace) -> None:
    from hybrid.export.trajectory import write_csv, write_events, write_npz

    if args.out is not None:
        if Path(args.out).suffix.lower() == ".npz":
            write_npz(run, args.out)
        else:
            write_csv(run, args.out)
    if args.events is not None:
        write_events(run, args.events)
    if args.plot is not None:
        from hybrid.export.plot import plot_run

        plot_run(run, args.plot)
