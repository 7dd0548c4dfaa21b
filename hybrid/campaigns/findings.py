"""A sweep's table as findings, for the CI formats of ``hybrid check`` (github, junit, sarif).

One finding per requirement, placed at the requirement in its spec file:
``requirement-violated`` (error) when some run violates it, naming the varied
values of the violating run of lowest robustness; ``requirement-held`` (a note)
when every run satisfies it, with the lowest robustness. Runs that raised or
timed out give one ``sweep-run-failed`` error at the top of the swept file,
naming the first of them. The reports go through
:func:`hybrid.analysis.formats.write` unchanged.

Examples
--------
>>> import hybrid
>>> heater = hybrid.load_text('''
... automaton: heater
... parameters: {k: 0.1}
... state: {x: {initial: 20.0}}
... locations: {cooling: {flow: {x: -k*x}}}
... requirements: [{name: warm, always: "x >= 15"}]
... ''', file="heater.yaml")
>>> table = hybrid.sweep(heater, t_end=5.0, grid={"k": [0.01, 0.1]}, workers=0)
>>> for f in sweep_findings(heater, table)[0].findings:  # doctest: +NORMALIZE_WHITESPACE
...     print(f.text())
heater.yaml:6:16: error requirement-violated: requirement 'warm' (always x >= 15) is
  violated in 1 of 2 runs; lowest robustness -2.86939 at k=0.1 (run 1, violated at t=2.87682)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from hybrid.analysis.findings import Finding, Report
from hybrid.campaigns.table import FAILED, SweepTable
from hybrid.compose import System, as_system
from hybrid.simulation.watched import watched_requirements

__all__ = ["sweep_findings", "values_text"]


def values_text(row: dict[str, Any], names: Sequence[str]) -> str:
    """``e=0.5, init.h=10``: a run's varied values as a person reads them."""
    return ", ".join(f"{n}={row[n]:.6g}" for n in names)


def sweep_findings(model: Any, table: SweepTable) -> list[Report]:
    """The findings of ``table``, one report per file they are placed in."""
    system: System = as_system(model)
    findings: list[Finding] = []
    total = len(table.rows)
    for w in watched_requirements(system):
        r = w.requirement
        rows = [row for row in table.rows if row.get(f"{w.name}.robustness") is not None]
        violated = [row for row in rows if row.get(f"{w.name}.holds") is False]
        what = f"requirement '{w.name}' ({r.kind} {r.source})"
        if violated:
            worst = min(violated, key=lambda row: _robustness(row, w.name))
            at = worst.get(f"{w.name}.violated_at")
            when = "" if at is None else f", violated at t={at:.6g}"
            message = (
                f"{what} is violated in {len(violated)} of {total} runs; lowest robustness "
                f"{_robustness(worst, w.name):.6g} at {values_text(worst, table.varied)} "
                f"(run {worst['run']}{when})"
            )
            findings.append(Finding.at("requirement-violated", r.position, message, where=w.name))
        elif rows:
            lowest = min(rows, key=lambda row: _robustness(row, w.name))
            message = (
                f"{what} holds in all {len(rows)} runs; lowest robustness "
                f"{_robustness(lowest, w.name):.6g} at {values_text(lowest, table.varied)} "
                f"(run {lowest['run']})"
            )
            findings.append(Finding.at("requirement-held", r.position, message, where=w.name))
    failed = [row for row in table.rows if row.get("cause") in FAILED]
    if failed:
        first = failed[0]
        message = (
            f"{len(failed)} of {total} runs failed; the first, run {first['run']} at "
            f"{values_text(first, table.varied)}: {first['cause']}: {first.get('message') or ''}"
        )
        findings.append(Finding.at("sweep-run-failed", system.position, message.rstrip(": ")))
    by_file: dict[str, list[Finding]] = {}
    for f in findings:
        by_file.setdefault(f.file, []).append(f)
    if not by_file:
        by_file[system.file] = []
    return [
        Report(tuple(sorted(fs, key=Finding.sort_key)), system.name, file)
        for file, fs in by_file.items()
    ]


def _robustness(row: dict[str, Any], name: str) -> float:
    value = row.get(f"{name}.robustness")
    return math.inf if value is None or math.isnan(float(value)) else float(value)
