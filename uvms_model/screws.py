r"""Planar twists (screws of order d = 3) for Davies' method.

A planar twist is written in world coordinates as

.. math::

    \$ = [\omega,\ v_{Ox},\ v_{Oy}],

where :math:`\omega` is the angular rate about +z and :math:`v_O` is the velocity of the
body point that momentarily sits at the world origin O. The velocity of any body point r is
:math:`v(r) = v_O + \omega\,\hat z \times r = (v_{Ox} - \omega r_y,\ v_{Oy} + \omega r_x)`.

Unit twists of the two planar joint types:

.. math::

    \$_R(p) = [1,\ p_y,\ -p_x]        \quad\text{(revolute about +z through point p)}

    \$_P(u) = [0,\ u_x,\ u_y]         \quad\text{(prismatic along unit vector u)}

:math:`\$_R(p)` follows from :math:`v(p) = 0`; :math:`\$_P(u)` is a pure translation.
"""

from __future__ import annotations

import math

__all__ = ["Twist", "point_velocity", "prismatic", "revolute"]

Twist = tuple[float, float, float]
"""A planar twist ``(w, v_Ox, v_Oy)``."""


def revolute(p: tuple[float, float]) -> Twist:
    """Unit twist of a revolute joint about +z through point ``p``.

    Parameters
    ----------
    p : tuple of float
        Point ``(p_x, p_y)`` on the joint axis, world frame.

    Returns
    -------
    Twist
        ``(1, p_y, -p_x)``.
    """
    return (1.0, float(p[1]), -float(p[0]))


def prismatic(u: tuple[float, float]) -> Twist:
    """Unit twist of a prismatic joint along direction ``u``.

    Parameters
    ----------
    u : tuple of float
        Direction ``(u_x, u_y)``; normalised here (must be non-zero).

    Returns
    -------
    Twist
        ``(0, u_x, u_y)`` with ``|u| = 1``.

    Raises
    ------
    ValueError
        If ``u`` is the zero vector.
    """
    ux, uy = float(u[0]), float(u[1])
    norm = math.hypot(ux, uy)
    if norm == 0.0:
        raise ValueError("prismatic direction must be non-zero")
    return (0.0, ux / norm, uy / norm)


def point_velocity(twist: Twist, r: tuple[float, float]) -> tuple[float, float]:
    """Velocity of the body point at ``r`` for a given twist.

    Parameters
    ----------
    twist : Twist
        ``(w, v_Ox, v_Oy)``.
    r : tuple of float
        World point ``(r_x, r_y)``.

    Returns
    -------
    tuple of float
        ``(v_Ox - w r_y, v_Oy + w r_x)``.
    """
    w, vx, vy = twist
    return (vx - w * r[1], vy + w * r[0])
