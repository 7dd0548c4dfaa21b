r"""The paper's functional machine (FM), section 4, as a pure function of floats.

The paper fixes the topology (one input unit, two hidden units, one output unit), the inputs
:math:`\alpha` and :math:`|\alpha - \gamma_{min}|`, the weight :math:`\hat w` (eq. 7), the
bias :math:`\theta_p` (polarization, set by the finite state machine of Fig. 4), a unit law
:math:`s = f(\sum_i w_i x_i + \theta_p)` with :math:`f` tanh or sigmoid, and that the vehicle
twist is :math:`\$_V = s\,\alpha\,\$_E` (eq. 8) with :math:`s = \sum y_i`. It leaves the
wiring open. Our choice:

.. math::

    x_1 = \alpha = 1/\gamma,\qquad x_2 = |\alpha - \gamma_{min}|,\qquad
    \hat w = (\alpha - \gamma)/\gamma,

    y_k = f(\hat w\, x_k + \theta_p)\quad (k = 1, 2),\qquad
    s = \tfrac12 (y_1 + y_2).

* Input unit: a linear fan-out of :math:`(x_1, x_2)`, one input to each hidden unit (our
  choice: the single input unit only distributes, it has no weights of its own).
* Hidden units: the paper's unit law with the shared weight :math:`\hat w` and the shared
  bias :math:`\theta_p` (our choice: both units see the same polarization).
* Output unit: the paper's "sum of the outputs", scaled by 1/2 (our choice) so that
  :math:`s \in (0, 1)` for the sigmoid and :math:`s \in (-1, 1)` for tanh.

Since :math:`\hat w = \alpha^2 - 1`, :math:`\hat w > 0` below :math:`\gamma = 1` (the vehicle
must help) and :math:`\hat w < 0` above it. With ``activation="tanh"``, ``theta_p = 0`` and
the clipped variant (:math:`s \leftarrow \min(\max(s, 0), s_{max})`) the FM is exactly zero
whenever :math:`\gamma \ge 1`, the rest condition of state S1, without relying on a large
negative bias; the sigmoid needs :math:`\theta_p \ll 0` for (near) rest.
"""

from __future__ import annotations

import math
from typing import Literal, NamedTuple

from uvms_model.indices import alpha, w_hat
from uvms_model.quintic import quintic_state

__all__ = [
    "GAMMA_MIN",
    "Activation",
    "FMUnits",
    "functional_machine",
    "functional_machine_output",
    "functional_machine_rate",
    "functional_machine_units",
    "sigmoid",
    "smooth_ramp",
]

Activation = Literal["sigmoid", "tanh"]

GAMMA_MIN: float = 0.65
"""Default gamma_min of the second input (our choice: the paper's gamma_tol)."""


class FMUnits(NamedTuple):
    """Inputs, weight and unit outputs of one FM evaluation."""

    x1: float
    x2: float
    weight: float
    y1: float
    y2: float
    s: float


def sigmoid(z: float) -> float:
    """Logistic function ``1 / (1 + exp(-z))``, overflow-safe.

    Parameters
    ----------
    z : float
        Argument.

    Returns
    -------
    float
        Value in ``[0, 1]``.
    """
    if z >= 0.0:
        return 1.0 / (1.0 + math.exp(-z))
    ez = math.exp(z)
    return ez / (1.0 + ez)


def _activate(z: float, activation: Activation) -> float:
    if activation == "sigmoid":
        return sigmoid(z)
    if activation == "tanh":
        return math.tanh(z)
    return _unknown_activation(activation)


def _unknown_activation(activation: str) -> float:
    """ValueError here, NaN in the compiled form (:mod:`uvms_model.compiled`)."""
    raise ValueError(f"unknown activation {activation!r}; use 'sigmoid' or 'tanh'")


def functional_machine_units(
    gamma: float,
    theta_p: float,
    gamma_min: float = GAMMA_MIN,
    activation: Activation = "sigmoid",
) -> FMUnits:
    """Evaluate the FM and return every intermediate value.

    Parameters
    ----------
    gamma : float
        Performance index (non-zero).
    theta_p : float
        Polarization (bias) set by the finite state machine.
    gamma_min : float
        Reference of the second input ``|alpha - gamma_min|``.
    activation : {"sigmoid", "tanh"}
        Unit activation f.

    Returns
    -------
    FMUnits
        ``(x1, x2, weight, y1, y2, s)``.
    """
    a = alpha(gamma)
    x1 = a
    x2 = abs(a - gamma_min)
    w = w_hat(gamma)
    y1 = _activate(w * x1 + theta_p, activation)
    y2 = _activate(w * x2 + theta_p, activation)
    return FMUnits(x1, x2, w, y1, y2, 0.5 * (y1 + y2))


def functional_machine(
    gamma: float,
    theta_p: float,
    gamma_min: float = GAMMA_MIN,
    activation: Activation = "sigmoid",
) -> float:
    """FM output s, the factor in ``$V = s alpha $E`` (eq. 8).

    Parameters
    ----------
    gamma : float
        Performance index (non-zero).
    theta_p : float
        Polarization (bias).
    gamma_min : float
        Reference of the second input.
    activation : {"sigmoid", "tanh"}
        Unit activation f.

    Returns
    -------
    float
        ``s = (f(w x1 + theta_p) + f(w x2 + theta_p)) / 2``.
    """
    return functional_machine_units(gamma, theta_p, gamma_min, activation).s


def smooth_ramp(u: float, width: float) -> tuple[float, float]:
    """Output-unit activation: 0 for ``u <= 0``, ``u`` for ``u >= width``, C2 in between.

    In between, ``u sigma(u / width)`` with ``sigma`` the quintic smoothstep (the law of
    :func:`uvms_model.quintic.quintic_state` from rest at 0 to rest at 1), so value,
    slope and curvature are continuous at both ends; ``width = 0`` is the hard ramp
    ``max(u, 0)``.

    Parameters
    ----------
    u : float
        Input (the sum of the hidden units, scaled).
    width : float
        Width of the rounded corner (non-negative).

    Returns
    -------
    tuple of float
        Value and slope ``d/du``.

    Examples
    --------
    >>> smooth_ramp(-0.3, 0.1), smooth_ramp(0.5, 0.1)
    ((0.0, 0.0), (0.5, 1.0))
    >>> smooth_ramp(0.05, 0.1)   # u * sigma(1/2) = 0.05 * 0.5; slope 0.5 + 0.5 * 1.875
    (0.025, 1.4375)
    """
    if u <= 0.0:
        return 0.0, 0.0
    if u >= width:
        return u, 1.0
    x = u / width
    sigma, dsigma, _ = quintic_state(x, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0)
    return u * sigma, sigma + x * dsigma


def functional_machine_output(
    gamma: float,
    theta_p: float,
    gamma_min: float = GAMMA_MIN,
    activation: Activation = "tanh",
    ramp: float = 0.0,
) -> float:
    """FM output s >= 0: the output unit's activation :func:`smooth_ramp` on the hidden sum.

    Parameters
    ----------
    gamma : float
        Performance index (non-zero).
    theta_p : float
        Polarization (bias).
    gamma_min : float
        Reference of the second input.
    activation : {"sigmoid", "tanh"}
        Hidden-unit activation f (tanh: exact rest for ``gamma >= 1`` when ``theta_p <= 0``).
    ramp : float
        Width of the output unit's rounded corner at 0 (0: ``max(s, 0)``).

    Returns
    -------
    float
        ``smooth_ramp(functional_machine(...), ramp)``.

    Examples
    --------
    >>> functional_machine_output(1.2, 0.0, activation="tanh")   # gamma >= 1, no bias: rest
    0.0
    """
    return smooth_ramp(functional_machine(gamma, theta_p, gamma_min, activation), ramp)[0]


def functional_machine_rate(
    gamma: float,
    gamma_dot: float,
    theta_p: float,
    theta_dot: float,
    gamma_min: float = GAMMA_MIN,
    activation: Activation = "tanh",
    ramp: float = 0.0,
) -> float:
    """Time derivative of :func:`functional_machine_output` along a motion.

    By the chain rule through the units: with :math:`\\dot\alpha = -\alpha^2\\dot\\gamma`,
    :math:`\\dot{\\hat w} = 2\alpha\\dot\alpha`, :math:`\\dot z_k = \\dot{\\hat w} x_k +
    \\hat w \\dot x_k + \\dot\theta_p`, the hidden sum changes at
    :math:`\frac12 \\sum_k f'(z_k)\\dot z_k` and the output at that times the ramp's slope.

    Parameters
    ----------
    gamma, gamma_dot : float
        Performance index (non-zero) and its rate.
    theta_p, theta_dot : float
        Polarization (bias) and its rate.
    gamma_min : float
        Reference of the second input.
    activation : {"sigmoid", "tanh"}
        Hidden-unit activation f.
    ramp : float
        Width of the output unit's rounded corner.

    Returns
    -------
    float
        ds/dt.

    Examples
    --------
    >>> functional_machine_rate(1.2, 0.0, 0.5, 0.0)   # nothing changes: s is constant
    0.0
    >>> h = 1e-6
    >>> s = lambda g: functional_machine_output(g, 0.3, activation="tanh", ramp=0.1)
    >>> fd = (s(0.8 + h) - s(0.8 - h)) / (2 * h)
    >>> abs(functional_machine_rate(0.8, 1.0, 0.3, 0.0, ramp=0.1) - fd) < 1e-8
    True
    """
    units = functional_machine_units(gamma, theta_p, gamma_min, activation)
    _, slope = smooth_ramp(units.s, ramp)
    if slope == 0.0:
        return 0.0
    a = units.x1
    a_dot = -a * a * gamma_dot
    w_dot = 2.0 * a * a_dot
    x2_dot = math.copysign(1.0, a - gamma_min) * a_dot
    z1_dot = w_dot * units.x1 + units.weight * a_dot + theta_dot
    z2_dot = w_dot * units.x2 + units.weight * x2_dot + theta_dot
    hidden = 0.5 * (_slope(units.y1, activation) * z1_dot + _slope(units.y2, activation) * z2_dot)
    return slope * hidden


def _slope(y: float, activation: Activation) -> float:
    """f'(z) written with y = f(z)."""
    return 1.0 - y * y if activation == "tanh" else y * (1.0 - y)
