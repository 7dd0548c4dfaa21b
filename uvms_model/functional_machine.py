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

__all__ = [
    "GAMMA_MIN",
    "Activation",
    "FMUnits",
    "functional_machine",
    "functional_machine_clipped",
    "functional_machine_units",
    "sigmoid",
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


def functional_machine_clipped(
    gamma: float,
    theta_p: float,
    gamma_min: float = GAMMA_MIN,
    activation: Activation = "tanh",
    s_min: float = 0.0,
    s_max: float = 1.0,
) -> float:
    """FM output limited to ``[s_min, s_max]``.

    Parameters
    ----------
    gamma : float
        Performance index (non-zero).
    theta_p : float
        Polarization (bias).
    gamma_min : float
        Reference of the second input.
    activation : {"sigmoid", "tanh"}
        Unit activation f (default tanh: exact rest for ``gamma >= 1`` when ``theta_p <= 0``).
    s_min, s_max : float
        Limits, ``s_min <= s_max``.

    Returns
    -------
    float
        ``min(max(s, s_min), s_max)``.
    """
    if s_min > s_max:
        raise ValueError("s_min must not exceed s_max")
    s = functional_machine(gamma, theta_p, gamma_min, activation)
    return min(max(s, s_min), s_max)
