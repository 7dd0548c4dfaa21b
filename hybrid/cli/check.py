"""The `hybrid check` and `hybrid graph` commands.

``run_check`` checks every file, prints the findings of all of them in the
chosen format, and returns the exit code of the contract: 0 when no finding
is an error, 1 when one is (or, with ``strict``, when one is a warning), 2
when a file is not a valid spec. An invalid file's errors go to stderr as
``file:line:column: message`` (as ``hybrid validate`` prints them) and, in the
structured formats, also appear as ``invalid-spec`` findings; the other files
are still checked and reported. Each finding is reported once, however many
of the files checked include the file it is placed in. The repository's
defaults come from ``[tool.hybrid.check]`` in the nearest pyproject.toml
(:mod:`hybrid.reader.project`). While a large product is explored, one line of
progress (modes explored, frontier, modes per second) is drawn on ``err`` when
it is a terminal, unless ``quiet``; it is erased before the report.

Examples
--------
>>> import io
>>> out = io.StringIO()
>>> run_check(["specs/thermostat.yaml"], fmt="text", out=out, config=CheckConfig())
0
>>> out.getvalue()
'specs/thermostat.yaml: ok\\n'
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable, Sequence
from dataclasses import replace
from pathlib import Path
from typing import TextIO

from hybrid.analysis import system_graph
from hybrid.analysis.findings import RULES, Finding, Report
from hybrid.analysis.formats import FORMATS, write
from hybrid.analysis.ignore import check_rule_ids
from hybrid.cli.exits import EXIT_FINDINGS, EXIT_INVALID, EXIT_OK
from hybrid.errors import SpecError, UsageError
from hybrid.export.diagrams import DIAGRAM_FORMATS
from hybrid.export.pictures import RENDERED_FORMATS, render
from hybrid.files import atomic_write
from hybrid.progress import Reporter, Tracker, terminal_reporter
from hybrid.reach.check import check
from hybrid.reader.loader import load
from hybrid.reader.project import CheckConfig, read_check_config

__all__ = [
    "GRAPH_SUFFIXES",
    "exploration_progress",
    "graph_format",
    "once",
    "run_check",
    "run_graph",
]


def run_check(
    files: Sequence[str],
    *,
    fmt: str = "text",
    strict: bool = False,
    ignore: Sequence[str] = (),
    out: TextIO | None = None,
    err: TextIO | None = None,
    config: CheckConfig | None = None,
    quiet: bool = False,
    reach_t_end: float | None = None,
    reach_max_jumps: int | None = None,
) -> int:
    """Check ``files`` and print the report; returns the exit code (0, 1 or 2).

    Parameters
    ----------
    files
        Spec files (automata or systems).
    fmt
        ``text``, ``json``, ``github``, ``junit`` or ``sarif``.
    strict
        Warnings fail the run too.
    ignore
        Rule ids not to report (added to the repository's ``[tool.hybrid.check]``).
    out, err
        Streams for the report and for spec errors (default: stdout, stderr).
    config
        The repository's defaults (default: read from the nearest pyproject.toml).
    quiet
        No progress line on ``err`` (it is drawn only when ``err`` is a terminal).
    reach_t_end, reach_max_jumps
        Decide unproved forbidden entries of affine models with ``hybrid reach``
        over this horizon (default: each spec's ``checks: {reach: {...}}``).
    """
    if fmt not in FORMATS:
        raise ValueError(f"unknown format '{fmt}'; choose from {', '.join(FORMATS)}")
    out = out or sys.stdout
    err = err or sys.stderr
    if config is None:
        config = read_check_config(rules=[r for r in RULES if r != "invalid-spec"])
    rules = check_rule_ids((*config.ignore, *ignore))
    strict = strict or config.strict
    reports: list[Report] = []
    invalid = False
    for file in files:
        try:
            model = load(file)
        except SpecError as exc:
            invalid = True
            print(str(exc), file=err)
            findings = tuple(
                Finding.at("invalid-spec", position, message, where=file)
                for position, message in exc.problems
            )
            reports.append(Report(findings, "", file))
            continue
        line = terminal_reporter(quiet, err)
        tracker, progress = exploration_progress(f"check {file}", line)
        try:
            report = check(
                model,
                ignore=rules,
                progress=progress,
                reach_t_end=reach_t_end,
                reach_max_jumps=reach_max_jumps,
            )
        finally:
            if line is not None:
                line.clear()
        if tracker is not None:
            tracker.finish()
        reports.append(replace(report, file=file))
    text = write(fmt, once(reports), strict=strict)
    if text:
        print(text, file=out)
    if invalid:
        return EXIT_INVALID
    if any(r.failed(strict=strict) for r in reports):
        return EXIT_FINDINGS
    return EXIT_OK


def exploration_progress(
    task: str, line: Reporter | None, interval: float = 0.2
) -> tuple[Tracker | None, Callable[[int, int], None] | None]:
    """A tracker reporting to ``line`` and the ``progress(modes, frontier)`` callback feeding it.

    The explorer reports the modes of one group of interacting components at a
    time; the count shown adds up the groups. Nothing is reported for a product
    explored within ``interval`` seconds: only a large one shows.

    Examples
    --------
    >>> seen = []
    >>> tracker, progress = exploration_progress("check s.yaml", seen.append, interval=0.0)
    >>> progress(100, 40); progress(250, 10); progress(30, 5)   # a second group starts
    >>> seen[-1].text().split(", ")[:2]
    ['check s.yaml: 280 modes', '5 frontier']
    """
    if line is None:
        return None, None
    tracker = Tracker(task, unit="modes", report=line, interval=interval)
    counted = [0, 0]  # modes of the groups finished, modes of the current group

    def progress(modes: int, frontier: int) -> None:
        if modes < counted[1]:  # the next group of components
            counted[0] += counted[1]
        counted[1] = modes
        tracker.update(counted[0] + modes, frontier=frontier)

    return tracker, progress


def once(reports: Sequence[Report]) -> list[Report]:
    """The reports with every finding kept only the first time its place and rule appear.

    A component file checked on its own and as part of a system gives the same
    findings twice (with unqualified and qualified names); CI annotations must
    not repeat them.
    """
    seen: set[tuple[str, str, int, int]] = set()
    result: list[Report] = []
    for report in reports:
        kept: list[Finding] = []
        for f in report.findings:
            key = (f.rule, os.path.normpath(os.path.abspath(f.file)), f.line, f.column)
            if key not in seen:
                seen.add(key)
                kept.append(f)
        result.append(replace(report, findings=tuple(kept), repeated=len(report.findings) - len(kept)))
    return result


GRAPH_SUFFIXES = {".dot": "dot", ".gv": "dot", ".mmd": "mermaid", ".mermaid": "mermaid",
                  ".svg": "svg", ".png": "png"}  # fmt: skip
"""The format a file name says, for ``hybrid graph --out``."""


def graph_format(fmt: str | None, path: str | None) -> str:
    """``--format``, else the format ``--out``'s name says, else ``dot``; a UsageError when
    the two disagree (a ``.svg`` file of DOT text, say).

    Examples
    --------
    >>> graph_format(None, "g.svg"), graph_format(None, None), graph_format("mermaid", "g.md")
    ('svg', 'dot', 'mermaid')
    """
    said = GRAPH_SUFFIXES.get(Path(path).suffix.lower()) if path is not None else None
    if fmt is None:
        return said or "dot"
    if said is not None and said != fmt:
        raise UsageError(
            f"--out {path}: the name says {said}, --format says {fmt}; leave out --format "
            f"(the name decides), or name the file .{fmt}"
        )
    return fmt


def run_graph(
    file: str, *, fmt: str | None = None, out: TextIO | None = None, path: str | None = None
) -> int:
    """Print the location graph of ``file`` (the reachable product of a system).

    ``svg`` and ``png`` are drawn by Graphviz (:mod:`hybrid.export.pictures`);
    ``path`` writes the output to that file (atomically) instead of ``out``; the
    format is ``fmt``, else the one ``path``'s name says, else ``dot``
    (:func:`graph_format`). Raises :class:`hybrid.SpecError` for an invalid spec
    (the CLI exits 2) and :class:`hybrid.UsageError` when Graphviz is missing.
    """
    fmt = graph_format(fmt, path)
    writers = DIAGRAM_FORMATS
    if fmt not in writers and fmt not in RENDERED_FORMATS:
        choices = (*writers, *RENDERED_FORMATS)
        raise ValueError(f"unknown format '{fmt}'; choose from {', '.join(choices)}")
    out = out or sys.stdout
    if path is not None:
        from hybrid.export.outputs import writable_file

        writable_file(path, "--out")
    if fmt == "png" and path is None and out.isatty():
        raise UsageError("--format png is binary: write it with --out FILE or redirect stdout")
    graph = system_graph(load(file))
    if not graph.graph.get("complete", True):
        print(
            f"{file}: the product has more modes than drawn; showing the first "
            f"{graph.number_of_nodes()}",
            file=sys.stderr,
        )
    data = render(graph, fmt) if fmt in RENDERED_FORMATS else (writers[fmt](graph) + "\n").encode()
    if path is not None:
        with atomic_write(path) as handle:
            handle.write(data)
    elif fmt == "png":
        out.flush()
        out.buffer.write(data)
    else:
        out.write(data.decode("utf-8"))
    return EXIT_OK
