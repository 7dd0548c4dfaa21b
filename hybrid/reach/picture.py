"""The picture of a reach result: sets projected on two variables, runs and forbidden sets over them.

Examples
--------
>>> clip_polygon([(0, 0), (2, 0), (2, 2), (0, 2)], [((1.0, 0.0), 1.0)])
[(0, 0), (1.0, 0.0), (1.0, 2.0), (0, 2)]
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from hybrid.errors import UsageError
from hybrid.reach.affine import TIME

if TYPE_CHECKING:
    from hybrid.reach.result import ReachResult
    from hybrid.simulation.result import Run

__all__ = ["DRAWN_POINTS", "axis_index", "clip_polygon", "draw"]

DRAWN_POINTS = 2000
"""Points of the nominal run drawn over the sets, evenly spaced to the horizon (and its jumps)."""

Point = tuple[float, float]
HalfPlane = tuple[tuple[float, float], float]
"""``((a, b), c)``: the points with ``a x + b y <= c``."""


def clip_polygon(polygon: list[Point], planes: Sequence[HalfPlane]) -> list[Point]:
    """``polygon`` cut by each half-plane in turn (Sutherland-Hodgman)."""
    out = list(polygon)
    for (a, b), c in planes:
        if not out:
            break
        src, out = out, []
        for i, p in enumerate(src):
            q = src[(i + 1) % len(src)]
            fp, fq = a * p[0] + b * p[1] - c, a * q[0] + b * q[1] - c
            if fp <= 0:
                out.append(p)
            if (fp < 0 < fq) or (fq < 0 < fp):
                s = fp / (fp - fq)
                out.append((p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1])))
    return out


def axis_index(variables: Sequence[str], name: str, model: str) -> int:
    """The column of ``name`` among ``variables`` (``-1`` for the time ``t``), or a UsageError."""
    if name == TIME:
        return -1
    if name not in variables:
        raise UsageError(
            f"'{name}' is not a state variable of {model} (state: {', '.join(variables)}, or t)"
        )
    return list(variables).index(name)


def _column(result: ReachResult, name: str) -> int:
    return axis_index(result.variables, name, result.model)


def draw(result: ReachResult, x: str, y: str, *, ax: Any = None, runs: Sequence[Run] = ()) -> Any:
    """Draw ``result`` on ``ax`` (a new figure's axes if ``None``); return the axes."""
    try:
        import matplotlib.pyplot as plt
        from matplotlib.collections import PolyCollection
    except ImportError:  # pragma: no cover - depends on the environment
        raise UsageError("plotting needs matplotlib: pip install 'hybrid[plot]'") from None
    ix, iy = _column(result, x), _column(result, y)

    def lo_hi(s: Any, i: int) -> tuple[float, float]:
        return (s.t[0], s.t[1]) if i < 0 else (float(s.lo[i]), float(s.hi[i]))

    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 4.8))
    boxes = []
    for s in result.sets:
        (x0, x1), (y0, y1) = lo_hi(s, ix), lo_hi(s, iy)
        boxes.append([(x0, y0), (x1, y0), (x1, y1), (x0, y1)])
    ax.add_collection(
        PolyCollection(boxes, facecolors="#9ecae1", edgecolors="#3182bd", linewidths=0.3, alpha=0.6)
    )
    ax.autoscale_view()
    if not runs and result.source is not None:
        from hybrid.simulation.engine import simulate

        # on a fine grid: drawn through its step points only, a run's straight chords
        # left the sets (the bouncing ball's 9 points), as if the sets missed it
        nominal = simulate(result.source, result.t_end, max_jumps=result.max_jumps,
                           dt=result.t_end / DRAWN_POINTS, handle_sigint=False)  # fmt: skip
        runs = [nominal]
    for run in runs:
        xs = run.t if ix < 0 else run.states[:, ix]
        ys = run.t if iy < 0 else run.states[:, iy]
        ax.plot(xs, ys, color="black", linewidth=0.8)
    for p in result.properties:
        if p.witness is not None and all(p.witness is not r for r in runs):
            run = p.witness
            xs = run.t if ix < 0 else run.states[:, ix]
            ys = run.t if iy < 0 else run.states[:, iy]
            ax.plot(xs, ys, color="#d62728", linewidth=0.9, label="witness")
    x_lim, y_lim = ax.get_xlim(), ax.get_ylim()
    view = [(x_lim[0], y_lim[0]), (x_lim[1], y_lim[0]), (x_lim[1], y_lim[1]), (x_lim[0], y_lim[1])]
    n = len(result.variables) + 1
    cols = [n - 1 if i < 0 else i for i in (ix, iy)]
    for p in result.properties:
        for case in p.condition:
            others = np.delete(case.mat, cols, axis=1)
            if np.any(others != 0.0):
                continue  # the case reads other variables: not a region of this plane
            planes = [
                ((float(r[cols[0]]), float(r[cols[1]])), float(v))
                for r, v in zip(case.mat, case.vec, strict=True)
            ]
            region = clip_polygon(view, planes)
            if len(region) >= 3:
                ax.fill(*zip(*region, strict=True), color="#d62728", alpha=0.25, linewidth=0)
    ax.set_xlim(x_lim)
    ax.set_ylim(y_lim)
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    verdict = result.verdict if result.properties else "no forbidden state to decide"
    ax.set_title(f"{result.model}: {len(result.sets)} sets, {verdict}")
    return ax
