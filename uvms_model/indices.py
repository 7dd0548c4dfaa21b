r"""Kinematic performance indices of the paper (eqs. 4 and 7).

.. math::

    \gamma = \frac{\det N_s(q)}{\det N_s(q_{sv})} = \frac{\sin q_2}{\sin\theta_{sv}},\qquad
    \alpha = \frac{1}{\gamma},\qquad
    \hat w = \frac{\alpha - \gamma}{\gamma} = \alpha^2 - 1,\qquad
    \gamma_{max} = \frac{1}{\sin\theta_{sv}}.

:math:`\theta_{sv} = 0.78` rad is the paper's singular vicinity, so :math:`\gamma = 1` there
and :math:`\gamma_{max} = 1/\sin 0.78 = 1.4219` (the paper's 1.42). The inverse map
:math:`q_2 = \arcsin(\gamma \sin\theta_{sv})` (principal branch) gives 0.475, 0.78 and
0.831 rad for :math:`\gamma_{tol} = 0.65`, 1 and :math:`\gamma_{accel} = 1.05`.

The paper defines :math:`\gamma` as the *absolute* rate of the two determinants, so
:math:`\gamma = |\sin q_2| / \sin\theta_{sv}` here too (eq. 4 with ``|det Ns|``): both
elbow postures, :math:`q_2` and :math:`-q_2`, have the same performance, and an elbow
that passes through :math:`q_2 = 0` shows as :math:`\gamma \to 0`, not as a sign change.
All functions use plain ``math`` on floats (called once per ODE step).
"""

from __future__ import annotations

import math

__all__ = [
    "THETA_SV",
    "alpha",
    "gamma",
    "gamma_from_det",
    "gamma_max",
    "q2_for_gamma",
    "w_hat",
]

THETA_SV: float = 0.78
"""Singular-vicinity elbow angle of the paper, rad."""


def gamma(q2: float, theta_sv: float = THETA_SV) -> float:
    """Normalised performance index ``|sin q2| / sin theta_sv`` (eq. 4, an absolute rate).

    Parameters
    ----------
    q2 : float
        Elbow joint angle, rad.
    theta_sv : float
        Singular-vicinity angle, rad (default 0.78).

    Returns
    -------
    float
        gamma (non-negative).

    Examples
    --------
    >>> gamma(0.78), gamma(-0.78)
    (1.0, 1.0)
    """
    return abs(math.sin(q2)) / math.sin(theta_sv)


def gamma_from_det(det: float, det_sv: float) -> float:
    """Index from determinants, ``|det Ns(q) / det Ns(q_sv)|`` (eq. 4).

    Parameters
    ----------
    det : float
        Current ``det Ns``.
    det_sv : float
        ``det Ns`` at the singular vicinity (non-zero).

    Returns
    -------
    float
        gamma.
    """
    return abs(det / det_sv)


def alpha(gamma_value: float) -> float:
    """Reflex agent ``alpha = 1 / gamma``.

    Parameters
    ----------
    gamma_value : float
        Performance index (non-zero; ``ZeroDivisionError`` at the singularity itself).

    Returns
    -------
    float
        alpha.
    """
    return 1.0 / gamma_value


def w_hat(gamma_value: float) -> float:
    """Kinematic regulation index ``(alpha - gamma) / gamma`` (eq. 7).

    Parameters
    ----------
    gamma_value : float
        Performance index (non-zero).

    Returns
    -------
    float
        w_hat, equal to ``alpha**2 - 1``: positive below gamma = 1, negative above.
    """
    a = 1.0 / gamma_value
    return (a - gamma_value) / gamma_value


def gamma_max(theta_sv: float = THETA_SV) -> float:
    """Largest index, reached at ``q2 = pi/2``: ``1 / sin theta_sv``.

    Parameters
    ----------
    theta_sv : float
        Singular-vicinity angle, rad.

    Returns
    -------
    float
        gamma_max (1.4219 for 0.78 rad).
    """
    return 1.0 / math.sin(theta_sv)


def q2_for_gamma(gamma_value: float, theta_sv: float = THETA_SV) -> float:
    """Elbow angle in ``[-pi/2, pi/2]`` at which the index equals ``gamma_value``.

    Parameters
    ----------
    gamma_value : float
        Target index, ``|gamma_value| <= gamma_max(theta_sv)``.
    theta_sv : float
        Singular-vicinity angle, rad.

    Returns
    -------
    float
        ``asin(gamma_value sin theta_sv)``.

    Raises
    ------
    ValueError
        If the target exceeds ``gamma_max``.
    """
    s = gamma_value * math.sin(theta_sv)
    if abs(s) > 1.0:
        raise ValueError(f"|gamma| = {abs(gamma_value)} exceeds gamma_max {gamma_max(theta_sv)}")
    return math.asin(s)
