"""Figures of a run over hybrid time (needs the ``plot`` extra: matplotlib).

A figure shows, from top to bottom: a *location lane* (a bar per stay, one row
per location, ticks where jumps happen), one panel per state variable with its
``unit:`` on the axis, and one panel of the signals with a legend entry each.
Curves are broken at every jump; each jump is drawn as in the HyEQ toolbox's
``plotHybrid``: a dashed line from the value before it (hollow marker) to the
value after it (filled marker). Values are drawn against ``t``, against the
jump count ``j``, or both side by side (``against="both"``). A system gets one
section per component (:func:`figure_of`) or one figure per component
(:func:`figures_of`).

Figures are made without pyplot, so nothing is shown, kept open or saved unless
asked (:func:`plot` with ``show=True`` or ``path=``; :meth:`hybrid.Run.plot`).

Examples
--------
>>> import hybrid
>>> run = hybrid.simulate(hybrid.load("specs/thermostat.yaml"), t_end=20.0)
>>> fig = figure_of(run)
>>> [ax.get_ylabel() for ax in fig.axes]
['location', 'T [degC]', 'signals']
>>> [t.get_text() for t in fig.axes[0].get_yticklabels()]
['off', 'on']
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hybrid.errors import UsageError
from hybrid.export.hybrid_time import Stay, View, jump_rows, stays, views
from hybrid.files import atomic_write
from hybrid.simulation.result import Run
from hybrid.version import install_hint

__all__ = [
    "AGAINST",
    "MAX_JUMP_LINES",
    "figure_of",
    "figures_of",
    "plot",
    "plot_run",
    "save_figure",
]

AGAINST = ("t", "j", "both")
"""What values are drawn against: time, the jump count, or both side by side."""

MAX_JUMP_LINES = 200
"""At most this many jumps are marked (a Zeno run has thousands)."""

_WIDTH, _LANE, _PANEL, _TITLE = 8.0, 0.5, 1.7, 0.7  # inches
_LANE_COLOURS = ("#c6dbef", "#fdd0a2", "#c7e9c0", "#dadaeb", "#fcbba1", "#d9d9d9", "#fee391")


def _figure_class(managed: bool) -> Any:
    try:
        if managed:
            import matplotlib.pyplot as plt

            return plt.figure
        from matplotlib.figure import Figure
    except ImportError:
        raise UsageError(f"plots need matplotlib: {install_hint('plot')}") from None
    return Figure


def figure_of(
    run: Run,
    *names: str,
    component: str | None = None,
    against: str = "t",
    signals: bool = True,
) -> Any:
    """One figure of ``run``: for a system, one section (subfigure) per component.

    Parameters
    ----------
    run : Run
        From :func:`hybrid.simulate`.
    *names : str
        State variables and signals to draw (default: all).
    component : str, optional
        In a system, only this component.
    against : {"t", "j", "both"}
        Values against time, against the jump count, or both side by side.
    signals : bool
        Draw the signals panel (``False`` with a signal among ``names``: a
        :class:`~hybrid.errors.UsageError`).

    Returns
    -------
    matplotlib.figure.Figure
        Not attached to pyplot: nothing is shown unless asked.
    """
    return _figure(run, names, component, against, signals, managed=False)


def figures_of(run: Run, *names: str, against: str = "t", signals: bool = True) -> dict[str, Any]:
    """One figure per component of a system (one, under the model's name, for an automaton).

    Examples
    --------
    >>> import hybrid
    >>> run = hybrid.simulate(hybrid.load("docs/examples/tank_system.yaml"), t_end=5.0)
    >>> figs = figures_of(run)   # the controller has no state: a location lane and its signals
    >>> list(figs), [ax.get_ylabel() for ax in figs["ctrl"].axes]
    (['plant', 'ctrl'], ['location', 'signals'])
    >>> [ax.get_ylabel() for ax in figs["plant"].axes]
    ['location', 'h [m]', 'signals']
    """
    return {
        view.name: _figure(run, names, view.name if run.components else None, against, signals)
        for view in views(run, names)
    }


def plot(
    run: Run,
    *names: str,
    component: str | None = None,
    against: str = "t",
    signals: bool = True,
    path: str | Path | None = None,
    show: bool = False,
) -> Any:
    """:func:`figure_of`, written to ``path`` and shown only when asked (:meth:`hybrid.Run.plot`)."""
    fig = _figure(run, names, component, against, signals, managed=show)
    if path is not None:
        save_figure(fig, path)
    if show:
        import matplotlib.pyplot as plt

        plt.show()
    return fig


def plot_run(run: Run, path: str | Path, *names: str, against: str = "t") -> None:
    """Write :func:`figure_of` ``run`` to ``path`` (format from the suffix), atomically."""
    save_figure(figure_of(run, *names, against=against), path)


def figure_format(path: str | Path, flag: str = "") -> str:
    """The format of a figure written to ``path`` (its suffix, ``png`` without one).

    A :class:`~hybrid.errors.UsageError` when matplotlib cannot write it, or is
    not installed: the command line asks before it runs anything (``flag``, its
    option, starts the message).

    Examples
    --------
    >>> figure_format("run.SVG"), figure_format("run")
    ('svg', 'png')
    """
    suffix = Path(path).suffix.lstrip(".").lower() or "png"
    try:
        from matplotlib.backend_bases import FigureCanvasBase
    except ImportError:
        raise UsageError(f"plots need matplotlib: {install_hint('plot')}") from None
    supported = FigureCanvasBase.get_supported_filetypes()
    if suffix not in supported:
        raise UsageError(
            f"{flag + ': ' if flag else ''}cannot write '.{suffix}' figures; use one of "
            f"{', '.join(sorted(supported))}"
        )
    return suffix


def save_figure(fig: Any, path: str | Path) -> None:
    """Write ``fig`` to ``path`` in the format its suffix names, whole or not at all."""
    suffix = figure_format(path)
    with atomic_write(path) as handle:
        fig.savefig(handle, format=suffix, dpi=110)


def _figure(
    run: Run,
    names: Sequence[str],
    component: str | None,
    against: str,
    signals: bool,
    managed: bool = False,
) -> Any:
    if against not in AGAINST:
        raise UsageError(f"against must be one of {', '.join(AGAINST)}, got '{against}'")
    selected = views(run, names, component)
    named = [s for view in selected for s in view.signals] if names and not signals else []
    if named:  # asked for by name, then left out: said, not dropped
        raise UsageError(
            f"'{named[0]}' is a signal, and signals=False leaves the signals panel out: "
            "name only states with signals=False, or drop signals=False"
        )
    new_figure = _figure_class(managed)
    heights = [_height(view, signals) for view in selected]
    width = _WIDTH * (2 if against == "both" else 1)
    fig = new_figure(figsize=(width, sum(heights) + _TITLE), layout="constrained")
    if len(selected) == 1 and component is None and not run.components:
        _draw(fig, run, selected[0], against, signals)
    else:
        parts = fig.subfigures(len(selected), 1, height_ratios=heights, squeeze=False)[:, 0]
        for part, view in zip(parts, selected, strict=True):
            _draw(part, run, view, against, signals)
            part.suptitle(f"component {view.name}", fontsize="medium", x=0.01, ha="left")
    term = run.termination
    marked = "" if len(run.jumps) <= MAX_JUMP_LINES else f"; first {MAX_JUMP_LINES} marked"
    fig.suptitle(
        f"{run.model}: {len(run.jumps)} jumps{marked}, ended by {term.cause} at t={term.t:.6g}"
    )
    return fig


def _height(view: View, signals: bool) -> float:
    panels = len(view.states) + (1 if signals and view.signals else 0)
    return _LANE + _PANEL * panels + 0.4


def _label(run: Run, name: str) -> str:
    return f"{name} [{run.units[name]}]" if name in run.units else name


def _draw(container: Any, run: Run, view: View, against: str, signals: bool) -> None:
    columns = ("t", "j") if against == "both" else (against,)
    show_signals = signals and bool(view.signals)
    rows = 1 + len(view.states) + (1 if show_signals else 0)
    ratios = [_LANE, *([_PANEL] * (rows - 1))]
    axes = container.subplots(
        rows, len(columns), sharex="col", squeeze=False, gridspec_kw={"height_ratios": ratios}
    )
    the_stays = stays(run, view)
    jumps = jump_rows(run)[:MAX_JUMP_LINES]
    for c, axis in enumerate(columns):
        _lane(axes[0, c], run, the_stays, jumps, axis)
        for r, name in enumerate(view.states, start=1):
            ax = axes[r, c]
            values = run[name]
            _flow(ax, run, the_stays, axis, values, name, "C0")
            _jumps(ax, run, jumps, axis, values, "C0")
            if c == 0:
                ax.set_ylabel(_label(run, name))
            if r == 1 and c == len(columns) - 1 and len(jumps):
                _marker_legend(ax)
        if show_signals:
            ax = axes[-1, c]
            for k, name in enumerate(view.signals):
                colour = f"C{k % 10}"
                values = run[name]
                _flow(ax, run, the_stays, axis, values, _label(run, name), colour, dense=False)
                _jumps(ax, run, jumps, axis, values, colour)
            if c == 0:
                ax.set_ylabel("signals")
            if c == len(columns) - 1:
                ax.legend(
                    loc="upper left",
                    bbox_to_anchor=(1.01, 1.0),
                    fontsize="small",
                    ncol=max(1, math.ceil(len(view.signals) / 14)),
                )
        for ax in axes[1:, c]:
            ax.grid(True, alpha=0.3)
        axes[-1, c].set_xlabel("t [s]" if axis == "t" else "j (jumps)")


def _x(run: Run, axis: str) -> NDArray[np.float64]:
    return run.t if axis == "t" else run.j.astype(float)


def _flow(
    ax: Any,
    run: Run,
    the_stays: list[Stay],
    axis: str,
    values: NDArray[np.float64],
    name: str,
    colour: str,
    dense: bool = True,
) -> None:
    """One line for the whole run, broken (NaN) between stays."""
    xs: list[Any] = []
    ys: list[Any] = []
    state = run.state_names.index(name) if name in run.state_names else None
    if dense and axis == "t" and run.segments and state is not None:
        for _, t0, t1, interpolant in run.segments:
            grid = np.linspace(t0, t1, 200)
            xs += [grid, [np.nan]]
            ys += [interpolant(grid)[state], [np.nan]]
    else:
        x = _x(run, axis)
        for stay in the_stays:
            xs += [x[stay.start : stay.stop], [np.nan]]
            ys += [values[stay.start : stay.stop], [np.nan]]
    if xs:
        ax.plot(np.concatenate(xs), np.concatenate(ys), color=colour, lw=1.3, label=name)


def _jumps(
    ax: Any,
    run: Run,
    rows: NDArray[np.int64],
    axis: str,
    values: NDArray[np.float64],
    colour: str,
) -> None:
    """Each jump: a dashed line from before (hollow marker) to after (filled marker)."""
    if not len(rows):
        return
    x = _x(run, axis)
    x0, x1, y0, y1 = x[rows], x[rows + 1], values[rows], values[rows + 1]
    gap = np.full(len(rows), np.nan)
    ax.plot(
        np.column_stack([x0, x1, gap]).ravel(),
        np.column_stack([y0, y1, gap]).ravel(),
        ls="--",
        lw=0.8,
        color=colour,
        alpha=0.8,
        label="_jump",
        gid="jump",
    )
    ax.plot(
        x0,
        y0,
        ls="none",
        marker="o",
        ms=4,
        mfc="white",
        mec=colour,
        label="_before",
        gid="jump-before",
    )
    ax.plot(x1, y1, ls="none", marker="o", ms=4, color=colour, label="_after", gid="jump-after")


def _marker_legend(ax: Any) -> None:
    from matplotlib.lines import Line2D

    handles = [
        Line2D([], [], ls="none", marker="o", ms=4, mfc="white", mec="0.3"),
        Line2D([], [], ls="none", marker="o", ms=4, color="0.3"),
    ]
    ax.legend(
        handles,
        ["before a jump", "after a jump"],
        loc="upper left",
        bbox_to_anchor=(1.01, 1.0),
        fontsize="small",
    )


def _lane(ax: Any, run: Run, the_stays: list[Stay], rows: NDArray[np.int64], axis: str) -> None:
    """A bar per stay, one row per location (first visited on top), ticks at jumps."""
    locations = list(dict.fromkeys(stay.location for stay in the_stays))
    row_of = {loc: k for k, loc in enumerate(locations)}
    for loc, k in row_of.items():
        if axis == "t":
            spans = [(s.t0, s.t1 - s.t0) for s in the_stays if s.location == loc]
        else:
            spans = [(s.j - 0.4, 0.8) for s in the_stays if s.location == loc]
        ax.broken_barh(
            spans,
            (k - 0.35, 0.7),
            facecolors=_LANE_COLOURS[k % len(_LANE_COLOURS)],
            edgecolors="0.4",
            linewidth=0.5,
            gid=f"lane:{loc}",
        )
    if len(rows):
        x = _x(run, axis)
        by_start = {s.start: s for s in the_stays}
        before = [row_of[_stay_at(the_stays, int(i)).location] for i in rows]
        after = [row_of[by_start[int(i) + 1].location] for i in rows]
        gap = np.full(len(rows), np.nan)
        ax.plot(
            np.column_stack([x[rows], x[rows + 1], gap]).ravel(),
            np.column_stack([before, after, gap]).ravel(),
            color="0.25",
            lw=0.8,
            ls="--",
            gid="lane-jumps",
        )
        ax.plot(
            x[rows + 1], after, ls="none", marker="|", ms=9, color="0.15", gid="lane-jump-marks"
        )
    ax.set_yticks(range(len(locations)), locations)
    ax.set_ylim(len(locations) - 0.5, -0.5)
    ax.set_ylabel("location")
    ax.tick_params(axis="y", length=0)


def _stay_at(the_stays: list[Stay], row: int) -> Stay:
    for stay in the_stays:
        if stay.start <= row < stay.stop:
            return stay
    raise AssertionError(f"row {row} is in no stay")
