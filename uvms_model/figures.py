"""Analogues of the paper's Figs. 7-12 for one mission (needs the ``plot`` extra).

For each mission three figures: gamma and alpha with gamma_tol, gamma_accel and
gamma_max and the active location of the automaton shaded (Figs. 7 and 10);
vehicle x, y, phi and their rates (Figs. 8 and 11); joints q1..q3 and their
rates (Figs. 9 and 12).
"""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np

from uvms_model.missions import MissionResult

__all__ = ["write_figures"]

_SHADE = {"q0": None, "q1": "tab:red", "q2": "tab:orange"}


def write_figures(result: MissionResult, out_dir: Path, prefix: str) -> list[Path]:
    """Write the three figures of ``result`` as PNG files; returns their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    run = result.run
    t = run.t
    model = run.model
    params = _parameters(result)
    paths: list[Path] = []

    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(t, run["gamma"], label="gamma", color="C0")
    ax.plot(t, np.clip(run["alpha"], -5, 5), label="alpha (clipped to 5)", color="C1")
    for name, style in (("gamma_tol", ":"), ("gamma_accel", "--"), ("gamma_max", "-.")):
        ax.axhline(params[name], color="0.4", ls=style, lw=1, label=f"{name} = {params[name]}")
    _shade(ax, result)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("[u]")
    ax.set_title(f"{model}: performance index (cf. Figs. 7/10); red: q1, orange: q2")
    ax.legend(loc="lower right", fontsize=8)
    paths.append(_save(fig, out_dir / f"{prefix}_gamma.png"))

    fig = _two_panels(
        plt,
        result,
        [("x", "x"), ("y", "y"), ("phi", "phi")],
        [("x_rate", "xp"), ("y_rate", "yp"), ("phid", "phip")],
        ("[m], [rad]", "[m/s], [rad/s]"),
    )
    fig.suptitle(f"{model}: vehicle position and velocity (cf. Figs. 8/11)")
    paths.append(_save(fig, out_dir / f"{prefix}_vehicle.png"))

    fig = _two_panels(
        plt,
        result,
        [("q1", "q1"), ("q2", "q2"), ("q3", "q3")],
        [("q1_rate", "q1p"), ("q2_rate", "q2p"), ("q3_rate_out", "q3p")],
        ("[rad]", "[rad/s]"),
    )
    fig.suptitle(f"{model}: joint positions and velocities (cf. Figs. 9/12)")
    paths.append(_save(fig, out_dir / f"{prefix}_joints.png"))
    plt.close("all")
    return paths


def _two_panels(
    plt: Any,
    result: MissionResult,
    positions: list[tuple[str, str]],
    rates: list[tuple[str, str]],
    ylabels: tuple[str, str],
) -> Any:
    """Positions on the left, their rates on the right, the automaton's locations shaded."""
    run = result.run
    fig, axes = plt.subplots(1, 2, figsize=(11, 4))
    for ax, columns, ylabel in zip(axes, (positions, rates), ylabels, strict=True):
        for name, label in columns:
            ax.plot(run.t, run[name], label=label)
        _shade(ax, result)
        ax.set_xlabel("t [s]")
        ax.set_ylabel(ylabel)
        ax.legend(fontsize=8)
    return fig


def _parameters(result: MissionResult) -> dict[str, float]:
    """The parameters of every component of the simulated model, merged."""
    from hybrid.compose import as_system

    merged: dict[str, float] = {}
    for component in as_system(result.model).components:
        merged.update(component.automaton.parameters)
    return merged


def _shade(ax: object, result: MissionResult) -> None:
    visited = [*result.visited, ("end", float(result.run.t[-1]))]
    for (loc, start), (_, stop) in itertools.pairwise(visited):
        color = _SHADE.get(loc)
        if color is not None:
            ax.axvspan(start, stop, color=color, alpha=0.15)  # type: ignore[attr-defined]


def _save(fig: object, path: Path) -> Path:
    from hybrid.export.atomic import atomic_write

    with atomic_write(path) as handle:
        fig.savefig(handle, format="png", dpi=100)  # type: ignore[attr-defined]
    return path
