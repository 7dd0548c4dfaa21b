"""Planar UVMS kinematics of dos Santos & De Pieri (IFAC 2011), pure math.

Modules: :mod:`~uvms_model.screws` (planar twists), :mod:`~uvms_model.chain` (forward
kinematics, network matrix, Davies' partition solve), :mod:`~uvms_model.indices` (gamma,
alpha, w_hat), :mod:`~uvms_model.functional_machine` (the FM), :mod:`~uvms_model.quintic`
(transition law) and :mod:`~uvms_model.paths` (mission paths).
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
    network_matrix,
    primary_indices,
    solve_partition,
    solve_q0,
    solve_state3,
)
from uvms_model.functional_machine import (
    FMUnits,
    functional_machine,
    functional_machine_clipped,
    functional_machine_units,
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
from uvms_model.quintic import Quintic, quintic_coefficients, transition_target
from uvms_model.screws import point_velocity, prismatic, revolute

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
    "functional_machine_clipped",
    "functional_machine_units",
    "gamma",
    "gamma_from_det",
    "gamma_max",
    "mission1_path",
    "mission2_path",
    "network_matrix",
    "point_velocity",
    "primary_indices",
    "prismatic",
    "q2_for_gamma",
    "quintic_coefficients",
    "revolute",
    "solve_partition",
    "solve_q0",
    "solve_state3",
    "transition_target",
    "w_hat",
]
