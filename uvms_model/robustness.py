"""Robustness of the missions' outcomes to our parameter choices.

Two studies, both from the specs:

* :func:`one_at_a_time`: every parameter docs/uvms.md marks as ours
  (:data:`~uvms_model.missions.OWN_PARAMETERS`) at 0.9 and 1.1 times its value, and each
  initial joint angle moved by -0.1, -0.05, +0.05 and +0.1 rad, one at a time.
* :func:`robustness_map`: a grid over two parameters, the outcome of each point
  classified by :func:`classify`; :func:`write_map_figure` draws it.

Both are campaigns of :func:`hybrid.sweep` (:func:`_sweep_outcomes`): the points are
run in worker processes, each row read back as an :class:`Outcome` (the switches are
jumps of the automaton's three switching edges, ``min |gamma|`` and the top speed are
summaries on the 0.1 s grid, and ``dexterity`` is the robustness of mission 2's
requirement ``always: gamma >= 0.5``, the exact minimum of ``|gamma|`` less 0.5).

Run ``python -m uvms_model.robustness [OUT_DIR]`` to write the map of mission 2
(``uvms_robustness_map.png``) and print the one-at-a-time table.

Examples
--------
>>> classify(Outcome("uvms_mission_2", "t_end", 0.6, 0.25, epsilon=1, beta=1))
'paper'
>>> classify(Outcome("uvms_mission_2", "t_end", 0.6, 0.25, epsilon=1))
'no beta'
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import hybrid
from uvms_model.missions import (
    INITIAL_POSTURE,
    OWN_PARAMETERS,
    UVMS_EDGES,
    MissionResult,
    derived_start,
    run_mission,
    specs_dir,
)

__all__ = [
    "OUTCOME_DT",
    "POSTURE_STEPS",
    "Outcome",
    "RobustnessMap",
    "Variant",
    "classify",
    "main",
    "one_at_a_time",
    "outcome_of",
    "robustness_map",
    "summarise",
    "write_map_figure",
]

POSTURE_STEPS = (-0.1, -0.05, 0.05, 0.1)
"""Perturbations of each initial joint angle, rad (10% of an angle depends on its zero)."""

M1_MIN_GAMMA = 0.65
"""Mission 1 keeps the paper's outcome: no switch and min |gamma| above gamma_tol."""
M2_MIN_GAMMA = 0.5
"""Mission 2 keeps the paper's outcome: epsilon then beta, and min |gamma| above this."""
OUTCOME_DT = 0.1
"""Recording grid of :func:`outcome_of`, s."""


@dataclass(frozen=True)
class Outcome:
    """What one run of a mission did.

    The automaton's switches are counted per edge. Their order needs no record: beta
    leaves q1 only, which epsilon (from q0) and epsilon_again (from q2) enter, so
    ``epsilon == 1, beta == 1, epsilon_again == 0`` is the sequence epsilon, beta and
    nothing else.
    """

    mission: str
    cause: str
    min_abs_gamma: float
    max_vehicle_speed: float
    dexterity: float = math.nan
    """Robustness of mission 2's requirement ``always: gamma >= 0.5`` (NaN without it)."""
    epsilon: int = 0
    """Jumps q0 -> q1 (into kinematic state 3)."""
    beta: int = 0
    """Jumps q1 -> q2 (gamma back above the unit value)."""
    epsilon_again: int = 0
    """Jumps q2 -> q1 (kinematic state 3 entered again)."""

    @property
    def switches(self) -> int:
        """All changes of kinematic state."""
        return self.epsilon + self.beta + self.epsilon_again


def classify(outcome: Outcome) -> str:
    """``"paper"`` if the run has the paper's outcome for its mission, strictly, else why not.

    Mission 1 (paper: "gamma reaches values above gamma_tol, hence the functional
    machine is enough"): the run reaches its end without a switch and
    ``min |gamma| > gamma_tol = 0.65``. Mission 2 (paper: gamma falls below gamma_tol,
    the switch to kinematic state 3, "where the vehicle is secondary until gamma takes
    the unit value again"): the run reaches its end after exactly one epsilon and then
    one beta (back at the unit value before the end), no re-entry into kinematic state
    3, and ``min |gamma| > 0.5``. A run that ends still in kinematic state 3 (epsilon
    without beta) is not the paper's outcome.

    Parameters
    ----------
    outcome : Outcome
        The run.

    Returns
    -------
    str
        ``"paper"``, ``"ended <cause>"``, ``"switched"`` (mission 1), ``"no switch"``,
        ``"no beta"``, ``"re-entered"`` (mission 2) or ``"low gamma"``.

    Examples
    --------
    >>> classify(Outcome("uvms_mission_1", "t_end", 0.79, 0.2))
    'paper'
    >>> classify(Outcome("uvms_mission_2", "t_end", 0.57, 0.25, epsilon=1, beta=1,
    ...                  epsilon_again=1))
    're-entered'
    """
    if outcome.cause != "t_end":
        return f"ended {outcome.cause}"
    if outcome.mission.endswith("1"):
        if outcome.switches:
            return "switched"
        return "paper" if outcome.min_abs_gamma > M1_MIN_GAMMA else "low gamma"
    if outcome.switches == 0:
        return "no switch"
    if outcome.beta == 0:
        return "no beta"
    if (outcome.epsilon, outcome.beta, outcome.epsilon_again) != (1, 1, 0):
        return "re-entered"
    return "paper" if outcome.min_abs_gamma > M2_MIN_GAMMA else "low gamma"


def outcome_of(
    mission: str,
    parameters: Mapping[str, float] | None = None,
    initial: Mapping[str, float] | None = None,
    *,
    rtol: float = 1e-7,
    atol: float = 1e-9,
    dt: float | None = OUTCOME_DT,
) -> Outcome:
    """Simulate ``mission`` with overrides and summarise it.

    Parameters
    ----------
    mission : str
        ``"uvms_mission_1"`` or ``"uvms_mission_2"``.
    parameters, initial : mapping, optional
        Overrides (see :func:`uvms_model.missions.run_mission`).
    rtol, atol : float
        Solver tolerances.
    dt : float, optional
        Recording grid, s; the smallest ``|gamma|`` is read on it (solver steps alone
        can step over the bottom of a dip).

    Returns
    -------
    Outcome
        The run's end, switches, smallest ``|gamma|`` and top vehicle speed.
    """
    result = run_mission(mission, parameters, initial=initial, rtol=rtol, atol=atol, dt=dt)
    return summarise(result)


def summarise(result: MissionResult) -> Outcome:
    """The :class:`Outcome` of a simulated mission.

    Parameters
    ----------
    result : MissionResult
        A run of :func:`uvms_model.missions.run_mission`.

    Returns
    -------
    Outcome
        Its end, smallest ``|gamma|`` (on its recording grid), top vehicle speed and
        switches per edge.
    """
    edges = [edge for _, edge in result.switches]
    return Outcome(
        result.name,
        result.run.termination.cause,
        result.min_abs_gamma,
        result.max_vehicle_speed,
        epsilon=edges.count("epsilon"),
        beta=edges.count("beta"),
        epsilon_again=edges.count("epsilon_again"),
    )


@dataclass(frozen=True)
class Variant:
    """One perturbed run of :func:`one_at_a_time`."""

    name: str
    """``"uvms.v_max x0.9"``, ``"q2 -0.1 rad"``, ..."""
    outcome: Outcome

    @property
    def verdict(self) -> str:
        return classify(self.outcome)


def _nominal(model: hybrid.Automaton | hybrid.System, qualified: str) -> float:
    comp, _, name = qualified.rpartition(".")
    if isinstance(model, hybrid.Automaton):
        return float(model.parameters[name])
    for component in model.components:
        if component.name == comp:
            return float(component.automaton.parameters[name])
    raise KeyError(qualified)


def _initial(model: hybrid.Automaton | hybrid.System, state: str) -> float:
    return float(dict(zip(model.state_names, model.initial_vector(), strict=True))[state])


def one_at_a_time(
    mission: str,
    parameters: Sequence[str] = OWN_PARAMETERS,
    posture: Sequence[str] = INITIAL_POSTURE,
    *,
    factor: float = 0.1,
    steps: Sequence[float] = POSTURE_STEPS,
    base: Mapping[str, float] | None = None,
    rtol: float = 1e-7,
    atol: float = 1e-9,
    workers: int = 1,
) -> list[Variant]:
    """Each own parameter at ``1 -/+ factor`` times its value, each joint moved by each step.

    Parameters
    ----------
    mission : str
        Mission spec stem.
    parameters : sequence of str
        Qualified parameter names to perturb.
    posture : sequence of str
        Initial joint angles to perturb by each of ``steps``.
    factor : float
        Relative perturbation of the parameters.
    steps : sequence of float
        Steps of each initial joint angle, rad.
    base : mapping, optional
        Parameter overrides every variant starts from (default: the specs' values).
    rtol, atol : float
        Solver tolerances.
    workers : int
        Processes to run the variants in (1: in this process).

    Returns
    -------
    list of Variant
        Two per parameter and one per step of each joint, in that order.
    """
    base = dict(base or {})
    model = hybrid.load(specs_dir() / f"{mission}.yaml", parameters=base)
    nominal = {name: _nominal(model, name) for name in parameters}
    nominal.update({f"init.{q}": _initial(model, q) for q in posture})
    labels: list[str] = []
    points: list[dict[str, float]] = []
    for name in parameters:
        for f in (1.0 - factor, 1.0 + factor):
            labels.append(f"{name} x{f:g}")
            points.append({**nominal, name: nominal[name] * f})
    for state in posture:
        for step in steps:
            labels.append(f"{state} {step:+g} rad")
            points.append({**nominal, f"init.{state}": nominal[f"init.{state}"] + step})
    # the path starts at the end effector of the initial posture: its three parameters
    # follow a posture step (as run_mission does)
    for point in points:
        initial = {k[len("init.") :]: v for k, v in point.items() if k.startswith("init.")}
        point.update(derived_start(model, initial))
    outcomes = _sweep_outcomes(model, mission, points, rtol, atol, workers)
    return [Variant(label, o) for label, o in zip(labels, outcomes, strict=True)]


@dataclass(frozen=True)
class RobustnessMap:
    """Outcomes of a mission over a grid of two parameters."""

    mission: str
    x_name: str
    x_values: tuple[float, ...]
    y_name: str
    y_values: tuple[float, ...]
    outcomes: tuple[tuple[Outcome, ...], ...]
    """``outcomes[i][j]`` at ``(x_values[j], y_values[i])``."""
    nominal: tuple[float, float]


def robustness_map(
    mission: str,
    x_name: str,
    x_values: Iterable[float],
    y_name: str,
    y_values: Iterable[float],
    *,
    rtol: float = 1e-7,
    atol: float = 1e-9,
    workers: int = 1,
) -> RobustnessMap:
    """Run ``mission`` on the grid ``x_values x y_values`` of two qualified parameters.

    Parameters
    ----------
    mission : str
        Mission spec stem.
    x_name, y_name : str
        Qualified parameter names (``"uvms.v_max"``, ``"polarization.theta_accel"``).
    x_values, y_values : iterable of float
        Grid values.
    rtol, atol : float
        Solver tolerances.
    workers : int
        Processes to run the grid in.

    Returns
    -------
    RobustnessMap
        The grid of outcomes and the nominal point.
    """
    xs, ys = tuple(float(v) for v in x_values), tuple(float(v) for v in y_values)
    model = hybrid.load(specs_dir() / f"{mission}.yaml")
    nominal = (_nominal(model, x_name), _nominal(model, y_name))
    points = [{y_name: y, x_name: x} for y in ys for x in xs]  # y slowest: rows of the map
    flat = _sweep_outcomes(model, mission, points, rtol, atol, workers)
    rows = tuple(tuple(flat[i * len(xs) : (i + 1) * len(xs)]) for i in range(len(ys)))
    return RobustnessMap(mission, x_name, xs, y_name, ys, rows, nominal)


def _sweep_outcomes(
    model: hybrid.Automaton | hybrid.System,
    mission: str,
    points: Sequence[Mapping[str, float]],
    rtol: float,
    atol: float,
    workers: int,
) -> list[Outcome]:
    """Run ``points`` of ``mission`` as one :func:`hybrid.sweep`; an outcome per point, in order."""
    switching = [f"uvms.{edge}" for edge in UVMS_EDGES]
    table = hybrid.sweep(
        model,
        t_end=60.0,
        points=points,
        summaries=[*(f"jumps:{e}" for e in switching), "min:gamma", "max:vehicle_speed"],
        rtol=rtol,
        atol=atol,
        dt=OUTCOME_DT,
        workers=workers if workers > 1 else 0,
    )
    return [_outcome(mission, row, switching) for row in table.rows]


def _outcome(mission: str, row: Mapping[str, Any], switching: Sequence[str]) -> Outcome:
    if row["cause"] in ("error", "timeout"):
        raise RuntimeError(f"{mission} at {row}: {row['message']}")
    robustness = row.get("dexterity.robustness")
    counts = {e.rpartition(".")[2]: int(row[f"jumps:{e}"]) for e in switching}
    return Outcome(
        mission,
        str(row["cause"]),
        float(row["min:gamma"]),
        float(row["max:vehicle_speed"]),
        math.nan if robustness is None else float(robustness),
        **counts,
    )


def write_map_figure(result: RobustnessMap, path: Path) -> Path:
    """Draw ``result``: min |gamma| as colour, the outcome class as a mark per point.

    Parameters
    ----------
    result : RobustnessMap
        The grid.
    path : Path
        PNG file to write.

    Returns
    -------
    Path
        ``path``.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    from uvms_model.figures import save_png

    gamma = np.array([[o.min_abs_gamma for o in row] for row in result.outcomes])
    fig, ax = plt.subplots(figsize=(7.5, 5.5))
    mesh = ax.pcolormesh(
        result.x_values, result.y_values, gamma, shading="nearest", cmap="viridis",
        vmin=0.0, vmax=1.0,
    )  # fmt: skip
    fig.colorbar(mesh, ax=ax, label="min |gamma|")
    for i, y in enumerate(result.y_values):
        for j, x in enumerate(result.x_values):
            o = result.outcomes[i][j]
            ok = classify(o) == "paper"
            ax.text(
                x, y, str(o.switches) if o.cause == "t_end" else "x",
                ha="center", va="center", fontsize=8,
                color="white" if ok else "red", fontweight="normal" if ok else "bold",
            )  # fmt: skip
    x0, y0 = result.nominal
    box_x = [0.9 * x0, 1.1 * x0, 1.1 * x0, 0.9 * x0, 0.9 * x0]
    box_y = [0.9 * y0, 0.9 * y0, 1.1 * y0, 1.1 * y0, 0.9 * y0]
    ax.plot(box_x, box_y, color="w", ls="--", lw=1.5)
    ax.plot([x0], [y0], marker="*", color="w", ms=14, mec="k")
    ax.set_xlabel(result.x_name)
    ax.set_ylabel(result.y_name)
    ax.set_title(
        f"{result.mission}: switches per run; white: the paper's outcome (strict),\n"
        "red: not (1: epsilon without beta; x: ended early); star: ours; box: +-10%",
        fontsize=9,
    )
    return save_png(fig, path)


def main(argv: list[str] | None = None) -> int:
    """Write the robustness map of mission 2 and print the one-at-a-time table."""
    from uvms_model.figures import output_folder

    out = output_folder(argv)
    for mission in ("uvms_mission_1", "uvms_mission_2"):
        variants = one_at_a_time(mission, workers=2)
        kept = sum(v.verdict == "paper" for v in variants)
        print(f"{mission}: {kept} of {len(variants)} one-at-a-time variants keep the outcome")
        for v in variants:
            o = v.outcome
            print(
                f"  {v.name:34s} {v.verdict:12s} switches {o.switches}  "
                f"min |gamma| {o.min_abs_gamma:.3f}  max speed {o.max_vehicle_speed:.3f}"
            )
    grid = robustness_map(
        "uvms_mission_2",
        "uvms.v_max", [round(0.21 + 0.015 * k, 3) for k in range(13)],
        "polarization.theta_accel", [round(0.65 + 0.05 * k, 2) for k in range(13)],
        workers=2,
    )  # fmt: skip
    path = write_map_figure(grid, out / "uvms_robustness_map.png")
    verdicts = [classify(o) for row in grid.outcomes for o in row]
    counts = ", ".join(f"{v} {verdicts.count(v)}" for v in sorted(set(verdicts)))
    print(f"map of {grid.mission}: {counts} (of {len(verdicts)})")
    print(f"figure: {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
