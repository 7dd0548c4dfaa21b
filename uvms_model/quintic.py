r"""Quintic transition law between kinematic states (paper eq. 9).

From :math:`\xi_i = [t_0, p_0, v_0, a_0]` to :math:`\xi_f = [t_f, p_f, v_f, a_f]`, with
:math:`T = t_f - t_0 > 0`, :math:`d = p_f - p_0` and :math:`\tau = t - t_0`:

.. math::

    p(t) = c_0 + c_1\tau + c_2\tau^2 + c_3\tau^3 + c_4\tau^4 + c_5\tau^5,

    c_0 = p_0,\quad c_1 = v_0,\quad c_2 = a_0/2,

    c_3 = \frac{20d - (8v_f + 12v_0)T - (3a_0 - a_f)T^2}{2T^3},

    c_4 = \frac{-30d + (14v_f + 16v_0)T + (3a_0 - 2a_f)T^2}{2T^4},

    c_5 = \frac{12d - 6(v_f + v_0)T - (a_0 - a_f)T^2}{2T^5}.

The paper's target is :math:`p_f = \alpha_j p_i` with :math:`\alpha_j = 1/\gamma_j` of the
target state and :math:`v_f = a_f = 0` (:func:`transition_target`).

Outside :math:`[t_0, t_f]` (our choice, ``clamp=True``) the law continues from the
boundary state it has at that end with constant acceleration,
:math:`p + v\tau + a\tau^2/2`: after :math:`t_f` with the paper's :math:`v_f = a_f = 0` it
holds :math:`(p_f, 0, 0)`, the rest the target asks for; before :math:`t_0` (only reached
by event-location round-off) it is the start state's Taylor extension. Position, velocity
and acceleration are continuous at both ends. ``clamp=False`` evaluates the raw polynomial.

:func:`quintic_state` is the one evaluation of the law: :class:`Quintic`, the function
``quintic`` the specs call (:mod:`uvms_model.functions`) and the path timing
(:func:`uvms_model.paths.smoothstep5`) all use it.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Quintic", "quintic_coefficients", "quintic_state", "transition_target"]

Coefficients = tuple[float, float, float, float, float, float]


def _bad_duration(t0: float, tf: float) -> float:
    """``tf <= t0``: ValueError here, NaN in the compiled form (:mod:`uvms_model.compiled`)."""
    raise ValueError(f"quintic needs tf > t0, got t0={t0}, tf={tf}")


def quintic_coefficients(
    t0: float,
    p0: float,
    v0: float,
    a0: float,
    tf: float,
    pf: float,
    vf: float = 0.0,
    af: float = 0.0,
) -> Coefficients:
    """Coefficients ``(c0, ..., c5)`` in powers of ``t - t0``.

    Parameters
    ----------
    t0, p0, v0, a0 : float
        Start time, position, velocity, acceleration.
    tf, pf, vf, af : float
        End time (``tf > t0``), position, velocity, acceleration.

    Returns
    -------
    tuple of float
        ``(c0, c1, c2, c3, c4, c5)``.

    Raises
    ------
    ValueError
        If ``tf <= t0``.
    """
    T = tf - t0
    if not T > 0.0:
        T = _bad_duration(t0, tf)
    d = pf - p0
    c3 = (20.0 * d - (8.0 * vf + 12.0 * v0) * T - (3.0 * a0 - af) * T**2) / (2.0 * T**3)
    c4 = (-30.0 * d + (14.0 * vf + 16.0 * v0) * T + (3.0 * a0 - 2.0 * af) * T**2) / (2.0 * T**4)
    c5 = (12.0 * d - 6.0 * (vf + v0) * T - (a0 - af) * T**2) / (2.0 * T**5)
    return (p0, v0, 0.5 * a0, c3, c4, c5)


def _evaluate(
    coeffs: Coefficients,
    t0: float,
    tf: float,
    end: tuple[float, float, float],
    t: float,
    clamp: bool,
) -> tuple[float, float, float]:
    """The law at ``t`` from its coefficients and its end state ``(pf, vf, af)``."""
    if clamp and t > tf:
        pf, vf, af = end
        tau = t - tf
        return pf + tau * (vf + 0.5 * af * tau), vf + af * tau, af
    c0, c1, c2, c3, c4, c5 = coeffs
    s = t - t0
    if clamp and s < 0.0:
        return c0 + s * (c1 + s * c2), c1 + 2.0 * c2 * s, 2.0 * c2
    p = c0 + s * (c1 + s * (c2 + s * (c3 + s * (c4 + s * c5))))
    v = c1 + s * (2.0 * c2 + s * (3.0 * c3 + s * (4.0 * c4 + s * 5.0 * c5)))
    a = 2.0 * c2 + s * (6.0 * c3 + s * (12.0 * c4 + s * 20.0 * c5))
    return p, v, a


def quintic_state(
    t: float,
    t0: float,
    p0: float,
    v0: float,
    a0: float,
    tf: float,
    pf: float,
    vf: float = 0.0,
    af: float = 0.0,
    clamp: bool = True,
) -> tuple[float, float, float]:
    """Position, velocity and acceleration of the law at ``t`` (the one evaluation).

    Parameters
    ----------
    t : float
        Time.
    t0, p0, v0, a0 : float
        Start boundary values.
    tf, pf, vf, af : float
        End boundary values (``tf > t0``).
    clamp : bool
        If true, outside ``[t0, tf]`` the boundary state continues with constant
        acceleration (``(pf, 0, 0)`` after ``tf`` when ``vf = af = 0``).

    Returns
    -------
    tuple of float
        ``(p, v, a)``.

    Examples
    --------
    >>> quintic_state(0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0)   # the quintic smoothstep
    (0.5, 1.875, 0.0)
    >>> quintic_state(2.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0)   # held at rest after tf
    (1.0, 0.0, 0.0)
    """
    if clamp and t > tf and tf - t0 > 0.0:
        # held after the end: the end state alone (what _evaluate computes there), without
        # the coefficients (most calls come long after a switch's law has ended)
        tau = t - tf
        return pf + tau * (vf + 0.5 * af * tau), vf + af * tau, af
    coeffs = quintic_coefficients(t0, p0, v0, a0, tf, pf, vf, af)
    return _evaluate(coeffs, t0, tf, (pf, vf, af), t, clamp)


def transition_target(p_i: float, gamma_j: float) -> float:
    """Paper's final position ``p_f = alpha_j p_i = p_i / gamma_j`` (eq. 9).

    Parameters
    ----------
    p_i : float
        Position of the conducted primary joint at the switch.
    gamma_j : float
        Performance index of the target kinematic state (non-zero).

    Returns
    -------
    float
        ``p_i / gamma_j``.
    """
    return p_i / gamma_j


@dataclass(frozen=True)
class Quintic:
    """A quintic law on ``[t0, tf]``; build with :meth:`from_boundary`.

    Parameters
    ----------
    t0, tf : float
        Start and end times.
    coeffs : tuple of float
        ``(c0, ..., c5)`` in powers of ``t - t0``.
    pf, vf, af : float
        End position, velocity and acceleration (continued after ``tf`` when clamping).

    Examples
    --------
    >>> law = Quintic.from_boundary(0.0, 0.0, 0.0, 0.0, 1.0, 1.0)
    >>> law.evaluate(0.5) == quintic_state(0.5, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0)
    True
    """

    t0: float
    tf: float
    coeffs: Coefficients
    pf: float
    vf: float = 0.0
    af: float = 0.0

    @classmethod
    def from_boundary(
        cls,
        t0: float,
        p0: float,
        v0: float,
        a0: float,
        tf: float,
        pf: float,
        vf: float = 0.0,
        af: float = 0.0,
    ) -> Quintic:
        """Law from ``xi_i = [t0, p0, v0, a0]`` to ``xi_f = [tf, pf, vf, af]``.

        Parameters
        ----------
        t0, p0, v0, a0 : float
            Start boundary values.
        tf, pf, vf, af : float
            End boundary values.

        Returns
        -------
        Quintic
            The law.
        """
        return cls(t0, tf, quintic_coefficients(t0, p0, v0, a0, tf, pf, vf, af), pf, vf, af)

    def evaluate(self, t: float, clamp: bool = True) -> tuple[float, float, float]:
        """Position, velocity and acceleration at time ``t`` (see :func:`quintic_state`).

        Parameters
        ----------
        t : float
            Time.
        clamp : bool
            If true, outside ``[t0, tf]`` the boundary state continues with constant
            acceleration.

        Returns
        -------
        tuple of float
            ``(p, v, a)``.
        """
        return _evaluate(self.coeffs, self.t0, self.tf, (self.pf, self.vf, self.af), t, clamp)

    def position(self, t: float, clamp: bool = True) -> float:
        """Position at ``t`` (see :meth:`evaluate`)."""
        return self.evaluate(t, clamp)[0]

    def velocity(self, t: float, clamp: bool = True) -> float:
        """Velocity at ``t`` (see :meth:`evaluate`)."""
        return self.evaluate(t, clamp)[1]

    def acceleration(self, t: float, clamp: bool = True) -> float:
        """Acceleration at ``t`` (see :meth:`evaluate`)."""
        return self.evaluate(t, clamp)[2]
