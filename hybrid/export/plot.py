"""Figures of a run: each state against t, jumps marked (needs the ``plot`` extra).

Examples
--------
>>> import hybrid
>>> run = hybrid.simulate(hybrid.load("specs/thermostat.yaml"), t_end=20.0)
>>> fig = figure_of(run)
>>> [ax.get_ylabel() for ax in fig.axes]
['T']
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from hybrid.errors import SimulationError, UsageError
from hybrid.export.atomic import atomic_write
from hybrid.simulation.result import Run
from hybrid.version import install_hint

__all__ = ["MAX_JUMP_LINES", "figure_of", "plot_run"]

MAX_JUMP_LINES = 200
"""At most this many jump instants are marked (a Zeno run has thousands)."""


def _pyplot() -> Any:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise UsageError(f"--plot needs matplotlib: {install_hint('plot')}") from None
    return plt


def figure_of(run: Run) -> Any:
    """A figure with one panel per state variable against ``t``; dashed lines at jumps.

    With ``run.segments`` (``simulate(..., dense=True)``) the curves are drawn from
    the solver's interpolants, otherwise from the stored points; either way the
    line is broken at every jump.
    """
    plt = _pyplot()
    names = run.state_names
    fig, axes = plt.subplots(
        len(names), 1, sharex=True, figsize=(8, 2.2 * len(names) + 0.8), squeeze=False
    )
    jump_times = sorted({jump.t for jump in run.jumps})[:MAX_JUMP_LINES]
    for k, (ax, name) in enumerate(zip(axes[:, 0], names, strict=True)):
        if run.segments:
            for _, t0, t1, interpolant in run.segments:
                grid = np.linspace(t0, t1, 200)
                ax.plot(grid, interpolant(grid)[k], color="C0", lw=1.2)
        else:
            start = 0
            for i in range(1, len(run) + 1):
                if i == len(run) or run.j[i] != run.j[start]:
                    ax.plot(run.t[start:i], run[name][start:i], color="C0", lw=1.2)
                    start = i
        for tj in jump_times:
            ax.axvline(tj, color="0.6", lw=0.6, ls="--")
        ax.set_ylabel(name)
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("t")
    term = run.termination
    fig.suptitle(f"{run.model}: {len(run.jumps)} jumps, ended by {term.cause} at t={term.t:.6g}")
    fig.tight_layout()
    return fig


def plot_run(run: Run, path: str | Path) -> None:
    """Write :func:`figure_of` ``run`` to ``path`` (format from the suffix), atomically."""
    plt = _pyplot()
    fig = figure_of(run)
    suffix = Path(path).suffix.lstrip(".").lower() or "png"
    if suffix not in fig.canvas.get_supported_filetypes():
        plt.close(fig)
        raise SimulationError(
            f"--plot: cannot write '.{suffix}' figures; use one of "
            f"{', '.join(sorted(fig.canvas.get_supported_filetypes()))}"
        )
    try:
        with atomic_write(path) as handle:
            fig.savefig(handle, format=suffix, dpi=110)
    finally:
        plt.close(fig)
