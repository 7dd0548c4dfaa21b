r"""The vehicle law of location q0 (paper eq. 8) with a smooth speed limit, and its rate.

Eq. 8 sets the vehicle twist proportional to the end-effector twist,
:math:`\$_V = s\,\alpha\,\$_E`; in the plane (the end-effector twist a translation
:math:`v_E` here, the heading being aligned separately) the commanded velocity is

.. math::

    c = s\,\alpha\,v_E .

The paper gives no speed limit; a vehicle has one (thrusters). Our choice is a smooth
limit of the speed :math:`r = |c|` to ``v_max``,

.. math::

    V = c\,h(r),\qquad h(r) = \bigl(1 + (r/v_{max})^n\bigr)^{-1/n},\quad n = 4,

which leaves slow commands almost unchanged (:math:`h = 0.985` at half the limit), never
exceeds :math:`v_{max}`, and is smooth, so the vehicle's acceleration stays continuous.
Its rate, with :math:`\dot c = \dot s\alpha v_E + s\dot\alpha v_E + s\alpha\dot v_E` and
:math:`u = (r/v_{max})^n`:

.. math::

    \dot V = h\,\dot c - (1 + u)^{-1/n - 1}\,\frac{u}{r^2}\,(c\cdot\dot c)\,c .
"""

from __future__ import annotations

import math

__all__ = ["SATURATION_ORDER", "limited_velocity", "limited_velocity_rate"]

SATURATION_ORDER = 4
"""Exponent n of the smooth speed limit (our choice)."""


def limited_velocity(cx: float, cy: float, v_max: float) -> tuple[float, float]:
    """Commanded velocity ``c`` after the smooth speed limit.

    Parameters
    ----------
    cx, cy : float
        Commanded velocity, m/s.
    v_max : float
        Speed limit, m/s (positive).

    Returns
    -------
    tuple of float
        ``c h(|c|)``, whose speed is below ``v_max``.

    Examples
    --------
    >>> vx, vy = limited_velocity(3.0, 4.0, 0.25)   # a command of 5 m/s
    >>> round(math.hypot(vx, vy), 6)
    0.25
    >>> limited_velocity(0.0, 0.0, 0.25)
    (0.0, 0.0)
    """
    h = (1.0 + (math.hypot(cx, cy) / v_max) ** SATURATION_ORDER) ** (-1.0 / SATURATION_ORDER)
    return cx * h, cy * h


def limited_velocity_rate(
    cx: float, cy: float, cx_dot: float, cy_dot: float, v_max: float
) -> tuple[float, float]:
    """Time derivative of :func:`limited_velocity` while the command changes at ``c_dot``.

    Parameters
    ----------
    cx, cy : float
        Commanded velocity, m/s.
    cx_dot, cy_dot : float
        Its rate, m/s^2.
    v_max : float
        Speed limit, m/s.

    Returns
    -------
    tuple of float
        The vehicle's acceleration, m/s^2.

    Examples
    --------
    >>> limited_velocity_rate(0.0, 0.0, 0.1, -0.2, 0.25)   # from rest: h = 1
    (0.1, -0.2)
    """
    n = SATURATION_ORDER
    r2 = cx * cx + cy * cy
    u = (r2 / (v_max * v_max)) ** (n / 2)
    h = (1.0 + u) ** (-1.0 / n)
    if r2 == 0.0:
        return h * cx_dot, h * cy_dot
    k = (1.0 + u) ** (-1.0 / n - 1.0) * u / r2 * (cx * cx_dot + cy * cy_dot)
    return h * cx_dot - k * cx, h * cy_dot - k * cy
