"""Analogues of the paper's Figs. 7-12 for one mission (needs the ``plot`` extra).

For each mission five figures: the XY plane with the end-effector path, the vehicle's
path and snapshots of the arm (the left panels of Figs. 7 and 10); gamma and alpha with
gamma_tol, gamma_accel and gamma_max and the active location of the automaton shaded
(the right panels of Figs. 7 and 10); vehicle x, y, phi and their rates (Figs. 8 and
11); joints q1..q3 (unwrapped, with the lines at -pi and pi that the tool-heading law
keeps them within) and their rates (Figs. 9 and 12); the
functional machine: its output s, the bias theta_p and the polarization state.
"""

from __future__ import annotations

import itertools
from pathlib import Path
from typing import Any

import numpy as np

from uvms_model.missions import MissionResult

__all__ = ["output_folder", "save_png", "write_figures"]

_SHADE = {"q0": None, "q1": "tab:red", "q2": "tab:orange"}


def write_figures(result: MissionResult, out_dir: Path, prefix: str) -> list[Path]:
    """Write the five figures of ``result`` as PNG files; returns their paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    run = result.run
    t = run.t
    model = run.model
    params = _parameters(result)
    paths: list[Path] = [_xy_figure(plt, result, out_dir / f"{prefix}_xy.png")]

    fig, ax = plt.subplots(figsize=(8, 4))
    ax.plot(t, run["gamma"], label="|gamma|", color="C0")
    ax.plot(t, np.clip(run["alpha"], -5, 5), label="alpha (clipped to 5)", color="C1")
    for name, style in (("gamma_tol", ":"), ("gamma_accel", "--"), ("gamma_max", "-.")):
        ax.axhline(params[name], color="0.4", ls=style, lw=1, label=f"{name} = {params[name]}")
    _shade(ax, result)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("[u]")
    ax.set_title(f"{model}: performance index (cf. Figs. 7/10); red: q1, orange: q2")
    # beside the axes: inside, at the lower right, it covered mission 2's dip below gamma_tol
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, borderaxespad=0.0)
    fig.set_size_inches(10.5, 4)
    fig.tight_layout()
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
        [("q1_rate", "q1p"), ("q2_rate", "q2p"), ("q3_rate", "q3p")],
        ("[rad]", "[rad/s]"),
    )
    for bound in (-np.pi, np.pi):
        fig.axes[0].axhline(bound, color="0.4", ls=":", lw=1)
    fig.suptitle(
        f"{model}: joint positions (unwrapped; dotted: +-pi) and velocities (cf. Figs. 9/12)"
    )
    paths.append(_save(fig, out_dir / f"{prefix}_joints.png"))

    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    ax1.plot(t, run["s"], label="s (FM output)")
    ax1.set_ylabel("s")
    polarization = [loc.split("|")[-1].split(".")[-1] for loc in run.location]
    for state, color in (("S2", "tab:green"), ("S3", "tab:purple")):
        inside = np.array([p == state for p in polarization])
        ax1.fill_between(t, 0, 1, where=inside, color=color, alpha=0.12, label=state,
                         transform=ax1.get_xaxis_transform())  # fmt: skip
    ax1.legend(fontsize=8)
    ax2.plot(t, run["theta_p"], label="theta_p (bias)", color="C1")
    ax2.set_ylabel("theta_p")
    ax2.set_xlabel("t [s]")
    fig.suptitle(f"{model}: functional machine (S2 green, S3 purple, S1 blank)")
    paths.append(_save(fig, out_dir / f"{prefix}_fm.png"))
    plt.close("all")
    return paths


def _xy_figure(plt: Any, result: MissionResult, path: Path) -> Path:
    """End-effector path (commanded and actual), vehicle path, arm snapshots every 5 s."""
    from uvms_model.chain import joint_points

    run = result.run
    p = _parameters(result)
    geometry = (p["a1"], p["a2"], p["a3"], p["base_x"], p["base_y"])
    fig, ax = plt.subplots(figsize=(7, 6))
    ax.plot(run["path[0]"], run["path[1]"], color="0.6", ls=":", lw=2, label="commanded path")
    ax.plot(run["ee[0]"], run["ee[1]"], color="C0", lw=1, label="end effector")
    ax.plot(run["x"], run["y"], color="C3", lw=1.5, label="vehicle")
    for k, when in enumerate(np.arange(0.0, float(run.t[-1]) + 1e-9, 5.0)):
        i = min(int(np.searchsorted(run.t, when)), len(run.t) - 1)
        x, y, phi, q1, q2, q3 = (float(run[c][i]) for c in ("x", "y", "phi", "q1", "q2", "q3"))
        pts = joint_points(x, y, phi, q1, q2, q3, *geometry)
        xs = [float(run["x"][i]), pts[0], pts[2], pts[4], pts[6]]
        ys = [float(run["y"][i]), pts[1], pts[3], pts[5], pts[7]]
        color = plt.cm.viridis(when / max(float(run.t[-1]), 1.0))
        ax.plot(xs, ys, "-o", color=color, ms=2.5, lw=1, label="arm every 5 s" if k == 0 else None)
    for loc, when in result.visited[1:]:
        i = min(int(np.searchsorted(run.t, when)), len(run.t) - 1)
        ax.plot(run["x"][i], run["y"][i], marker="s", color=_SHADE.get(loc) or "k", ms=7)
        ax.annotate(loc, (run["x"][i], run["y"][i]), textcoords="offset points", xytext=(4, 4))
    ax.set_aspect("equal")
    ax.set_xlabel("X [m]")
    ax.set_ylabel("Y [m]")
    ax.legend(fontsize=8, loc="best")
    ax.set_title(f"{run.model}: XY plane (cf. the left panels of Figs. 7/10)")
    return _save(fig, path)


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
    from hybrid.files import atomic_write

    with atomic_write(path) as handle:
        fig.savefig(handle, format="png", dpi=100)  # type: ignore[attr-defined]
    return path


def save_png(fig: object, path: Path) -> Path:
    """Write ``fig`` to ``path`` as a PNG, whole or not at all, and close it."""
    import matplotlib.pyplot as plt

    _save(fig, path)
    plt.close(fig)  # type: ignore[arg-type]
    return path


def output_folder(argv: list[str] | None) -> Path:
    """The folder a case-study command writes into: its one argument, else ``out`` (made)."""
    import sys

    args = sys.argv[1:] if argv is None else argv
    out = Path(args[0] if args else "out")
    out.mkdir(parents=True, exist_ok=True)
    return out
