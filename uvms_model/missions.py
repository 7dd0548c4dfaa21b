"""Run the paper's two missions (and their variants) from the specs, and measure them.

Every number the demo prints, the docs tabulate and the tests assert comes from
:func:`run_mission`: the automaton's switches, the smallest ``|gamma|``, the tracking
error, the steps of the accelerations at the jumps (continuity), the peak joint and
vehicle accelerations (against our budget), the vehicle's top speed, travel time and
energy.

The end-effector path starts where the end effector is: ``ee_x0``, ``ee_y0`` and
``ee_heading`` are derived from the geometry and the initial posture, so a variant
that changes either (a link length, an initial joint angle) is run with a consistent
start (:func:`derived_start`).

Examples
--------
>>> result = run_mission("uvms_mission_1", rtol=1e-6, atol=1e-9)
>>> result.run.termination.cause, result.visited
('t_end', [('q0', 0.0)])
"""

from __future__ import annotations

import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

import hybrid
from uvms_model.chain import joint_points
from uvms_model.metrics import (
    jump_steps,
    vehicle_energy,
    vehicle_travel_time,
    windowed_change,
)

__all__ = [
    "ABLATIONS",
    "ACCELERATION_SIGNALS",
    "ALWAYS_ON",
    "INITIAL_POSTURE",
    "JOINT_ACCELERATION_BUDGET",
    "MISSIONS",
    "OWN_PARAMETERS",
    "RATE_SIGNALS",
    "SMOOTHNESS_WINDOW",
    "VEHICLE_ACCELERATION_BUDGET",
    "MissionResult",
    "derived_start",
    "run_mission",
    "specs_dir",
]

MISSIONS = ("uvms_mission_1", "uvms_mission_2")
RATE_SIGNALS = ("x_rate", "y_rate", "phid", "q1_rate", "q2_rate", "q3_rate")
"""Joint and vehicle rates whose smoothness is measured (rad/s, m/s)."""
ACCELERATION_SIGNALS = ("x_acc", "y_acc", "phidd", "q1_acc", "q2_acc", "q3_acc")
"""Their accelerations (the specs compute them in closed form)."""
SMOOTHNESS_WINDOW = 0.02
"""Window of :attr:`MissionResult.rate_change`, s."""
JOINT_ACCELERATION_BUDGET = 1.0
"""Our actuator budget for every joint, rad/s^2 (not the paper's: it gives no limits)."""
VEHICLE_ACCELERATION_BUDGET = 0.5
"""Our thruster budget for the vehicle's acceleration ``|(x'', y'')|``, m/s^2."""
UVMS_EDGES = ("epsilon", "beta", "epsilon_again")
"""The automaton's switches of kinematic state."""

ABLATIONS: Mapping[str, Mapping[str, float]] = {
    "both (the paper's strategy)": {},
    "FM only": {"uvms.switching": 0.0},
    "automaton only": {"uvms.fm_on": 0.0},
    "no strategy": {"uvms.fm_on": 0.0, "uvms.switching": 0.0},
}
"""Ablations: parameter overrides of the same specs."""

ALWAYS_ON: Mapping[str, float] = {"uvms.always_on": 1.0, "uvms.switching": 0.0}
"""The baseline of section 3.2: the vehicle always moves, ``V = alpha E`` (s = 1)."""

OWN_PARAMETERS: tuple[str, ...] = (
    "uvms.a1",
    "uvms.a2",
    "uvms.a3",
    "uvms.base_x",
    "uvms.epsilon_path",
    "uvms.k_track",
    "uvms.v_max",
    "uvms.k_heading",
    "uvms.heading_follow",
    "uvms.wrist_gain",
    "uvms.wrist_rest",
    "uvms.T_recover",
    "uvms.T_rest",
    "uvms.gamma_min",
    "uvms.fm_ramp",
    "polarization.theta_accel",
    "polarization.theta_decel",
    "polarization.T_pol",
)
"""The numeric parameters docs/uvms.md marks as ours (zero-valued ones excluded)."""
INITIAL_POSTURE: tuple[str, ...] = ("q1", "q2", "q3")
"""Initial joint angles: ours too (the paper gives no initial conditions)."""


def specs_dir() -> Path:
    """The repository's ``specs/`` folder, where the missions' specs are.

    The case study is run from a checkout: this is ``specs/`` beside the package's
    folder, or, when the package is installed elsewhere (``pip install ./uvms_model``),
    ``specs/`` of the current directory. The specs are not shipped in the package.
    """
    beside = Path(__file__).resolve().parent.parent / "specs"
    if (beside / "uvms_singularity.yaml").is_file():
        return beside
    return Path.cwd() / "specs"


def _uvms_parameters(model: hybrid.Automaton | hybrid.System) -> dict[str, float]:
    if isinstance(model, hybrid.Automaton):
        return dict(model.parameters)
    for component in model.components:
        if "theta_sv" in component.automaton.parameters:
            return dict(component.automaton.parameters)
    raise ValueError("no UVMS component in the model")


def _uvms_prefix(model: hybrid.Automaton | hybrid.System) -> str:
    if isinstance(model, hybrid.Automaton):
        return ""
    for component in model.components:
        if "theta_sv" in component.automaton.parameters:
            return f"{component.name}."
    raise ValueError("no UVMS component in the model")


def _parameter(model: hybrid.Automaton | hybrid.System, qualified: str) -> float:
    return _uvms_parameters(model)[qualified.rpartition(".")[2]]


def derived_start(
    model: hybrid.Automaton | hybrid.System, initial: Mapping[str, float] | None = None
) -> dict[str, float]:
    """``ee_x0``, ``ee_y0``, ``ee_heading``: the end-effector pose of the initial state.

    Parameters
    ----------
    model : Automaton or System
        A loaded UVMS model (its geometry parameters are used).
    initial : mapping, optional
        Initial values overriding the spec's (``x``, ``y``, ``phi``, ``q1``, ...).

    Returns
    -------
    dict
        The three path-start parameters, qualified as the model needs them.
    """
    p = _uvms_parameters(model)
    x0 = dict(zip(model.state_names, model.initial_vector(), strict=True))
    x0.update(initial or {})
    *_, ex, ey, phie = joint_points(
        x0["x"], x0["y"], x0["phi"], x0["q1"], x0["q2"], x0["q3"],
        p["a1"], p["a2"], p["a3"], p["base_x"], p["base_y"],
    )  # fmt: skip
    prefix = _uvms_prefix(model)
    return {f"{prefix}ee_x0": ex, f"{prefix}ee_y0": ey, f"{prefix}ee_heading": phie}


@dataclass
class MissionResult:
    """A simulated mission and its measures."""

    name: str
    model: hybrid.Automaton | hybrid.System
    """The simulated model, parameters as overridden."""
    run: hybrid.Run
    wall_time: float
    visited: list[tuple[str, float]]
    """``(location of the uvms automaton, first entry time)``, in order."""
    switches: list[tuple[float, str]] = field(default_factory=list)
    """``(t, edge)`` of every jump of the uvms automaton (its switches of kinematic state)."""

    @property
    def real_time_factor(self) -> float:
        return float(self.run.t[-1] - self.run.t[0]) / self.wall_time

    @cached_property
    def min_abs_gamma(self) -> float:
        """Smallest ``|gamma|`` over the run (the paper's index is an absolute rate)."""
        return float(np.min(np.abs(self.run["gamma"])))

    @cached_property
    def max_tracking_error(self) -> float:
        return float(np.max(self.run["tracking_error"]))

    @cached_property
    def max_vehicle_speed(self) -> float:
        return float(np.max(self.run["vehicle_speed"]))

    @cached_property
    def rate_change(self) -> tuple[float, str]:
        """Largest change of any rate within :data:`SMOOTHNESS_WINDOW`, and which rate."""
        return max(
            (windowed_change(self.run.t, self.run[c], SMOOTHNESS_WINDOW), c) for c in RATE_SIGNALS
        )

    @cached_property
    def peak_joint_acceleration(self) -> tuple[float, str]:
        """Largest ``|q''|`` of any joint over the run (closed form, on the recording grid)."""
        return max((float(np.max(np.abs(self.run[f"{q}_acc"]))), q) for q in ("q1", "q2", "q3"))

    @cached_property
    def peak_vehicle_acceleration(self) -> float:
        """Largest ``|(x'', y'')|`` of the vehicle over the run, m/s^2."""
        return float(np.max(np.hypot(self.run["x_acc"], self.run["y_acc"])))

    @cached_property
    def within_budget(self) -> bool:
        """Both peaks within :data:`JOINT_ACCELERATION_BUDGET` and the vehicle's budget."""
        return (
            self.peak_joint_acceleration[0] <= JOINT_ACCELERATION_BUDGET
            and self.peak_vehicle_acceleration <= VEHICLE_ACCELERATION_BUDGET
        )

    @cached_property
    def acceleration_steps(self) -> dict[str, float]:
        """Largest step of any acceleration across the jumps, per edge (unqualified name)."""
        steps: dict[str, float] = {}
        for c in ACCELERATION_SIGNALS:
            at_jumps = jump_steps(self.run.t, self.run.j, self.run[c])
            for (_, step), jump in zip(at_jumps, self.run.jumps, strict=True):
                edge = jump.edge.split(".")[-1]
                steps[edge] = max(steps.get(edge, 0.0), step)
        return steps

    @cached_property
    def switch_acceleration_step(self) -> float:
        """Largest acceleration step at the automaton's switches (0 if none)."""
        return max((v for k, v in self.acceleration_steps.items() if k in UVMS_EDGES), default=0.0)

    @cached_property
    def jump_acceleration_step(self) -> float:
        """Largest acceleration step at any jump, switches and polarization alike (0 if none)."""
        return max(self.acceleration_steps.values(), default=0.0)

    @cached_property
    def vehicle_energy(self) -> float:
        """``int |v|^2 dt`` of the vehicle, m^2/s."""
        return vehicle_energy(self.run.t, self.run["x_rate"], self.run["y_rate"])

    @cached_property
    def vehicle_travel_time(self) -> float:
        """Time with the vehicle faster than 1 mm/s, s."""
        return vehicle_travel_time(self.run.t, self.run["vehicle_speed"])

    def summary(self) -> str:
        """The one-screen summary the demo prints."""
        term = self.run.termination
        acc, joint = self.peak_joint_acceleration
        lines = [
            f"{self.name}: {term.cause} at t={term.t:.2f} s, {len(self.run.jumps)} jumps, "
            f"wall {self.wall_time:.2f} s ({self.real_time_factor:.0f}x real time)",
            "  uvms locations entered: "
            + ", ".join(f"{loc} at {t:.2f} s" for loc, t in self.visited),
            f"  switches {len(self.switches)}   min |gamma| {self.min_abs_gamma:.3f}   "
            f"max end-effector error {self.max_tracking_error * 1e3:.2e} mm",
            f"  continuity: largest acceleration step at a jump {self.jump_acceleration_step:.1e}"
            f" (at a switch {self.switch_acceleration_step:.1e})",
            f"  budget: peak |q''| {acc:.3f} rad/s^2 ({joint}) of {JOINT_ACCELERATION_BUDGET:g}, "
            f"peak |v'| {self.peak_vehicle_acceleration:.3f} m/s^2 of "
            f"{VEHICLE_ACCELERATION_BUDGET:g}: {'within' if self.within_budget else 'OVER'}",
            f"  vehicle: max speed {self.max_vehicle_speed:.3f} m/s, moving "
            f"{self.vehicle_travel_time:.1f} s, energy {self.vehicle_energy:.3f} m^2/s",
        ]
        return "\n".join(lines)


def run_mission(
    name: str,
    parameters: Mapping[str, float] | None = None,
    *,
    initial: Mapping[str, float] | None = None,
    rtol: float = 1e-8,
    atol: float = 1e-10,
    dt: float | None = None,
) -> MissionResult:
    """Load ``specs/<name>.yaml``, simulate 60 s and measure the result.

    Parameters
    ----------
    name : str
        Spec file stem, e.g. ``"uvms_mission_2"``.
    parameters : mapping, optional
        Parameter overrides (qualified in a system, e.g. ``"uvms.v_max"``).
    initial : mapping, optional
        Initial-state overrides (``"q2"``, ...); the path start follows them.
    rtol, atol : float
        Solver tolerances.
    dt : float, optional
        Record on this uniform grid (1e-3 for the smoothness figures).

    Returns
    -------
    MissionResult
        The run and its measures.
    """
    path = specs_dir() / f"{name}.yaml"
    model = hybrid.load(path, parameters=parameters)
    start = derived_start(model, initial)
    if any(abs(v - _parameter(model, k)) > 1e-12 for k, v in start.items()):
        model = hybrid.load(path, parameters={**(parameters or {}), **start})
    t0 = time.perf_counter()
    run = hybrid.simulate(
        model, t_end=60.0, rtol=rtol, atol=atol, dt=dt, initial=initial, handle_sigint=False
    )
    wall = time.perf_counter() - t0
    uvms_loc = [loc.split("|")[0].split(".")[-1] for loc in run.location]
    visited: list[tuple[str, float]] = []
    for i, loc in enumerate(uvms_loc):
        if i == 0 or loc != uvms_loc[i - 1]:
            visited.append((loc, float(run.t[i])))
    switches = [
        (float(j.t), j.edge.split(".")[-1])
        for j in run.jumps
        if j.edge.split(".")[-1] in UVMS_EDGES and not j.edge.startswith("polarization")
    ]
    return MissionResult(name, model, run, wall, visited, switches)
