"""Figures of a run: each state against t, jumps marked (needs the ``plot`` extra)."""

from __future__ import annotations

from pathlib import Path

from hybrid.errors import SimulationError
from hybrid.export.atomic import atomic_write
from hybrid.simulation.result import Run

__all__ = ["plot_run"]


def plot_run(run: Run, path: str | Path) -> None:
    """Draw every state variable against ``t`` in stacked panels; dashed lines at jumps."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise SimulationError("--plot needs matplotlib: pip install 'hybrid[plot]'") from None
    names = run.state_names
    fig, axes = plt.subplots(
        len(names), 1, sharex=True, figsize=(8, 2.2 * len(names) + 0.8), squeeze=False
    )
    jump_times = sorted({jump.t for jump in run.jumps})
    import numpy as np

    for k, (ax, name) in enumerate(zip(axes[:, 0], names, strict=True)):
        if run.segments:  # smooth curves from the solver's interpolants
            for _, t0, t1, interpolant in run.segments:
                grid = np.linspace(t0, t1, 200)
                ax.plot(grid, interpolant(grid)[k], color="C0", lw=1.2)
        else:  # stored points, the line broken at each jump
            start = 0
            for i in range(1, len(run) + 1):
                if i == len(run) or run.j[i] != run.j[start]:
                    ax.plot(run.t[start:i], run[name][start:i], color="C0", lw=1.2)
                    start = i
        for tj in jump_times[:200]:
            ax.axvline(tj, color="0.6", lw=0.6, ls="--")
        ax.set_ylabel(name)
        ax.grid(True, alpha=0.3)
    axes[-1, 0].set_xlabel("t")
    cause = run.termination.cause
    fig.suptitle(
        f"{run.model}: {len(run.jumps)} jumps, ended by {cause} at t={run.termination.t:.6g}"
    )
    fig.tight_layout()
    suffix = Path(path).suffix.lstrip(".") or "png"
    with atomic_write(path) as handle:
        fig.savefig(handle, format=suffix, dpi=110)
    plt.close(fig)
