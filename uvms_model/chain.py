r"""Planar UVMS kinematic chain, network matrix and Davies' partition solve.

Geometry (world frame, :math:`e(t) = (\cos t, \sin t)`, :math:`Rot` the planar rotation):

.. math::

    P_0 = (x, y),\quad P_1 = P_0 + Rot(\phi)\, b,\quad
    t_1 = \phi + q_1,\ t_2 = t_1 + q_2,\ t_3 = t_2 + q_3,

    P_2 = P_1 + a_1 e(t_1),\quad P_3 = P_2 + a_2 e(t_2),\quad E = P_3 + a_3 e(t_3),

    (x_e, y_e) = E,\quad \phi_e = t_3.

One circuit, nine joints: vehicle as a virtual P-P-R chain :math:`(x, y, \phi)`, the arm's
revolutes :math:`(q_1, q_2, q_3)` and the virtual closing chain :math:`(x_e, y_e, \phi_e)`
(the paper's PPPS reduced to P-P-R in the plane), counted against the loop:

.. math::

    N = [\$_x\ \$_y\ \$_\phi\ \$_{q1}\ \$_{q2}\ \$_{q3}\ -\$_{xe}\ -\$_{ye}\ -\$_{\phi e}]
    \in \mathbb{R}^{3\times 9},

    \$_x = \$_{xe} = [0,1,0],\ \$_y = \$_{ye} = [0,0,1],\ \$_\phi = \$_R(P_0),\
    \$_{qk} = \$_R(P_k),\ \$_{\phi e} = \$_R(E).

Magnitudes :math:`\Psi = [\dot x, \dot y, \dot\phi, \dot q_1, \dot q_2, \dot q_3, \dot x_e,
\dot y_e, \dot\phi_e]` satisfy :math:`N\Psi = 0` (Kirchhoff circulation law). With three
secondary (unknown) magnitudes :math:`\Psi_s` and six primary (known) :math:`\Psi_p`:

.. math::

    N_s \Psi_s = -N_p \Psi_p,\qquad \Psi_s = -N_s^{-1} N_p \Psi_p.

Named partitions and their determinants (secondary columns in the order listed):

* location q0, secondary :math:`(q_1, q_2, q_3)`:
  :math:`\det N_s = (P_2 - P_1)\times(P_3 - P_1) = a_1 a_2 \sin q_2`;
* kinematic state 3 (location q1), secondary :math:`(x, y, q_2)`:
  :math:`\det N_s = \det[[0,0,1],[1,0,P_{2y}],[0,1,-P_{2x}]] = +1`;
* forward kinematics, secondary :math:`(x_e, y_e, \phi_e)`: :math:`\det N_s = -1`.

Accelerations (second order): differentiating :math:`N\Psi = 0` along the motion,

.. math::

    N\dot\Psi + \dot N\Psi = 0,\qquad
    N_s \dot\Psi_s = -(N_p \dot\Psi_p + \dot N \Psi),

where the column of a revolute joint through a point moving at :math:`\dot P` changes at
:math:`\dot\$_R(P) = [0, \dot P_y, -\dot P_x]` and prismatic columns are constant. The
same :math:`N_s` is inverted, so the accelerations of the secondary magnitudes are as
well defined as their rates.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from uvms_model.screws import Twist, prismatic, revolute

__all__ = [
    "EE_SECONDARY",
    "MAGNITUDE_NAMES",
    "PHI",
    "PHIE",
    "Q0_SECONDARY",
    "Q1",
    "Q2",
    "Q3",
    "STATE3_SECONDARY",
    "XE",
    "YE",
    "Chain",
    "ChainPose",
    "Config",
    "Vector",
    "X",
    "Y",
    "det_ns",
    "end_effector_pose",
    "forward_kinematics",
    "joint_point_rates",
    "joint_points",
    "network_column_rates",
    "network_columns",
    "network_matrix",
    "network_matrix_rate",
    "primary_indices",
    "solve_partition",
    "solve_partition_acceleration",
    "solve_q0",
    "solve_state3",
]

FloatArray = npt.NDArray[np.float64]
Config = Sequence[float] | FloatArray
"""Configuration ``(x, y, phi, q1, q2, q3)``."""
Vector = Sequence[float] | FloatArray
"""A short vector of floats (rates), list, tuple or array."""

X, Y, PHI, Q1, Q2, Q3, XE, YE, PHIE = range(9)
MAGNITUDE_NAMES: tuple[str, ...] = ("x", "y", "phi", "q1", "q2", "q3", "xe", "ye", "phie")

Q0_SECONDARY: tuple[int, int, int] = (Q1, Q2, Q3)
"""Secondary magnitudes of location q0 (arm joints); primary: x, y, phi, xe, ye, phie."""
STATE3_SECONDARY: tuple[int, int, int] = (X, Y, Q2)
"""Secondary magnitudes of kinematic state 3 (location q1); primary: phi, q1, q3, xe, ye, phie."""
EE_SECONDARY: tuple[int, int, int] = (XE, YE, PHIE)
"""Secondary magnitudes of forward kinematics (end-effector twist from joint rates)."""

_X_AXIS = prismatic((1.0, 0.0))
_Y_AXIS = prismatic((0.0, 1.0))
_MINUS_X_AXIS: Twist = (-_X_AXIS[0], -_X_AXIS[1], -_X_AXIS[2])
_MINUS_Y_AXIS: Twist = (-_Y_AXIS[0], -_Y_AXIS[1], -_Y_AXIS[2])


@dataclass(frozen=True)
class Chain:
    """Geometry of the planar UVMS (all values our choice; the paper gives none).

    Parameters
    ----------
    a1, a2, a3 : float
        Link lengths in m (defaults 1.0, 1.0, 0.25: a 2 m arm with a short wrist).
    b : tuple of float
        Arm base offset from the vehicle point P0 in the vehicle frame, m
        (default (0.5, 0.0): mounted on the fore-aft axis, at the bow).
    """

    a1: float = 1.0
    a2: float = 1.0
    a3: float = 0.25
    b: tuple[float, float] = (0.5, 0.0)

    def __post_init__(self) -> None:
        if min(self.a1, self.a2, self.a3) <= 0.0:
            raise ValueError("link lengths a1, a2, a3 must be positive")
        if len(self.b) != 2:
            raise ValueError("arm base offset b must be a 2-vector")


class ChainPose(NamedTuple):
    """Joint points and end-effector pose from :func:`forward_kinematics`."""

    p0: tuple[float, float]
    p1: tuple[float, float]
    p2: tuple[float, float]
    p3: tuple[float, float]
    e: tuple[float, float]
    xe: float
    ye: float
    phie: float


def _unpack(config: Config) -> tuple[float, float, float, float, float, float]:
    if len(config) != 6:
        raise ValueError("config must be (x, y, phi, q1, q2, q3)")
    x, y, phi, q1, q2, q3 = (float(v) for v in config)
    return x, y, phi, q1, q2, q3


def joint_points(
    x: float,
    y: float,
    phi: float,
    q1: float,
    q2: float,
    q3: float,
    a1: float,
    a2: float,
    a3: float,
    bx: float,
    by: float,
) -> tuple[float, float, float, float, float, float, float, float, float]:
    """Forward kinematics on scalars: the one implementation of the chain's geometry.

    :func:`forward_kinematics` wraps it for a :class:`Chain`; the functions the specs
    call (:mod:`uvms_model.functions`) use it directly, at every solver stage.

    Parameters
    ----------
    x, y, phi : float
        Vehicle point P0 and heading.
    q1, q2, q3 : float
        Arm joint angles, rad.
    a1, a2, a3 : float
        Link lengths, m.
    bx, by : float
        Arm base offset in the vehicle frame, m.

    Returns
    -------
    tuple of float
        ``(p1x, p1y, p2x, p2y, p3x, p3y, ex, ey, phie)`` with ``phie = phi + q1 + q2 + q3``.

    Examples
    --------
    >>> p = joint_points(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 0.25, 0.5, 0.0)
    >>> [round(v, 12) for v in p]
    [0.5, 0.0, 1.5, 0.0, 2.5, 0.0, 2.75, 0.0, 0.0]
    """
    c, s = math.cos(phi), math.sin(phi)
    p1x, p1y = x + c * bx - s * by, y + s * bx + c * by
    t1 = phi + q1
    t2 = t1 + q2
    t3 = t2 + q3
    p2x, p2y = p1x + a1 * math.cos(t1), p1y + a1 * math.sin(t1)
    p3x, p3y = p2x + a2 * math.cos(t2), p2y + a2 * math.sin(t2)
    ex, ey = p3x + a3 * math.cos(t3), p3y + a3 * math.sin(t3)
    return p1x, p1y, p2x, p2y, p3x, p3y, ex, ey, t3


def forward_kinematics(chain: Chain, config: Config) -> ChainPose:
    """Points P0..P3, E and the end-effector pose (by :func:`joint_points`).

    Parameters
    ----------
    chain : Chain
        Geometry.
    config : Config
        ``(x, y, phi, q1, q2, q3)``.

    Returns
    -------
    ChainPose
        Points and ``(xe, ye, phie)`` with ``phie = phi + q1 + q2 + q3``.

    Examples
    --------
    >>> pose = forward_kinematics(Chain(), (0.0, 0.0, 0.0, 0.0, math.pi / 2, 0.0))
    >>> [round(v, 12) for v in pose.p3]
    [1.5, 1.0]
    """
    x, y, phi, q1, q2, q3 = _unpack(config)
    p1x, p1y, p2x, p2y, p3x, p3y, ex, ey, t3 = joint_points(
        x, y, phi, q1, q2, q3, chain.a1, chain.a2, chain.a3, chain.b[0], chain.b[1]
    )
    return ChainPose((x, y), (p1x, p1y), (p2x, p2y), (p3x, p3y), (ex, ey), ex, ey, t3)


def network_columns(
    x: float,
    y: float,
    p1: tuple[float, float],
    p2: tuple[float, float],
    p3: tuple[float, float],
    e: tuple[float, float],
) -> tuple[Twist, ...]:
    """The nine columns of N from the joint points: the one implementation of N.

    Parameters
    ----------
    x, y : float
        Vehicle point P0 (axis of the heading joint).
    p1, p2, p3 : tuple of float
        Axes of the arm joints q1, q2, q3.
    e : tuple of float
        End-effector point E (axis of the closing chain's revolute).

    Returns
    -------
    tuple of Twist
        ``($x, $y, $phi, $q1, $q2, $q3, -$xe, -$ye, -$phie)``.

    Examples
    --------
    >>> network_columns(0.0, 0.0, (1, 0), (2, 0), (3, 0), (4, 0))[8]
    (-1.0, -0.0, 4.0)
    """
    phie = revolute(e)
    return (
        _X_AXIS,
        _Y_AXIS,
        revolute((x, y)),
        revolute(p1),
        revolute(p2),
        revolute(p3),
        _MINUS_X_AXIS,
        _MINUS_Y_AXIS,
        (-phie[0], -phie[1], -phie[2]),
    )


def joint_point_rates(
    x: float,
    y: float,
    phi: float,
    q1: float,
    q2: float,
    q3: float,
    xd: float,
    yd: float,
    phid: float,
    q1d: float,
    q2d: float,
    q3d: float,
    a1: float,
    a2: float,
    a3: float,
    bx: float,
    by: float,
) -> tuple[float, float, float, float, float, float, float, float]:
    """Velocities of the points P1, P2, P3 and E from the chain's rates (scalars).

    Each body point moves with the twist of its link: :math:`\\dot P_{k+1} = \\dot P_k +
    \\omega_k \\hat z \times (P_{k+1} - P_k)`, :math:`\\omega_k` the link's absolute rate.

    Parameters
    ----------
    x, y, phi, q1, q2, q3 : float
        Configuration.
    xd, yd, phid, q1d, q2d, q3d : float
        Its rates.
    a1, a2, a3, bx, by : float
        Geometry (see :func:`joint_points`).

    Returns
    -------
    tuple of float
        ``(p1xd, p1yd, p2xd, p2yd, p3xd, p3yd, exd, eyd)``.

    Examples
    --------
    >>> r = joint_point_rates(0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0,
    ...                       1.0, 1.0, 0.25, 0.5, 0.0)
    >>> [round(v, 12) for v in r]   # the whole chain turning at 1 rad/s about P0
    [0.0, 0.5, 0.0, 1.5, 0.0, 2.5, 0.0, 2.75]
    """
    p1x, p1y, p2x, p2y, p3x, p3y, ex, ey, _ = joint_points(
        x, y, phi, q1, q2, q3, a1, a2, a3, bx, by
    )
    w0 = phid
    w1 = w0 + q1d
    w2 = w1 + q2d
    w3 = w2 + q3d
    p1xd, p1yd = xd - w0 * (p1y - y), yd + w0 * (p1x - x)
    p2xd, p2yd = p1xd - w1 * (p2y - p1y), p1yd + w1 * (p2x - p1x)
    p3xd, p3yd = p2xd - w2 * (p3y - p2y), p2yd + w2 * (p3x - p2x)
    exd, eyd = p3xd - w3 * (ey - p3y), p3yd + w3 * (ex - p3x)
    return p1xd, p1yd, p2xd, p2yd, p3xd, p3yd, exd, eyd


def network_column_rates(
    xd: float,
    yd: float,
    p1d: tuple[float, float],
    p2d: tuple[float, float],
    p3d: tuple[float, float],
    ed: tuple[float, float],
) -> tuple[Twist, ...]:
    """Time derivatives of the nine columns of N (order of :func:`network_columns`).

    Parameters
    ----------
    xd, yd : float
        Velocity of P0.
    p1d, p2d, p3d, ed : tuple of float
        Velocities of P1, P2, P3 and E (:func:`joint_point_rates`).

    Returns
    -------
    tuple of Twist
        ``[0, Py', -Px']`` for the revolutes, zero for the prismatic columns, negated
        for the closing chain.

    Examples
    --------
    >>> network_column_rates(1.0, 0.0, (0, 0), (0, 0), (0, 0), (0.0, 2.0))[2]
    (0.0, 0.0, -1.0)
    """
    zero: Twist = (0.0, 0.0, 0.0)
    return (
        zero,
        zero,
        (0.0, float(yd), -float(xd)),
        (0.0, float(p1d[1]), -float(p1d[0])),
        (0.0, float(p2d[1]), -float(p2d[0])),
        (0.0, float(p3d[1]), -float(p3d[0])),
        zero,
        zero,
        (0.0, -float(ed[1]), float(ed[0])),
    )


def end_effector_pose(chain: Chain, config: Config) -> tuple[float, float, float]:
    """End-effector pose ``(xe, ye, phie)``.

    Parameters
    ----------
    chain : Chain
        Geometry.
    config : Config
        ``(x, y, phi, q1, q2, q3)``.

    Returns
    -------
    tuple of float
        ``(xe, ye, phie)``.
    """
    pose = forward_kinematics(chain, config)
    return pose.xe, pose.ye, pose.phie


def network_matrix(chain: Chain, config: Config) -> FloatArray:
    """Network matrix N (3 x 9), magnitude order ``MAGNITUDE_NAMES``.

    Parameters
    ----------
    chain : Chain
        Geometry.
    config : Config
        ``(x, y, phi, q1, q2, q3)``.

    Returns
    -------
    numpy.ndarray
        ``N`` with the closing chain (xe, ye, phie) counted negatively.
    """
    pose = forward_kinematics(chain, config)
    cols = network_columns(pose.p0[0], pose.p0[1], pose.p1, pose.p2, pose.p3, pose.e)
    return np.array(cols, dtype=np.float64).T


def network_matrix_rate(chain: Chain, config: Config, rates: Vector) -> FloatArray:
    """Time derivative of N (3 x 9) while the chain moves at ``rates``.

    Parameters
    ----------
    chain : Chain
        Geometry.
    config : Config
        ``(x, y, phi, q1, q2, q3)``.
    rates : sequence of float
        ``(xd, yd, phid, q1d, q2d, q3d)``.

    Returns
    -------
    numpy.ndarray
        ``dN/dt``, columns in the order of ``MAGNITUDE_NAMES``.
    """
    x, y, phi, q1, q2, q3 = _unpack(config)
    xd, yd, phid, q1d, q2d, q3d = _unpack(rates)
    p1xd, p1yd, p2xd, p2yd, p3xd, p3yd, exd, eyd = joint_point_rates(
        x, y, phi, q1, q2, q3, xd, yd, phid, q1d, q2d, q3d,
        chain.a1, chain.a2, chain.a3, chain.b[0], chain.b[1],
    )  # fmt: skip
    cols = network_column_rates(xd, yd, (p1xd, p1yd), (p2xd, p2yd), (p3xd, p3yd), (exd, eyd))
    return np.array(cols, dtype=np.float64).T


def _check_secondary(n_rows: int, n_cols: int, secondary: Sequence[int]) -> tuple[int, ...]:
    sec = tuple(int(i) for i in secondary)
    if len(sec) != n_rows:
        raise ValueError(f"need exactly {n_rows} secondary indices, got {len(sec)}")
    if len(set(sec)) != len(sec) or min(sec) < 0 or max(sec) >= n_cols:
        raise ValueError(f"secondary indices must be distinct and in [0, {n_cols}): {sec}")
    return sec


def primary_indices(secondary: Sequence[int], n_magnitudes: int = 9) -> tuple[int, ...]:
    """Primary indices: the complement of ``secondary``, in ascending order.

    Parameters
    ----------
    secondary : sequence of int
        Secondary magnitude indices.
    n_magnitudes : int
        Length of the magnitude vector (default 9).

    Returns
    -------
    tuple of int
        Ascending indices not in ``secondary``.
    """
    sec = set(int(i) for i in secondary)
    return tuple(i for i in range(n_magnitudes) if i not in sec)


def solve_partition(
    n_matrix: FloatArray,
    secondary_indices: Sequence[int],
    primary_values: Vector,
    tol: float = 1e-9,
) -> FloatArray:
    """Full magnitude vector from Davies' partition, ``Psi_s = -Ns^-1 Np Psi_p``.

    Parameters
    ----------
    n_matrix : numpy.ndarray
        Network matrix N (d x F).
    secondary_indices : sequence of int
        The d secondary (unknown) magnitude indices; their order sets the column order of Ns.
    primary_values : sequence of float
        The F - d primary magnitudes, ordered as ``primary_indices(secondary_indices, F)``
        (ascending magnitude index).
    tol : float
        Ns is declared singular when ``|det Ns| < tol``.

    Returns
    -------
    numpy.ndarray
        Psi (length F) with ``N @ Psi = 0``.

    Raises
    ------
    ValueError
        If the partition is malformed or Ns is singular.
    """
    n_mat = np.asarray(n_matrix, dtype=np.float64)
    d, f = n_mat.shape
    sec = _check_secondary(d, f, secondary_indices)
    prim = primary_indices(sec, f)
    psi_p = np.asarray(primary_values, dtype=np.float64)
    if psi_p.shape != (len(prim),):
        raise ValueError(f"need {len(prim)} primary values, got shape {psi_p.shape}")
    ns = n_mat[:, sec]
    det = float(np.linalg.det(ns))
    if not abs(det) >= tol:
        names = [MAGNITUDE_NAMES[i] if f == 9 else str(i) for i in sec]
        raise ValueError(
            f"secondary matrix Ns is singular for secondary {names}: "
            f"|det Ns| = {abs(det):.3e} < tol = {tol:.1e}"
        )
    psi = np.zeros(f, dtype=np.float64)
    psi[list(prim)] = psi_p
    psi[list(sec)] = np.linalg.solve(ns, -(n_mat[:, list(prim)] @ psi_p))
    return psi


def solve_partition_acceleration(
    n_matrix: FloatArray,
    n_rate: FloatArray,
    secondary_indices: Sequence[int],
    psi: Vector,
    primary_accelerations: Vector,
    tol: float = 1e-9,
) -> FloatArray:
    """Accelerations of all magnitudes, ``Ns Psi_s' = -(Np Psi_p' + N' Psi)``.

    Parameters
    ----------
    n_matrix, n_rate : numpy.ndarray
        N and dN/dt (d x F).
    secondary_indices : sequence of int
        The d secondary magnitudes.
    psi : sequence of float
        The full magnitude vector (rates, length F) at this instant.
    primary_accelerations : sequence of float
        Accelerations of the primary magnitudes, ordered as ``primary_indices``.
    tol : float
        Singularity tolerance on ``|det Ns|``.

    Returns
    -------
    numpy.ndarray
        Psi' (length F) with ``N Psi' + N' Psi = 0``.
    """
    n_mat = np.asarray(n_matrix, dtype=np.float64)
    bias = np.asarray(n_rate, dtype=np.float64) @ np.asarray(psi, dtype=np.float64)
    d, f = n_mat.shape
    sec = _check_secondary(d, f, secondary_indices)
    prim = list(primary_indices(sec, f))
    acc_p = np.asarray(primary_accelerations, dtype=np.float64)
    if acc_p.shape != (len(prim),):
        raise ValueError(f"need {len(prim)} primary accelerations, got shape {acc_p.shape}")
    ns = n_mat[:, sec]
    if not abs(float(np.linalg.det(ns))) >= tol:
        raise ValueError("secondary matrix Ns is singular")
    acc = np.zeros(f, dtype=np.float64)
    acc[prim] = acc_p
    acc[list(sec)] = np.linalg.solve(ns, -(n_mat[:, prim] @ acc_p + bias))
    return acc


def det_ns(chain: Chain, config: Config, secondary: Sequence[int] = Q0_SECONDARY) -> float:
    """Determinant of the secondary network sub-matrix Ns.

    Parameters
    ----------
    chain : Chain
        Geometry.
    config : Config
        ``(x, y, phi, q1, q2, q3)``.
    secondary : sequence of int
        Secondary magnitude indices, in column order (default ``Q0_SECONDARY``).

    Returns
    -------
    float
        ``det N[:, secondary]``; ``a1 a2 sin q2`` for q0, ``+1`` for kinematic state 3.
    """
    n_mat = network_matrix(chain, config)
    sec = _check_secondary(3, 9, secondary)
    return float(np.linalg.det(n_mat[:, sec]))


def solve_q0(
    chain: Chain,
    config: Config,
    vehicle_rates: Vector,
    ee_rates: Vector,
    tol: float = 1e-9,
) -> FloatArray:
    """Location q0: arm joint rates from vehicle and end-effector rates.

    Parameters
    ----------
    chain : Chain
        Geometry.
    config : Config
        ``(x, y, phi, q1, q2, q3)``.
    vehicle_rates : sequence of float
        ``(xd, yd, phid)``.
    ee_rates : sequence of float
        ``(xed, yed, phied)``.
    tol : float
        Singularity tolerance on ``|det Ns|``.

    Returns
    -------
    numpy.ndarray
        Full Psi (9,).
    """
    primary = [*vehicle_rates, *ee_rates]
    return solve_partition(network_matrix(chain, config), Q0_SECONDARY, primary, tol)


def solve_state3(
    chain: Chain,
    config: Config,
    ee_rates: Vector,
    phid: float,
    q1d: float,
    q3d: float,
    tol: float = 1e-9,
) -> FloatArray:
    """Kinematic state 3 (location q1): ``(xd, yd, q2d)`` from the other six rates.

    Parameters
    ----------
    chain : Chain
        Geometry.
    config : Config
        ``(x, y, phi, q1, q2, q3)``.
    ee_rates : sequence of float
        ``(xed, yed, phied)``.
    phid, q1d, q3d : float
        Primary vehicle heading rate and arm joint rates.
    tol : float
        Singularity tolerance on ``|det Ns|`` (here always 1).

    Returns
    -------
    numpy.ndarray
        Full Psi (9,).
    """
    primary = [phid, q1d, q3d, *ee_rates]
    return solve_partition(network_matrix(chain, config), STATE3_SECONDARY, primary, tol)
