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

Clamping (our choice, ``clamp=True``): for :math:`t < t_0` the start state
:math:`(p_0, v_0, a_0)` is returned unchanged (the law is started at :math:`t_0`; this only
absorbs event-location round-off); for :math:`t > t_f` the law holds :math:`(p_f, 0, 0)`, the
rest the paper's :math:`v_f = a_f = 0` target asks for. ``clamp=False`` evaluates the raw
polynomial everywhere.
"""

from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Quintic", "quintic_coefficients", "transition_target"]

Coefficients = tuple[float, float, float, float, float, float]


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
        raise ValueError(f"quintic needs tf > t0, got t0={t0}, tf={tf}")
    d = pf - p0
    c3 = (20.0 * d - (8.0 * vf + 12.0 * v0) * T - (3.0 * a0 - af) * T**2) / (2.0 * T**3)
    c4 = (-30.0 * d + (14.0 * vf + 16.0 * v0) * T + (3.0 * a0 - 2.0 * af) * T**2) / (2.0 * T**4)
    c5 = (12.0 * d - 6.0 * (vf + v0) * T - (a0 - af) * T**2) / (2.0 * T**5)
    return (p0, v0, 0.5 * a0, c3, c4, c5)


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
    pf : float
        End position, held exactly after ``tf`` when clamping.
    """

    t0: float
    tf: float
    coeffs: Coefficients
    pf: float

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
        return cls(t0, tf, quintic_coefficients(t0, p0, v0, a0, tf, pf, vf, af), pf)

    def _raw(self, t: float) -> tuple[float, float, float]:
        c0, c1, c2, c3, c4, c5 = self.coeffs
        s = t - self.t0
        p = c0 + s * (c1 + s * (c2 + s * (c3 + s * (c4 + s * c5))))
        v = c1 + s * (2.0 * c2 + s * (3.0 * c3 + s * (4.0 * c4 + s * 5.0 * c5)))
        a = 2.0 * c2 + s * (6.0 * c3 + s * (12.0 * c4 + s * 20.0 * c5))
        return p, v, a

    def evaluate(self, t: float, clamp: bool = True) -> tuple[float, float, float]:
        """Position, velocity and acceleration at time ``t``.

        Parameters
        ----------
        t : float
            Time.
        clamp : bool
            If true, ``t < t0`` gives the start state and ``t > tf`` gives ``(pf, 0, 0)``.

        Returns
        -------
        tuple of float
            ``(p, v, a)``.
        """
        if clamp:
            if t < self.t0:
                c0, c1, c2 = self.coeffs[:3]
                return c0, c1, 2.0 * c2
            if t > self.tf:
                return self.pf, 0.0, 0.0
        return self._raw(t)

    def position(self, t: float, clamp: bool = True) -> float:
        """Position at ``t`` (see :meth:`evaluate`)."""
        return self.evaluate(t, clamp)[0]

    def velocity(self, t: float, clamp: bool = True) -> float:
        """Velocity at ``t`` (see :meth:`evaluate`)."""
        return self.evaluate(t, clamp)[1]

    def acceleration(self, t: float, clamp: bool = True) -> float:
        """Acceleration at ``t`` (see :meth:`evaluate`)."""
        return self.evaluate(t, clamp)[2]
