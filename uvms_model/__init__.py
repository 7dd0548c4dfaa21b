"""Planar UVMS kinematics of dos Santos & De Pieri (IFAC 2011), pure math.

Modules: :mod:`~uvms_model.screws` (planar twists), :mod:`~uvms_model.chain` (forward
kinematics, network matrix, Davies' partition solve of rates and accelerations),
:mod:`~uvms_model.indices` (gamma, alpha, w_hat), :mod:`~uvms_model.functional_machine`
(the FM), :mod:`~uvms_model.vehicle` (eq. 8 with a speed limit), :mod:`~uvms_model.quintic`
(transition law, eq. 9), :mod:`~uvms_model.paths` (mission paths),
:mod:`~uvms_model.metrics` (smoothness and effort measures); :mod:`~uvms_model.functions`
registers what the specs call; :mod:`~uvms_model.missions`,
:mod:`~uvms_model.robustness`, :mod:`~uvms_model.mechanism`, :mod:`~uvms_model.figures`
and :mod:`~uvms_model.demo` run and show the case study.
"""

from uvms_model.chain import (
    EE_SECONDARY,
    MAGNITUDE_NAMES,
    Q0_SECONDARY,
    STATE3_SECONDARY,
    Chain,
    ChainPose,
    det_ns,
    end_effector_pose,
    forward_kinematics,
    joint_point_rates,
    joint_points,
    network_column_rates,
    network_columns,
    network_matrix,
    network_matrix_rate,
    primary_indices,
    solve_partition,
    solve_partition_acceleration,
    solve_q0,
    solve_state3,
)
from uvms_model.functional_machine import (
    FMUnits,
    functional_machine,
    functional_machine_output,
    functional_machine_rate,
    functional_machine_units,
    smooth_ramp,
)
from uvms_model.indices import (
    THETA_SV,
    alpha,
    gamma,
    gamma_from_det,
    gamma_max,
    q2_for_gamma,
    w_hat,
)
from uvms_model.paths import DeformedCircle, PathState, mission1_path, mission2_path
from uvms_model.quintic import Quintic, quintic_coefficients, quintic_state, transition_target
from uvms_model.screws import point_velocity, prismatic, revolute
from uvms_model.vehicle import limited_velocity, limited_velocity_rate

__all__ = [
    "EE_SECONDARY",
    "MAGNITUDE_NAMES",
    "Q0_SECONDARY",
    "STATE3_SECONDARY",
    "THETA_SV",
    "Chain",
    "ChainPose",
    "DeformedCircle",
    "FMUnits",
    "PathState",
    "Quintic",
    "alpha",
    "det_ns",
    "end_effector_pose",
    "forward_kinematics",
    "functional_machine",
    "functional_machine_output",
    "functional_machine_rate",
    "functional_machine_units",
    "gamma",
    "gamma_from_det",
    "gamma_max",
    "joint_point_rates",
    "joint_points",
    "limited_velocity",
    "limited_velocity_rate",
    "mission1_path",
    "mission2_path",
    "network_column_rates",
    "network_columns",
    "network_matrix",
    "network_matrix_rate",
    "point_velocity",
    "primary_indices",
    "prismatic",
    "q2_for_gamma",
    "quintic_coefficients",
    "quintic_state",
    "revolute",
    "smooth_ramp",
    "solve_partition",
    "solve_partition_acceleration",
    "solve_q0",
    "solve_state3",
    "transition_target",
    "w_hat",
]
