"""How a :class:`~hybrid.simulation.result.Run` prints: in a terminal and in a notebook.

Examples
--------
>>> import hybrid
>>> run = hybrid.simulate(hybrid.load("specs/bouncing_ball.yaml"), t_end=2.0)
>>> print(run_text(run))
<Run bouncing_ball: t_end at t=2 j=1 (1 jumps, 9 points)
 states: h [m], v [m/s]; signals: energy; locations: falling>
"""

from __future__ import annotations

from html import escape
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from hybrid.simulation.result import Run

__all__ = ["run_html", "run_text"]

MAX_NAMES = 12
"""Columns named in a repr before the rest are counted."""

MAX_JUMP_ROWS = 10
"""Jumps listed in the notebook view before the rest are counted."""


def _names(names: list[str]) -> str:
    if len(names) <= MAX_NAMES:
        return ", ".join(names) or "none"
    return ", ".join(names[:MAX_NAMES]) + f", ... ({len(names)} in all)"


def _states(run: Run) -> list[str]:
    return [f"{s} [{run.units[s]}]" if s in run.units else s for s in run.state_names]


def _locations(run: Run) -> list[str]:
    return list(dict.fromkeys(str(loc) for loc in run.location))


def run_text(run: Run) -> str:
    """``<Run model: cause at t=.. j=.. (n jumps, m points)`` with its columns (and message)."""
    term = run.termination
    lines = [
        f"<Run {run.model}: {term.cause} at t={term.t:.6g} j={term.j} "
        f"({len(run.jumps)} jumps, {len(run)} points)",
        f" states: {_names(_states(run))}; signals: {_names(list(run.signal_names))}; "
        f"locations: {_names(_locations(run))}",
    ]
    if not term.ok:
        lines.append(f" {term.message}")
    return "\n".join(lines) + ">"


def _row(header: str, value: str) -> str:
    return f"<tr><th style='text-align:left'>{escape(header)}</th><td style='text-align:left'>{value}</td></tr>"


def run_html(run: Run) -> str:
    """A small HTML summary: how the run ended, its columns, its first jumps."""
    term = run.termination
    colour = "#1a7f37" if term.ok else "#b35900"
    t_range = f"[{run.t[0]:.6g}, {run.t[-1]:.6g}]" if len(run) else "empty"
    rows = [
        _row(
            "ended",
            f"<b style='color:{colour}'>{escape(term.cause)}</b> at t={term.t:.9g}, j={term.j}",
        ),
        _row("message", escape(term.message)),
        _row("points", f"{len(run)} (t in {t_range})"),
        _row("jumps", str(len(run.jumps))),
        _row("states", escape(_names(_states(run)))),
        _row("signals", escape(_names(list(run.signal_names)))),
        _row("locations", escape(_names(_locations(run)))),
    ]
    if term.zeno_time is not None:
        rows.append(_row("Zeno time", f"{term.zeno_time:.9g}"))
    parts = [
        "<div class='hybrid-run'>",
        f"<p><b>Run</b> <code>{escape(run.model)}</code></p>",
        "<table>",
        *rows,
        "</table>",
    ]
    if run.jumps:
        parts.append("<table><tr><th>t</th><th>j</th><th>edge</th><th>from</th><th>to</th></tr>")
        for jump in run.jumps[:MAX_JUMP_ROWS]:
            parts.append(
                f"<tr><td>{jump.t:.9g}</td><td>{jump.j}</td><td>{escape(jump.edge)}</td>"
                f"<td>{escape(jump.source)}</td><td>{escape(jump.target)}</td></tr>"
            )
        parts.append("</table>")
        if len(run.jumps) > MAX_JUMP_ROWS:
            parts.append(f"<p>... and {len(run.jumps) - MAX_JUMP_ROWS} more jumps</p>")
    parts.append("</div>")
    return "\n".join(parts)
