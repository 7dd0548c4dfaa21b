"""The comparison the paper never made: its strategy against the classical resolutions.

Every baseline is ``specs/uvms_baseline.yaml`` (same chain, path, tracking feedback,
vehicle heading and tool-heading law as the strategy) with one method of
:mod:`uvms_model.baselines`; the gains of methods 2-4 are swept with
:func:`hybrid.sweep`. The paper's strategy is :func:`uvms_model.missions.run_mission`.
Every run is recorded on a 10 ms grid and measured alike (:func:`measure`):

* ``min |gamma|`` and the smallest singular value of the whole vehicle-arm Jacobian
  (3 x 5, :func:`uvms_model.baselines.sigma_min`);
* the vehicle's rest time (speed below 1 mm/s) and its number of starts;
* a thruster-power proxy: drag power grows as ``|v|^3`` (quadratic drag times speed),
  so ``int |v|^3 dt``; a start from rest costs a spin-up, counted apart (the starts);
* ``int |v|^2 dt``, peak joint rate and acceleration (differences of the rates), the
  end effector's largest tracking error and the joints' range (largest ``|q|``).

Run ``python -m uvms_model.compare [OUT_DIR]``: prints the gain study and the table,
and writes ``compare.md`` and a figure per mission (``|gamma|`` and the vehicle's speed
of every method); ``make demo`` prints :func:`headline`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import hybrid
from uvms_model.baselines import sigma_min
from uvms_model.missions import MISSIONS, run_mission, specs_dir

__all__ = [
    "BASELINES",
    "HEADLINE",
    "MISSION_PARAMETERS",
    "Metrics",
    "baseline_run",
    "headline",
    "main",
    "measure",
    "write_figure",
]

MISSION_PARAMETERS: Mapping[str, Mapping[str, float]] = {
    "uvms_mission_1": {"turns": 1.0, "centre_dy": 0.5},
    "uvms_mission_2": {"turns": 1.5, "centre_dy": 0.0},
}
"""The baseline spec's parameters for each mission (as the mission files set them)."""

BASELINES: Mapping[str, tuple[int, str, Sequence[float]]] = {
    "arm only": (0, "", ()),
    "pseudoinverse": (1, "", ()),
    "weighted pseudoinverse": (2, "w_vehicle", (2.0, 4.0, 8.0)),
    "damped least squares": (3, "damping", (0.1, 0.2, 0.4)),
    "task priority + manipulability": (4, "k_null", (0.5, 1.0, 2.0)),
}
"""Each baseline: method code, the gain swept and its values."""

DT = 0.01
"""Recording grid, s."""
REST_SPEED = 1e-3
"""Below this speed the vehicle is at rest, m/s."""


@dataclass(frozen=True)
class Metrics:
    """One run, measured."""

    end: str
    min_gamma: float
    min_sigma: float
    rest_time: float
    starts: int
    drag_energy: float
    """``int |v|^3 dt``, m^3/s^2."""
    speed_energy: float
    """``int |v|^2 dt``, m^2/s."""
    peak_rate: float
    peak_acceleration: float
    max_tracking_error: float
    joint_range: float

    def row(self, label: str) -> str:
        return (
            f"| {label} | {self.end} | {self.min_gamma:.3f} | {self.min_sigma:.3f} "
            f"| {self.rest_time:.1f} | {self.starts} | {self.drag_energy:.4f} "
            f"| {self.speed_energy:.3f} | {self.peak_rate:.3f} | {self.peak_acceleration:.3f} "
            f"| {self.max_tracking_error * 1e3:.2g} | {self.joint_range:.2f} |"
        )


HEADER = (
    "| method | end | min abs(gamma) | min sigma(J) | vehicle at rest [s] | starts "
    "| int abs(v)^3 dt | int abs(v)^2 dt | peak abs(q') [rad/s] | peak abs(q'') [rad/s^2] "
    "| max tracking error [mm] | max abs(q) [rad] |\n|" + "---|" * 12
)


def measure(run: hybrid.Run, geometry: Sequence[float]) -> Metrics:
    """The metrics of one run (strategy or baseline), from its recorded samples.

    Parameters
    ----------
    run : hybrid.Run
        Recorded on a uniform grid.
    geometry : sequence of float
        ``(a1, a2, a3, base_x, base_y)``.

    Returns
    -------
    Metrics
        The run's measures.
    """
    t = run.t
    dt = np.diff(t)
    speed = np.hypot(run["x_rate"], run["y_rate"])
    mid = 0.5 * (speed[1:] + speed[:-1])
    moving = speed > REST_SPEED
    same = (dt > 0) & (run.j[1:] == run.j[:-1])
    rates = np.array([run[f"q{k}_rate"] for k in (1, 2, 3)])
    accelerations = np.abs(np.diff(rates, axis=1)[:, same] / dt[same])
    config = np.array([run[k] for k in ("x", "y", "phi", "q1", "q2", "q3")])
    sigmas = [sigma_min(*config[:, i], *geometry) for i in range(0, len(t), 10)]
    return Metrics(
        end=f"{run.termination.cause} at {run.termination.t:.1f} s",
        min_gamma=float(np.min(run["gamma"])),
        min_sigma=float(min(sigmas)),
        rest_time=float(np.sum(dt[~moving[:-1]])),
        starts=int(np.sum(moving[1:] & ~moving[:-1])),
        drag_energy=float(np.sum(mid**3 * dt)),
        speed_energy=float(np.sum(mid**2 * dt)),
        peak_rate=float(np.max(np.abs(rates))),
        peak_acceleration=float(np.max(accelerations)) if accelerations.size else 0.0,
        max_tracking_error=float(np.max(run["tracking_error"])),
        joint_range=float(max(np.max(np.abs(run[q])) for q in ("q1", "q2", "q3"))),
    )


def _baseline(mission: str, overrides: Mapping[str, float]) -> hybrid.Automaton:
    model = hybrid.load(
        specs_dir() / "uvms_baseline.yaml",
        parameters={**MISSION_PARAMETERS[mission], **overrides},
    )
    assert isinstance(model, hybrid.Automaton)
    return model


def baseline_run(
    mission: str, method: int, overrides: Mapping[str, float] | None = None, t_end: float = 60.0
) -> hybrid.Run:
    """Simulate one baseline on ``mission`` (rtol 1e-8, the 10 ms grid).

    Parameters
    ----------
    mission : str
        ``"uvms_mission_1"`` or ``"uvms_mission_2"``.
    method : int
        Method code of :data:`uvms_model.baselines.METHODS`.
    overrides : mapping, optional
        Gains (``w_vehicle``, ``damping``, ``k_null``).
    t_end : float
        End time, s.

    Returns
    -------
    hybrid.Run
        The run.
    """
    model = _baseline(mission, {"method": float(method), **(overrides or {})})
    return hybrid.simulate(model, t_end=t_end, rtol=1e-8, atol=1e-10, dt=DT, handle_sigint=False)


def _geometry(model: hybrid.Automaton) -> tuple[float, ...]:
    p = model.parameters
    return (p["a1"], p["a2"], p["a3"], p["base_x"], p["base_y"])


def gain_study(mission: str) -> list[str]:
    """Each swept gain's min |gamma|, min sigma and end, as :func:`hybrid.sweep` reports them."""
    lines = []
    for label, (code, gain, values) in BASELINES.items():
        if not gain:
            continue
        model = _baseline(mission, {"method": float(code)})
        table = hybrid.sweep(
            model, t_end=60.0, points=[{gain: v} for v in values],
            summaries=["min:gamma", "min:sigma_min", "max:tracking_error"],
            rtol=1e-7, atol=1e-9, dt=0.05,
        )  # fmt: skip
        for value, row in zip(values, table.rows, strict=True):
            lines.append(
                f"  {label:32s} {gain}={value:<5g} {row['cause']:15s} "
                f"min |gamma| {row['min:gamma']:.3f}  min sigma {row['min:sigma_min']:.3f}  "
                f"max error {row['max:tracking_error'] * 1e3:.2g} mm"
            )
    return lines


def comparison_table(mission: str) -> str:
    """The markdown table of ``mission``: the strategy, then every baseline and gain."""
    strategy = run_mission(mission, rtol=1e-8, atol=1e-10, dt=DT)
    geometry = _geometry(_baseline(mission, {}))
    lines = [HEADER, measure(strategy.run, geometry).row("the paper's strategy")]
    for label, (code, gain, values) in BASELINES.items():
        for value in values or (None,):
            overrides = {gain: value} if value is not None else {}
            run = baseline_run(mission, code, overrides)
            name = f"{label} ({gain} {value:g})" if value is not None else label
            lines.append(measure(run, geometry).row(name))
    return "\n".join(lines)


HEADLINE: Mapping[str, tuple[int, Mapping[str, float]]] = {
    "pseudoinverse": (1, {}),
    "task priority + manipulability (k_null 0.5)": (4, {"k_null": 0.5}),
}
"""The baselines of the demo's headline, beside the paper's strategy."""


def headline(mission: str = "uvms_mission_2") -> str:
    """The demo's headline: the strategy against two baselines on ``mission`` (a table)."""
    geometry = _geometry(_baseline(mission, {}))
    strategy = run_mission(mission, rtol=1e-8, atol=1e-10, dt=DT)
    lines = [HEADER, measure(strategy.run, geometry).row("the paper's strategy")]
    for label, (code, overrides) in HEADLINE.items():
        lines.append(measure(baseline_run(mission, code, overrides), geometry).row(label))
    return "\n".join(lines)


def write_figure(mission: str, path: Path) -> Path:
    """``|gamma|`` and the vehicle's speed over time: the strategy and every baseline (first gain)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from uvms_model.figures import save_png

    runs = {"the paper's strategy": run_mission(mission, rtol=1e-8, atol=1e-10, dt=DT).run}
    for label, (code, gain, values) in BASELINES.items():
        overrides = {gain: values[0]} if values else {}
        name = f"{label} ({gain} {values[0]:g})" if values else label
        runs[name] = baseline_run(mission, code, overrides)
    fig, (ax1, ax2) = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True)
    for name, run in runs.items():
        style = {"color": "k", "lw": 2} if name.startswith("the paper") else {"lw": 1}
        ax1.plot(run.t, run["gamma"], label=name, **style)
        ax2.plot(run.t, np.hypot(run["x_rate"], run["y_rate"]), **style)
    ax1.axhline(0.65, color="0.5", ls=":", lw=1)
    ax1.set_ylabel("|gamma|")
    ax1.legend(fontsize=7, ncol=2)
    ax2.set_ylabel("vehicle speed [m/s]")
    ax2.set_xlabel("t [s]")
    ax1.set_title(f"{mission}: the paper's strategy against the classical resolutions", fontsize=9)
    return save_png(fig, path)


def main(argv: list[str] | None = None) -> int:
    """Print the gain study and the tables of both missions; write ``compare.md``."""
    from uvms_model.figures import output_folder

    out = output_folder(argv)
    parts = []
    for mission in MISSIONS:
        print(f"== {mission}: gains (hybrid.sweep) ==")
        print("\n".join(gain_study(mission)))
        table = comparison_table(mission)
        print(f"== {mission} ==\n{table}\n")
        parts.append(f"### {mission}\n\n{table}\n")
        print(f"figure: {write_figure(mission, out / f'{mission}_compare.png')}")
    (out / "compare.md").write_text("\n".join(parts))
    print(f"written: {out / 'compare.md'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
