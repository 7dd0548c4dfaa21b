r"""End-effector mission paths of the case study: "deformed circles" timed over 60 s.

The paper gives only: mission 1 travels :math:`2\pi r` on a deformed circle whose centre is
1.25 m right of and 0.5 m above the end effector's start; mission 2 travels :math:`3\pi r`
with the centre 1.25 m right; both last 60 s. Everything else here is our choice.

Shape (our choice, an oval): a polar curve about the centre :math:`C`,

.. math::

    \rho(\theta) = R\,[1 + \varepsilon \cos 2(\theta - \theta_a)],\qquad
    p(\theta) = C + \rho(\theta)\,(\cos\theta, \sin\theta),

elongated along the axis angle :math:`\theta_a` (default 0: horizontal) with
:math:`\varepsilon = 0.1`. :math:`R` is fixed by passing through the start point :math:`S`:
:math:`R = |S - C| / [1 + \varepsilon\cos 2(\theta_s - \theta_a)]`, :math:`\theta_s` the polar
angle of :math:`S` about :math:`C`.

The paper's :math:`r` (our definition): the equivalent radius, perimeter / :math:`2\pi`,

.. math::

    r = \frac{1}{2\pi}\int_0^{2\pi}\sqrt{\rho^2 + \rho'^2}\,d\theta,

(:math:`r = |S - C|` for :math:`\varepsilon = 0`). The integrand has period :math:`\pi`, so
every half lap has length :math:`\pi r`: ``turns = 1`` (mission 1, a closed lap) travels
exactly :math:`2\pi r` and ``turns = 1.5`` (mission 2) exactly :math:`3\pi r`.

Timing (our choice): the polar angle follows a quintic smoothstep in time,

.. math::

    \theta(t) = \theta_s + \delta\,2\pi n\,\sigma(\tau),\quad
    \sigma(\tau) = 10\tau^3 - 15\tau^4 + 6\tau^5,\quad \tau = (t - t_0)/T \in [0, 1],

:math:`\delta = \pm 1` the direction (default +1, counter-clockwise), :math:`n` the turns,
so the commanded velocity and acceleration start and end at zero. Velocity
:math:`\dot p = [\rho'(\theta)(\cos\theta, \sin\theta) + \rho(\theta)(-\sin\theta,
\cos\theta)]\,\dot\theta`. Outside :math:`[t_0, t_0 + T]` the path holds its end point.

Heading (our choice): ``heading + follow (theta - theta_s)``, the start heading turned by
the fraction ``follow`` of the path's polar progress (0: held, 1: a constant angle to the
radius); the specs add to it the lean of a wrist regulator (docs/uvms.md).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from uvms_model.quintic import quintic_state

__all__ = [
    "MISSION1_CENTRE_OFFSET",
    "MISSION2_CENTRE_OFFSET",
    "DeformedCircle",
    "PathState",
    "mission1_path",
    "mission2_path",
    "oval_geometry",
    "path_state",
    "smoothstep5",
]

MISSION1_CENTRE_OFFSET: tuple[float, float] = (1.25, 0.5)
"""Centre minus start for mission 1, m (paper)."""
MISSION2_CENTRE_OFFSET: tuple[float, float] = (1.25, 0.0)
"""Centre minus start for mission 2, m (paper)."""

_PERIMETER_NODES = 4096


class PathState(NamedTuple):
    """Commanded end-effector pose, twist magnitudes and their rates at one instant."""

    xe: float
    ye: float
    phie: float
    vxe: float
    vye: float
    wphie: float
    axe: float
    aye: float
    dwphie: float


def smoothstep5(tau: float) -> tuple[float, float]:
    """Quintic smoothstep and its derivative, clamped to ``[0, 1]``.

    Parameters
    ----------
    tau : float
        Normalised time.

    Returns
    -------
    tuple of float
        ``(sigma, dsigma/dtau)`` with ``sigma = 10 tau^3 - 15 tau^4 + 6 tau^5``, the quintic
        law from rest at 0 to rest at 1 (:func:`uvms_model.quintic.quintic_state`).

    Examples
    --------
    >>> smoothstep5(0.5)
    (0.5, 1.875)
    """
    sigma, dsigma, _ = quintic_state(tau, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0)
    return sigma, dsigma


def oval_geometry(dx: float, dy: float, epsilon: float, axis_angle: float) -> tuple[float, float]:
    """Polar angle of the start about the centre and the base radius ``R`` of the oval.

    Parameters
    ----------
    dx, dy : float
        Centre minus start, m (non-zero).
    epsilon, axis_angle : float
        Radial deformation and direction of the long axis, rad.

    Returns
    -------
    tuple of float
        ``(theta_s, R)`` with ``R = |S - C| / [1 + epsilon cos 2(theta_s - theta_a)]``.

    Examples
    --------
    >>> oval_geometry(-1.0, 0.0, 0.0, 0.0) == (0.0, 1.0)
    True
    """
    theta_s = math.atan2(-dy, -dx)
    big_r = math.hypot(dx, dy) / (1.0 + epsilon * math.cos(2.0 * (theta_s - axis_angle)))
    return theta_s, big_r


def path_state(
    t: float,
    t_start: float,
    duration: float,
    laps: float,
    theta_start: float,
    axis_angle: float,
    base_radius: float,
    epsilon: float,
    cx: float,
    cy: float,
    heading: float,
    follow: float,
) -> tuple[float, float, float, float, float, float, float, float, float]:
    """The commanded end effector at ``t``: the one evaluation of the path (scalars).

    :class:`DeformedCircle` calls it with its geometry; so does the function
    ``uvms_path`` the specs call (:mod:`uvms_model.functions`), compiled or not.

    Parameters
    ----------
    t, t_start, duration : float
        Time, start time t0 and travel time T, s.
    laps : float
        Signed turns: ``direction * turns``.
    theta_start, axis_angle, base_radius, epsilon : float
        Geometry (:func:`oval_geometry`).
    cx, cy : float
        Centre, m.
    heading, follow : float
        Heading at the start and heading_follow (see :class:`DeformedCircle`).

    Returns
    -------
    tuple of float
        ``(xe, ye, phie, vxe, vye, wphie, axe, aye, dwphie)``.

    Examples
    --------
    >>> [round(v, 12) for v in path_state(0.0, 0.0, 60.0, 1.0, math.pi, 0.0, 1.0, 0.0,
    ...                                    1.0, 0.0, 0.0, 0.0)][:3]
    [0.0, 0.0, 0.0]
    """
    sigma, dsigma, ddsigma = quintic_state((t - t_start) / duration, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0)
    sweep = laps * 2.0 * math.pi
    theta = theta_start + sweep * sigma
    theta_dot = sweep * dsigma / duration
    theta_ddot = sweep * ddsigma / duration**2
    arg = 2.0 * (theta - axis_angle)
    big_r, eps = base_radius, epsilon
    rho = big_r * (1.0 + eps * math.cos(arg))
    drho = -2.0 * big_r * eps * math.sin(arg)
    ddrho = -4.0 * big_r * eps * math.cos(arg)
    c, s = math.cos(theta), math.sin(theta)
    # p(theta) = C + rho e, e = (c, s), e_perp = (-s, c):
    # p_theta = rho' e + rho e_perp, p_theta_theta = (rho'' - rho) e + 2 rho' e_perp
    ptx, pty = drho * c - rho * s, drho * s + rho * c
    pttx, ptty = (ddrho - rho) * c - 2.0 * drho * s, (ddrho - rho) * s + 2.0 * drho * c
    return (
        cx + rho * c,
        cy + rho * s,
        heading + follow * (theta - theta_start),
        ptx * theta_dot,
        pty * theta_dot,
        follow * theta_dot,
        pttx * theta_dot**2 + ptx * theta_ddot,
        ptty * theta_dot**2 + pty * theta_ddot,
        follow * theta_ddot,
    )


@dataclass(frozen=True)
class DeformedCircle:
    """Oval end-effector path through ``start``, timed by a quintic smoothstep.

    Parameters
    ----------
    start : tuple of float
        End-effector start point S, m.
    centre_offset : tuple of float
        Centre minus start, m (non-zero).
    turns : float
        Laps travelled, a positive multiple of 0.5 (length ``2 pi r turns``).
    duration : float
        Travel time T, s (default 60).
    epsilon : float
        Radial deformation, ``|epsilon| < 1`` (default 0.1, our choice).
    axis_angle : float
        Direction of the oval's long axis, rad (default 0).
    direction : int
        +1 counter-clockwise (default), -1 clockwise.
    heading : float
        Constant end-effector heading, rad.
    t_start : float
        Start time t0, s.
    heading_follow : float
        0 (default): the end-effector heading is held at ``heading``; 1: it turns with
        the polar angle about the centre, ``phie = heading + (theta - theta_s)``.
    """

    start: tuple[float, float]
    centre_offset: tuple[float, float]
    turns: float
    duration: float = 60.0
    epsilon: float = 0.1
    axis_angle: float = 0.0
    direction: int = 1
    heading: float = 0.0
    t_start: float = 0.0
    heading_follow: float = 0.0
    centre: tuple[float, float] = field(init=False)
    theta_start: float = field(init=False)
    base_radius: float = field(init=False)
    r: float = field(init=False)
    length: float = field(init=False)

    def __post_init__(self) -> None:
        if not self.duration > 0.0:
            raise ValueError("duration must be positive")
        if not abs(self.epsilon) < 1.0:
            raise ValueError("|epsilon| must be below 1")
        if self.direction not in (1, -1):
            raise ValueError("direction must be +1 or -1")
        half_laps = 2.0 * self.turns
        if not (self.turns > 0.0 and abs(half_laps - round(half_laps)) < 1e-12):
            raise ValueError("turns must be a positive multiple of 0.5")
        dx, dy = float(self.centre_offset[0]), float(self.centre_offset[1])
        dist = math.hypot(dx, dy)
        if dist == 0.0:
            raise ValueError("centre_offset must be non-zero")
        sx, sy = float(self.start[0]), float(self.start[1])
        theta_s, big_r = oval_geometry(dx, dy, self.epsilon, self.axis_angle)
        theta = np.linspace(0.0, 2.0 * math.pi, _PERIMETER_NODES, endpoint=False)
        arg = 2.0 * (theta - self.axis_angle)
        rho = big_r * (1.0 + self.epsilon * np.cos(arg))
        drho = -2.0 * big_r * self.epsilon * np.sin(arg)
        # Trapezoid rule on a smooth periodic integrand: exponentially accurate.
        perimeter = float(np.mean(np.hypot(rho, drho))) * 2.0 * math.pi
        object.__setattr__(self, "centre", (sx + dx, sy + dy))
        object.__setattr__(self, "theta_start", theta_s)
        object.__setattr__(self, "base_radius", big_r)
        object.__setattr__(self, "r", perimeter / (2.0 * math.pi))
        object.__setattr__(self, "length", perimeter * self.turns)

    @property
    def t_end(self) -> float:
        """End time ``t0 + T``, s."""
        return self.t_start + self.duration

    def __call__(self, t: float) -> PathState:
        """Commanded end-effector state at time ``t``.

        Parameters
        ----------
        t : float
            Time, s.

        Returns
        -------
        PathState
            ``(xe, ye, phie, vxe, vye, wphie)``.
        """
        return PathState(
            *path_state(
                t,
                self.t_start,
                self.duration,
                self.direction * self.turns,
                self.theta_start,
                self.axis_angle,
                self.base_radius,
                self.epsilon,
                self.centre[0],
                self.centre[1],
                self.heading,
                self.heading_follow,
            )
        )


def mission1_path(
    start: tuple[float, float],
    heading: float = 0.0,
    duration: float = 60.0,
    epsilon: float = 0.1,
    direction: int = 1,
) -> DeformedCircle:
    """Mission 1: one closed lap (``2 pi r``), centre 1.25 m right, 0.5 m above start.

    Parameters
    ----------
    start : tuple of float
        End-effector start point, m.
    heading : float
        Constant end-effector heading, rad.
    duration : float
        Travel time, s.
    epsilon : float
        Radial deformation.
    direction : int
        +1 counter-clockwise, -1 clockwise.

    Returns
    -------
    DeformedCircle
        The path.
    """
    return DeformedCircle(
        start, MISSION1_CENTRE_OFFSET, 1.0, duration, epsilon, 0.0, direction, heading
    )


def mission2_path(
    start: tuple[float, float],
    heading: float = 0.0,
    duration: float = 60.0,
    epsilon: float = 0.1,
    direction: int = 1,
) -> DeformedCircle:
    """Mission 2: one and a half laps (``3 pi r``), centre 1.25 m right of start.

    Parameters
    ----------
    start : tuple of float
        End-effector start point, m.
    heading : float
        Constant end-effector heading, rad.
    duration : float
        Travel time, s.
    epsilon : float
        Radial deformation.
    direction : int
        +1 counter-clockwise, -1 clockwise.

    Returns
    -------
    DeformedCircle
        The path.
    """
    return DeformedCircle(
        start, MISSION2_CENTRE_OFFSET, 1.5, duration, epsilon, 0.0, direction, heading
    )
