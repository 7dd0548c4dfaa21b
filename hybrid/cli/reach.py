"""The ``hybrid reach`` command: flowpipes of an affine model and a verdict per forbidden entry.

Exit codes (CONTRACT.md, "Reachability"): 0 every entry proved, 1 one
refuted, 3 none refuted and one unknown, 2 invalid input or a model reach
cannot handle. The report uses the formats of ``hybrid check``: a proved entry
is a ``property-proved`` note, a refuted one ``property-violated`` (error) and
an unknown one ``property-unproved`` (warning). Outputs that cannot be written
are refused before the work starts.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

from hybrid.analysis.findings import Finding, Report
from hybrid.analysis.formats import FORMATS, write
from hybrid.cli.exits import EXIT_FINDINGS, EXIT_OK
from hybrid.errors import UsageError
from hybrid.progress import terminal_reporter

if TYPE_CHECKING:  # the reach modules (scipy) load only when the command runs
    from hybrid.reach.result import PropertyResult, ReachResult

__all__ = ["EXIT_UNKNOWN", "add_reach_command", "findings_of", "run_reach"]

EXIT_UNKNOWN = 3
"""No entry refuted, one unknown."""


def add_reach_command(sub: Any, types: Mapping[str, Callable[[str], object]]) -> None:
    """Add ``hybrid reach`` to the subcommands."""
    p = sub.add_parser("reach", help="prove or refute forbidden states of an affine model")
    p.add_argument("file", metavar="FILE", help="spec or system file")
    p.add_argument(
        "--t-end",
        type=types["positive"],
        default=None,
        help="horizon (default: the spec's checks: {reach: {t_end}})",
    )
    p.add_argument("--max-jumps", type=types["count"], default=None, help="jump bound (default 10)")
    p.add_argument(
        "--step", type=types["positive"], default=None, help="flowpipe step (default t-end / 4000)"
    )
    p.add_argument("--format", choices=tuple(FORMATS), default="text", help="report format")
    p.add_argument(
        "--sets", metavar="SETS.json|SETS.npz", help="write every set: location, times, box"
    )
    p.add_argument(
        "--witness", metavar="DIR", help="write each witness run: overrides, CSV, events JSON"
    )
    p.add_argument(
        "--plot", metavar="X,Y", help="draw the sets projected on two variables (with --out)"
    )
    p.add_argument("--out", metavar="FIG.svg|png", help="figure file for --plot")
    p.add_argument(
        "--quiet", action="store_true", help="no progress line (drawn only on a terminal)"
    )


def _check_args(args: argparse.Namespace) -> None:
    from hybrid.export.outputs import writable_directory, writable_file

    if args.sets is not None:
        writable_file(args.sets, "--sets")
        if Path(args.sets).suffix.lower() not in (".json", ".npz"):
            raise UsageError(f"--sets: use a .json or .npz file name, got '{args.sets}'")
    if args.witness is not None:
        writable_directory(args.witness, "--witness")
    if (args.plot is None) != (args.out is None):
        raise UsageError("--plot X,Y and --out FIG go together")
    if args.plot is not None:
        if len(args.plot.split(",")) != 2:
            raise UsageError(f"--plot: give two variables as X,Y, got '{args.plot}'")
        if Path(args.out).suffix.lower() not in (".svg", ".png", ".pdf"):
            raise UsageError(f"--out: use a .svg, .png or .pdf file name, got '{args.out}'")
        writable_file(args.out, "--out")


REACH_RULES = ("property-proved", "property-violated", "property-unproved")
"""The rules of ``reach``'s findings: one per verdict."""


def findings_of(result: ReachResult) -> list[Finding]:
    """One finding per forbidden entry: proved (note), refuted (error), unknown (warning)."""
    rule = {
        "proved": "property-proved",
        "refuted": "property-violated",
        "unknown": "property-unproved",
    }
    return [
        Finding.at(rule[p.verdict], p.position, p.message, where=f"forbidden: {p.entry.text()}")
        for p in result.properties
    ]


def run_reach(args: argparse.Namespace) -> int:
    """The ``reach`` command; returns the exit code."""
    _check_args(args)  # before the imports: a refused output costs no half second of them
    from hybrid.reach.api import reach
    from hybrid.reader.loader import load

    model = load(args.file)
    if args.plot is not None:
        from hybrid.reach.picture import axis_index

        for name in args.plot.split(","):
            axis_index(model.state_names, name.strip(), model.name)
    t_end = args.t_end if args.t_end is not None else model.properties.reach_t_end
    if t_end is None:
        raise UsageError("give the horizon: --t-end T, or checks: {reach: {t_end: T}} in the spec")
    max_jumps = args.max_jumps
    if max_jumps is None:
        max_jumps = model.properties.reach_max_jumps
    step = args.step if args.step is not None else model.properties.reach_step
    line = terminal_reporter(args.quiet)
    try:
        result = reach(model, t_end, max_jumps=10 if max_jumps is None else max_jumps, step=step,
                       progress=line)  # fmt: skip
    finally:
        if line is not None:
            line.clear()
    if args.sets is not None:
        from hybrid.files import atomic_write

        with atomic_write(args.sets) as handle:
            result.write_sets(handle, Path(args.sets).suffix.lower().lstrip("."))
    if args.witness is not None:
        _write_witnesses(result, Path(args.witness))
    if args.plot is not None:
        _plot(result, args.plot, args.out)
    findings = tuple(findings_of(result))
    if args.format == "text":
        print(_text(result, args.file))
    else:  # strict: an unknown fails here (exit 3), as a warning does with check --strict
        report = Report(findings, result.model, args.file, ran=REACH_RULES)
        print(write(args.format, [report], strict=True))
    if result.verdict == "refuted":
        return EXIT_FINDINGS
    if result.verdict == "unknown":
        return EXIT_UNKNOWN
    return EXIT_OK


def _text(result: ReachResult, file: str) -> str:
    lines = [f"{p.position}: {p.verdict}: {p.message}" for p in result.properties]
    # with no forbidden entry nothing is proved, though the exit code is that of "proved"
    said = result.verdict if result.properties else "no forbidden state to decide (properties: forbidden)"
    lines.append(
        f"{file}: {said}: {len(result.sets)} sets, t <= {result.t_end:g}, "
        f"{result.max_jumps} jumps, step {result.step:g}, {result.seconds:.3g} s"
        + ("" if result.complete else " (search stopped early: nothing is proved)")
        + (f" ({result.jump_past_bound}: not covered)" if result.jump_past_bound else "")
    )
    return "\n".join(lines)


def _write_witnesses(result: ReachResult, folder: Path) -> None:
    from hybrid.export.outputs import make_directory
    from hybrid.export.trajectory import write_csv, write_events

    make_directory(folder, "--witness")
    for i, p in enumerate(result.properties):
        if p.witness is None:
            continue
        stem = folder / f"witness-{i + 1}"
        write_csv(p.witness, stem.with_suffix(".csv"))
        write_events(p.witness, stem.with_suffix(".events.json"))
        stem.with_suffix(".overrides.json").write_text(
            json.dumps(_overrides(p), indent=2) + "\n", encoding="utf-8"
        )


def _overrides(p: PropertyResult) -> dict[str, Any]:
    """The witness as spec overrides: initial state, inputs as (start, value) steps, entry time."""
    inputs = {}
    for name, f in p.witness_inputs.items():
        starts = getattr(f, "starts", None)
        values = getattr(f, "values", None)
        if starts is not None and values is not None:
            inputs[name] = [[float(t), float(v)] for t, v in zip(starts, values, strict=True)]
    return {
        "entry": p.entry.text(),
        "reached_at": p.witness_time,
        "initial": {
            **({"location": p.witness_location} if p.witness_location is not None else {}),
            "state": p.witness_initial,
        },
        "inputs": inputs,
    }


def _plot(result: ReachResult, axes: str, out: str) -> None:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise UsageError("--plot needs matplotlib: pip install 'hybrid[plot]'") from None
    x, y = (a.strip() for a in axes.split(","))
    ax = result.plot(x, y)
    ax.figure.savefig(out)
    plt.close(ax.figure)

