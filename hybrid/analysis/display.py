"""How a check :class:`~hybrid.analysis.findings.Report` prints: in a terminal and in a notebook.

Examples
--------
>>> from hybrid.errors import Position
>>> from hybrid.analysis.findings import Finding, Report
>>> f = Finding.at("dead-edge", Position("a.yaml", 3, 5), "edge 'e' can never fire", where="e")
>>> print(report_text(Report((f,), "a", "a.yaml")))
<Report a (a.yaml): ok, 0 errors, 1 warning, 0 notes
 a.yaml:3:5: warning dead-edge: edge 'e' can never fire>
"""

from __future__ import annotations

from html import escape
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from hybrid.analysis.findings import Report

__all__ = ["report_html", "report_text"]

MAX_FINDINGS = 20
"""Findings listed in the terminal repr before the rest are counted."""

COLOURS = {"error": "#cf222e", "warning": "#9a6700", "note": "#0969da"}


def _counts(report: Report) -> str:
    parts = []
    for severity in ("error", "warning", "note"):
        n = report.count(severity)
        parts.append(f"{n} {severity}{'' if n == 1 else 's'}")
    return ", ".join(parts)


def _title(report: Report) -> str:
    name = report.name or "<model>"
    return f"{name} ({report.file})" if report.file else name


def report_text(report: Report) -> str:
    """``<Report name (file): ok|failed, counts`` and one line per finding."""
    verdict = "ok" if report.ok else "failed"
    lines = [f"<Report {_title(report)}: {verdict}, {_counts(report)}"]
    lines += [f" {f.text()}" for f in report.findings[:MAX_FINDINGS]]
    if len(report.findings) > MAX_FINDINGS:
        lines.append(f" ... and {len(report.findings) - MAX_FINDINGS} more findings")
    return "\n".join(lines) + ">"


def report_html(report: Report) -> str:
    """The verdict and a table of every finding (severity, rule, place, message)."""
    verdict = "ok" if report.ok else "failed"
    colour = "#1a7f37" if report.ok else COLOURS["error"]
    parts = [
        "<div class='hybrid-report'>",
        f"<p><b>Report</b> <code>{escape(_title(report))}</code>: "
        f"<b style='color:{colour}'>{verdict}</b>, {escape(_counts(report))}</p>",
    ]
    if report.findings:
        parts.append(
            "<table><tr><th>severity</th><th>rule</th><th>where</th><th>place</th>"
            "<th style='text-align:left'>message</th></tr>"
        )
        for f in report.findings:
            place = f"{f.file}:{f.line}:{f.column}"
            parts.append(
                f"<tr><td style='color:{COLOURS.get(f.severity, 'inherit')}'>{escape(f.severity)}</td>"
                f"<td><code>{escape(f.rule)}</code></td><td>{escape(f.where)}</td>"
                f"<td>{escape(place)}</td><td style='text-align:left'>{escape(f.message)}</td></tr>"
            )
        parts.append("</table>")
    parts.append("</div>")
    return "\n".join(parts)
