"""``hybrid sweep`` and ``hybrid falsify``: campaigns of many runs from the command line.

``sweep`` writes the table (``--out results.csv|results.parquet``) and prints a
summary, or with ``--format github|junit|sarif|json|text`` the findings of
:mod:`hybrid.campaigns.findings` (as ``hybrid check`` prints its own). Exit 0
when every run ran and no requirement was violated, 1 when a run raised or
timed out or a requirement was violated (or Ctrl-C stopped the campaign: the
rows finished are kept for ``--resume``), 2 for an invalid spec or usage.

``falsify`` searches the varied ranges for a violation of one requirement and
writes ``falsification.json`` (the values, robustness, every evaluation), and
the trajectory (``trajectory.csv``) and events (``events.json``) of the
counterexample, or of the lowest-robustness run when none was found, into
``--out DIR``. Exit 1 when it finds a violation, 0 when none within the budget.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from hybrid.cli.compile import compile_notes
from hybrid.cli.exits import EXIT_FINDINGS, EXIT_OK
from hybrid.cli.settings import given_once, settings_from
from hybrid.errors import UsageError
from hybrid.progress import TerminalLine, terminal_reporter
from hybrid.simulation.interrupts import Interrupts

__all__ = ["add_campaign_commands", "run_falsify", "run_sweep"]

REPORT_FORMATS = ("summary", "text", "json", "github", "junit", "sarif")


def add_campaign_commands(
    sub: argparse._SubParsersAction,  # type: ignore[type-arg]
    types: Mapping[str, Callable[[str], Any]],
) -> None:
    """Add ``sweep`` and ``falsify``; ``types`` are the parser's argument types by name."""
    from hybrid.campaigns.samplers import SAMPLERS

    p = sub.add_parser("sweep", help="run a spec over a grid or samples of parameters")
    p.add_argument("file", metavar="FILE", help="spec or system file")
    p.add_argument("--grid", action="append", default=[], metavar="NAME=LO:HI:N",
                   help="N values from LO to HI (a parameter, init.x or input.u; NAME=N: across "
                        "the declared set of init.x or input.u; NAME=V1,V2,...: those "
                        "values); repeatable")  # fmt: skip
    p.add_argument("--vary", action="append", default=[], metavar="NAME=LO:HI",
                   help="a range to draw --sample points from (a bare init.x or input.u: its "
                        "declared range; none: every declared range); repeatable")  # fmt: skip
    p.add_argument("--sample", type=types["some"], default=None, metavar="N",
                   help="N seeded samples of the --vary ranges (N >= 1)")  # fmt: skip
    p.add_argument("--seed", type=int, default=0, help="seed of the samples, a whole number >= 0 (default 0)")
    p.add_argument("--sampler", choices=SAMPLERS, default="lhs", help="how samples are drawn")
    p.add_argument("--summary", action="append", default=[], metavar="KIND:NAME",
                   help="a column per run: max:x, min:x, last:x, mean:x, jumps:EDGE, jump_t:K")  # fmt: skip
    _common(p, types)
    from hybrid.simulation.settings import CHOICES  # auto: hybrid.campaigns.choosing

    p.add_argument("--backend", default="auto", choices=CHOICES,
                   help="scipy (reference), compiled (numba: one ensemble call per batch) or "
                   "auto (the default: compiled when cached or when it pays; docs/backends.md)")  # fmt: skip
    p.add_argument("--out", required=True, help="results file (.csv or .parquet)")
    p.add_argument("--resume", action="store_true", help="finish an interrupted campaign")
    p.add_argument("--format", choices=REPORT_FORMATS, default="summary",
                   help="print a summary (default) or findings as hybrid check does")  # fmt: skip

    p = sub.add_parser("falsify", help="search parameter ranges for a requirement's violation")
    p.add_argument("file", metavar="FILE", help="spec or system file")
    p.add_argument("--requirement", required=True, metavar="NAME", help="the requirement")
    p.add_argument("--vary", action="append", default=[], metavar="NAME=LO:HI",
                   help="a range to search (a parameter, init.x or input.u; a bare init.x or "
                        "input.u: its declared range; none: every declared range); repeatable")  # fmt: skip
    p.add_argument("--budget", type=types["count"], default=100, help="simulations at most")
    p.add_argument("--seed", type=int, default=0, help="seed of the global phase, a whole number >= 0 (default 0)")
    p.add_argument("--sampler", choices=SAMPLERS, default="lhs", help="the global design")
    _common(p, types)
    p.add_argument("--backend", default="auto", choices=CHOICES,
                   help="scipy (reference), compiled (numba; requirements are monitored over "
                   "its steps) or auto (the default: compiled when cached or when it pays; "
                   "docs/backends.md)")  # fmt: skip
    p.add_argument("--out", metavar="DIR", help="write the counterexample here")


def _common(p: argparse.ArgumentParser, types: Mapping[str, Callable[[str], Any]]) -> None:
    from hybrid.cli.settings import add_settings_flags

    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=types["count"], default=None,
                       help="local worker processes (default: every core; 0: in this process)")  # fmt: skip
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help="run on a Dask cluster: the scheduler's address (tcp://host:8786)")  # fmt: skip
    p.add_argument("--run-timeout", type=types["positive"], default=None, metavar="SECONDS",
                   help="a run longer than this is a row with cause timeout")  # fmt: skip
    p.add_argument("--param", type=types["param"], action="append", default=[],
                   metavar="NAME=VALUE", help="hold a parameter at a value")  # fmt: skip
    p.add_argument("--input", type=types["assignment"], action="append", default=[],
                   metavar="NAME=EXPR", help="drive a free input with an expression of t")  # fmt: skip
    add_settings_flags(p, types["positive"], types["count"], each_run=True)
    p.add_argument("--quiet", action="store_true",
                   help="no progress and no note of the backend auto chose on stderr")  # fmt: skip


def _quiet_backend_note(quiet: bool) -> None:
    """With ``--quiet``, no ``note: backend auto: ...`` line (the command's warnings stay)."""
    if quiet:
        import warnings

        from hybrid.campaigns.choosing import BackendNote

        warnings.simplefilter("ignore", BackendNote)  # within the command's catch_warnings


def _notifier(line: TerminalLine | None) -> Callable[[str], None]:
    def notify(text: str) -> None:
        if line is not None:
            line.message(f"hybrid: {text}")
        else:
            print(f"hybrid: {text}", file=sys.stderr, flush=True)

    return notify


def run_sweep(args: argparse.Namespace) -> int:
    """The ``sweep`` command; returns the exit code."""
    from hybrid.analysis.formats import write
    from hybrid.campaigns.findings import sweep_findings, values_text
    from hybrid.campaigns.resumable import parts_dir
    from hybrid.campaigns.space import parse_grid, parse_range
    from hybrid.campaigns.sweep import sweep
    from hybrid.reader.loader import load

    if args.sample is None and args.vary:
        raise UsageError("--vary gives ranges to sample: add --sample N")
    grid = [parse_grid(text) for text in args.grid]
    vary = [parse_range(text) for text in args.vary]
    held, inputs = given_once(args.param, "--param"), given_once(args.input, "--input")
    from hybrid.export.outputs import writable_file

    writable_file(args.out, "--out")
    line = terminal_reporter(args.quiet)
    _quiet_backend_note(args.quiet)
    interrupts = Interrupts(notify=_notifier(line))
    with interrupts.installed():
        model = load(args.file)
        with compile_notes(args.file, line):
            table = sweep(
                model,
                settings=settings_from(args),
                grid=grid,
                vary=vary or None,
                samples=args.sample,
                seed=args.seed,
                sampler=args.sampler,
                parameters=held or None,
                inputs=inputs or None,
                summaries=args.summary,
                workers=args.workers,
                scheduler=args.scheduler,
                run_timeout=args.run_timeout,
                out=args.out,
                resume=args.resume,
                progress=line if line is not None else False,
                backend=args.backend,
            )
    if line is not None:
        line.clear()
    if table.resumed:
        print(
            f"{args.file}: resumed: {table.resumed} of {table.total} runs were done; "
            f"ran {len(table) - table.resumed}",
            file=sys.stderr,
        )
    if not table.complete:
        done = len(table) - table.lost
        why = (
            f"{table.lost} runs were lost to the executor (a worker died under them, twice)"
            if table.lost
            else "interrupted"
        )
        print(
            f"{args.file}: {why}: {done} of {table.total} runs done, kept in "
            f"{parts_dir(Path(args.out))}/; the same command with --resume runs only the rest",
            file=sys.stderr,
        )
        return EXIT_FINDINGS
    reports = sweep_findings(model, table)
    failed = table.failed()
    violated = any(f.rule == "requirement-violated" for r in reports for f in r.findings)
    if args.format == "summary":
        causes: dict[str, int] = {}
        for row in table.rows:
            causes[str(row["cause"])] = causes.get(str(row["cause"]), 0) + 1
        shown = ", ".join(f"{n} {c}" for c, n in sorted(causes.items()))
        print(f"{args.file}: {len(table)} runs ({shown}); results in {args.out}")
        for report in reports:
            for f in report.findings:
                print(f"  {f.text()}")
        for row in failed[:5]:
            print(
                f"  run {row['run']} ({values_text(row, table.varied)}): {row['cause']}: "
                f"{row.get('message') or ''}",
                file=sys.stderr,
            )
    else:
        print(write(args.format, reports))
    return EXIT_FINDINGS if failed or violated else EXIT_OK


def run_falsify(args: argparse.Namespace) -> int:
    """The ``falsify`` command; returns the exit code."""
    from hybrid.campaigns.space import parse_range
    from hybrid.export.outputs import writable_directory

    vary = [parse_range(text) for text in args.vary]
    held, inputs = given_once(args.param, "--param"), given_once(args.input, "--input")
    # refused before the imports below (scipy.optimize among them: a second or two)
    out = writable_directory(args.out, "--out") if args.out else None
    from hybrid.campaigns.falsify import falsify
    from hybrid.campaigns.findings import values_text
    from hybrid.reader.loader import load

    line = terminal_reporter(args.quiet)
    _quiet_backend_note(args.quiet)
    interrupts = Interrupts(notify=_notifier(line))
    with interrupts.installed():
        model = load(args.file)
        with compile_notes(args.file, line):
            result = falsify(
                model,
                args.requirement,
                vary or None,
                settings=settings_from(args),
                budget=args.budget,
                seed=args.seed,
                sampler=args.sampler,
                parameters=held or None,
                inputs=inputs or None,
                workers=args.workers,
                scheduler=args.scheduler,
                run_timeout=args.run_timeout,
                progress=line if line is not None else False,
                backend=args.backend,
            )
    if line is not None:
        line.clear()
    if out is not None:
        _write_result(result, out)
    shown = values_text(result.values, list(result.values))
    where = f" into {out}" if out is not None else ""
    if result.found:
        at = result.violated_at
        when = "" if at is None else f", violated at t={at:.9g}"
        print(
            f"{args.file}: requirement '{args.requirement}' violated at {shown} (robustness "
            f"{result.robustness:.6g}{when}) after {result.evaluations} runs; written{where}"
        )
        return EXIT_FINDINGS
    stopped = "" if result.complete else " (interrupted)"
    failed = result.failed
    unjudged = (
        f"; {len(failed)} of them failed and were not judged (the first: {failed[0]['failed']})"
        if failed
        else ""
    )
    print(
        f"{args.file}: no violation of '{args.requirement}' in {result.evaluations} runs"
        f"{stopped}; lowest robustness {result.robustness:.6g} at {shown}{unjudged}"
    )
    return EXIT_OK if result.complete and not failed else EXIT_FINDINGS


def _write_result(result: Any, out: Path) -> None:
    from hybrid.export.outputs import make_directory
    from hybrid.export.trajectory import write_csv, write_events
    from hybrid.files import atomic_write

    make_directory(out, "--out")
    document = _finite(result.as_dict())
    with atomic_write(out / "falsification.json") as handle:
        handle.write((json.dumps(document, indent=2) + "\n").encode("utf-8"))
    if result.run is not None:
        write_csv(result.run, out / "trajectory.csv")
        write_events(result.run, out / "events.json")
        return
    for stale in ("trajectory.csv", "events.json"):  # an earlier search's run: not this one's
        path = out / stale
        if path.is_file() and not path.is_symlink():
            path.unlink()


def _finite(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_finite(v) for v in value]
    return value
