r"""The redundancy resolutions the paper argues against, on the same chain (the comparison).

The UVMS has five free rates for the end effector's three: the vehicle's ``x', y'`` and
the arm's ``q1', q2', q3'`` (the vehicle's heading ``phi'`` is imposed: it aligns with
the current, as in the strategy). With Davies' columns of :mod:`uvms_model.chain`, the
end effector's rates are

.. math::

    (\dot x_e, \dot y_e, \dot\phi_e) = J\,u + j_\phi\,\dot\phi,\qquad
    u = (\dot x, \dot y, \dot q_1, \dot q_2, \dot q_3),

``J`` (3 x 5) the whole vehicle-arm Jacobian. Given the commanded end-effector rates
``r`` (the same path, tracking feedback and tool-heading law as the strategy), each
method picks ``u`` with ``J u = r - j_phi phi'`` (Antonelli, *Underwater Robots*,
Springer, ch. 7-8: the formulations below are the textbook ones):

* ``0`` arm only: ``x' = y' = 0``, the arm's 3 x 3 solve (the strategy's "no strategy").
* ``1`` pseudoinverse: ``u = J^+ b``, the least-norm solution.
* ``2`` weighted pseudoinverse: ``u = W^-1 J^T (J W^-1 J^T)^-1 b``,
  ``W = diag(w, w, 1, 1, 1)``: ``w > 1`` makes vehicle motion dearer than joint motion.
* ``3`` damped least squares: ``u = J^T (J J^T + lambda^2 I)^-1 b`` (tracks ``b`` only
  approximately; the position feedback of the path corrects the drift).
* ``4`` task priority with a manipulability null-space task:
  ``u = J^+ b + (I - J^+ J) k grad m``, ``m = sin^2 q2`` (the arm's manipulability is
  ``a1 a2 |sin q2|``), whose gradient in ``u`` is ``sin 2q2`` on ``q2'``.

Examples
--------
>>> u = resolve(1, 0.0, 0.0, 0.0, 0.4, -1.4, -1.3, 0.1, 0.0, 0.0, 0.0,
...             1.0, 1.2, 0.25, 0.7, 0.0)
>>> J, jphi = jacobian(0.0, 0.0, 0.0, 0.4, -1.4, -1.3, 1.0, 1.2, 0.25, 0.7, 0.0)
>>> [round(float(v), 12) + 0.0 for v in J @ u]
[0.1, 0.0, 0.0]
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from uvms_model.chain import joint_points, network_columns

__all__ = ["METHODS", "jacobian", "resolve", "sigma_min", "uvms_resolve", "uvms_sigma_min"]

METHODS = {
    0: "arm only",
    1: "pseudoinverse",
    2: "weighted pseudoinverse",
    3: "damped least squares",
    4: "task priority + manipulability",
}
"""The methods of :func:`resolve`, by code."""

_FREE = (0, 1, 3, 4, 5)
"""Columns of N for ``x, y, q1, q2, q3``."""


def jacobian(
    x: float, y: float, phi: float, q1: float, q2: float, q3: float,
    a1: float, a2: float, a3: float, bx: float, by: float,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # fmt: skip
    """``J`` (3 x 5) and ``j_phi`` (3,): end-effector rates ``(xe', ye', phie')`` per free rate.

    Parameters
    ----------
    x, y, phi, q1, q2, q3 : float
        Configuration.
    a1, a2, a3, bx, by : float
        Geometry.

    Returns
    -------
    tuple of ndarray
        ``J`` for ``u = (x', y', q1', q2', q3')`` and the column of the vehicle's heading.
    """
    p1x, p1y, p2x, p2y, p3x, p3y, ex, ey, _ = joint_points(
        x, y, phi, q1, q2, q3, a1, a2, a3, bx, by
    )
    cols = np.array(network_columns(x, y, (p1x, p1y), (p2x, p2y), (p3x, p3y), (ex, ey))).T
    # sum_{i<6} col_i psi_i = -(col_6 xe' + col_7 ye' + col_8 phie') = A (xe', ye', phie')
    a = -cols[:, 6:9]
    solve = np.linalg.solve(a, cols[:, [*_FREE, 2]])
    return solve[:, :5], solve[:, 5]


def resolve(
    method: float, x: float, y: float, phi: float, q1: float, q2: float, q3: float,
    ee_vx: float, ee_vy: float, ee_w: float, phid: float,
    a1: float, a2: float, a3: float, bx: float, by: float,
    w_vehicle: float = 1.0, damping: float = 0.1, k_null: float = 0.0,
) -> NDArray[np.float64]:  # fmt: skip
    """The free rates ``u = (x', y', q1', q2', q3')`` by ``method`` (codes of :data:`METHODS`).

    Parameters
    ----------
    method : float
        Method code (0-4).
    x, y, phi, q1, q2, q3 : float
        Configuration.
    ee_vx, ee_vy, ee_w : float
        Commanded end-effector rates.
    phid : float
        The vehicle's heading rate (imposed).
    a1, a2, a3, bx, by : float
        Geometry.
    w_vehicle : float
        Weight of the vehicle's rates (method 2).
    damping : float
        lambda of method 3.
    k_null : float
        Gain of the null-space task (method 4).

    Returns
    -------
    ndarray
        ``u`` (5,).
    """
    jac, jphi = jacobian(x, y, phi, q1, q2, q3, a1, a2, a3, bx, by)
    b = np.array([ee_vx, ee_vy, ee_w]) - jphi * phid
    code = round(method)
    if code == 0:
        u = np.zeros(5)
        u[2:] = np.linalg.solve(jac[:, 2:], b)
        return u
    if code == 2:
        w_inv = np.diag([1.0 / w_vehicle, 1.0 / w_vehicle, 1.0, 1.0, 1.0])
        return np.asarray(w_inv @ jac.T @ np.linalg.solve(jac @ w_inv @ jac.T, b))
    if code == 3:
        return np.asarray(jac.T @ np.linalg.solve(jac @ jac.T + damping**2 * np.eye(3), b))
    pinv = np.linalg.pinv(jac)
    u = pinv @ b
    if code == 4:
        grad = np.array([0.0, 0.0, 0.0, np.sin(2.0 * q2), 0.0])
        u = u + (np.eye(5) - pinv @ jac) @ (k_null * grad)
    elif code != 1:
        raise ValueError(f"unknown method {method!r}: one of {sorted(METHODS)}")
    return np.asarray(u)


def sigma_min(
    x: float, y: float, phi: float, q1: float, q2: float, q3: float,
    a1: float, a2: float, a3: float, bx: float, by: float,
) -> float:  # fmt: skip
    """Smallest singular value of the whole vehicle-arm Jacobian ``J`` (3 x 5)."""
    jac, _ = jacobian(x, y, phi, q1, q2, q3, a1, a2, a3, bx, by)
    return float(np.linalg.svd(jac, compute_uv=False)[-1])


def uvms_resolve(*args: float) -> tuple[float, ...]:
    """:func:`resolve` for the specs: its 19 arguments in order, ``u`` as a 5-tuple."""
    return tuple(float(v) for v in resolve(*args))


def uvms_sigma_min(*args: float) -> float:
    """:func:`sigma_min` for the specs."""
    return sigma_min(*args)
