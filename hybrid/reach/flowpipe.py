"""One location's flowpipe: box hulls of ``x' = A x + B u + c`` over time, sound in continuous time.

The reachable set at time ``t`` from a box ``X0`` with ``u(t)`` any measurable
function into the box ``U`` is

    R(t) = e^{At} X0 (+) { int_0^t e^{A(t-s)} (B u(s) + c) ds }.

This module evaluates the support function of ``R`` in the ``2n`` directions
``+e_p``, ``-e_p`` (the box hull), after Le Guernic and Girard, "Reachability
analysis of linear systems using support functions", Nonlinear Analysis: Hybrid
Systems 4 (2010). With ``h`` the step, ``Phi = e^{Ah}``, ``Phi1 = int_0^h e^{Ar} dr``
and ``Phi2 = int_0^h int_0^r e^{As} ds dr`` (all three from one ``expm`` of an
augmented matrix, :func:`exp_matrices`), and ``|M|`` the entrywise absolute value:

- **step points** (:func:`flowpipe`): ``R(t_k)`` is held as a centre ``c_k``
  (the exact image of the centres of ``X0`` and ``U``) and a radius bound ``r_k``:
  ``r_k = |Phi^k| r0 + sum_{m<k} g(Phi^m)`` with
  ``g(P) = h |P B| ur + |P| E_in |B| ur``. The first term is exact (the support
  of a box under a linear map); the second bounds the input's deviation from its
  centre over one step, ``int_0^h |w e^{Ar} b_j| dr <= h |w b_j| + |w| E_in |b_j|``
  with ``E_in = int_0^h (e^{|A|r} - I) dr = |A| Phi2(|A|)``, which holds because
  ``|e^{Ar} - I| <= e^{|A|r} - I`` entrywise (compare the series term by term);
- **between step points**: for ``t = t_k + s h``, ``0 <= s <= 1``,
  ``x(t) = (1-s) x_k + s (Phi x_k + h vbar) + R1 + R2`` with ``vbar`` in
  ``V = B U + c`` (the mean of ``v`` over the step lies in the convex ``V``),
  ``|R1| <= Phi2(|A|) |A^2| |x_k|`` (``e^{As h} - I - s (Phi - I) = sum_{k>=2}
  A^k h^k (s^k - s) / k!`` and ``|s^k - s| <= 1``) and
  ``|R2| <= E_in |V|`` (``int_0^{sh} (e^{Ar} - I) v dr``). So the segment
  ``[t_k, t_k+1]`` lies in the hull of ``R(t_k)`` and ``Phi R(t_k) (+) hV`` (whose
  radius is at most ``r_{k+1}``), bloated by those two bounds: Le Guernic and
  Girard's ``Omega_0`` with their ``E_Omega``, applied at every step to the box of
  ``R(t_k)`` rather than only to ``X0``.

Floating point: ``expm`` (scipy, Al-Mohy and Higham) and the matrix products
are taken as exact up to a relative error; every box is widened by
:data:`FP_MARGIN` times the magnitude of its bounds, and every error matrix by
the factor ``1 + FP_MARGIN``. docs/reach.md states this assumption and what was
measured to support it.

Examples
--------
A point decaying as ``x' = -x`` from 1: the step points are ``e^{-t}``.

>>> import numpy as np
>>> pipe = flowpipe(np.array([[-1.0]]), np.zeros((1, 0)), np.zeros(1),
...                 np.zeros(0), np.zeros(0), np.array([1.0]), np.array([1.0]), 0.5, 4)
>>> bool(abs(pipe.point_hi[4, 0] - np.exp(-2.0)) < 1e-9)
True
>>> bool(pipe.lo[0, 0] <= np.exp(-0.5) and pipe.hi[0, 0] >= 1.0)
True
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import expm

__all__ = ["FP_MARGIN", "Flowpipe", "Overflow", "exp_matrices", "flowpipe"]

FP_MARGIN = 1e-10
"""Relative widening of every box and error bound for the rounding of ``expm`` and products."""

Array = NDArray[np.float64]


class Overflow(ArithmeticError):
    """The bounds are not finite numbers (``|A| h`` too large for double precision)."""


def exp_matrices(a: Array, h: float) -> tuple[Array, Array, Array]:
    """``(e^{Ah}, Phi1, Phi2)``: ``Phi1 = sum A^k h^{k+1}/(k+1)!``, ``Phi2 = sum A^k h^{k+2}/(k+2)!``.

    All three are blocks of ``expm`` of the augmented matrix
    ``[[A, I, 0], [0, 0, I], [0, 0, 0]] * h`` (Le Guernic and Girard 2010, section 3.2).

    Examples
    --------
    >>> phi, phi1, phi2 = exp_matrices(np.array([[0.0]]), 2.0)
    >>> float(phi[0, 0]), float(phi1[0, 0]), float(phi2[0, 0])
    (1.0, 2.0, 2.0)
    """
    n = a.shape[0]
    big = np.zeros((3 * n, 3 * n))
    big[:n, :n] = a * h
    big[:n, n : 2 * n] = np.eye(n) * h
    big[n : 2 * n, 2 * n :] = np.eye(n) * h
    with np.errstate(over="ignore", invalid="ignore"):
        e = expm(big)
    return e[:n, :n], e[:n, n : 2 * n], e[:n, 2 * n :]


@dataclass(frozen=True)
class Flowpipe:
    """Box hulls of a flowpipe.

    ``tau[k]`` is the local time of step point ``k`` (``k * h``);
    ``point_lo[k], point_hi[k]`` bound the reachable states at ``tau[k]``;
    ``lo[k], hi[k]`` bound them over ``[tau[k], tau[k+1]]``. ``lo`` may be
    shorter than the steps asked for when ``keep`` stopped the computation.
    """

    tau: Array
    lo: Array
    hi: Array
    point_lo: Array
    point_hi: Array


def _widen(lo: Array, hi: Array) -> tuple[Array, Array]:
    pad = FP_MARGIN * np.maximum(np.abs(lo), np.abs(hi)) + 1e-300
    return lo - pad, hi + pad


BLOCK_ENTRIES = 1 << 18
"""Entries of the powers of ``Phi`` held at once (2 MiB): the steps of a block are computed
together, ``max(1, BLOCK_ENTRIES // n^2)`` of them, at most a chunk."""


def _steps(
    k0: int,
    m: int,
    phi: Array,
    p: Array,
    center: Array,
    inputs: Array,
    r0: Array,
    phi1_vc: Array,
    hvc: Array,
    e_omega: Array,
    err_in: Array,
    driven: tuple[float, Array, Array, Array] | None,
    point_lo: Array,
    point_hi: Array,
    seg_lo: Array,
    seg_hi: Array,
) -> tuple[Array, Array, Array]:
    """Steps ``k0 .. k0 + m - 1``: their segments and the step points after them, written in
    place; returns ``Phi^(k0+m)``, the centre and the inputs' radius after them.

    The recurrences (the powers of ``Phi``, the centres, the inputs' radius, added
    step by step in the same order) run one step at a time; everything else is
    computed for the ``m`` steps at once (the module docstring gives each bound).
    """
    n = phi.shape[0]
    powers = np.empty((m + 1, n, n))
    centers = np.empty((m + 1, n))
    moved = np.empty((m, n))
    powers[0], centers[0] = p, center
    for i in range(m):
        powers[i + 1] = phi @ powers[i]
        moved[i] = phi @ centers[i]
        centers[i + 1] = moved[i] + phi1_vc
    if driven is None:
        radius = np.abs(powers[1:]) @ r0 + inputs
        after = inputs
    else:  # inputs_{k+1} = inputs_k + h |P_k B| ur + |P_k| E_in |B| ur, added in that order
        h, b, u_r, ein_bu = driven
        terms = np.empty((2 * m + 1, n))
        terms[0] = inputs
        terms[1::2] = h * (np.abs(powers[:m] @ b) @ u_r)
        terms[2::2] = np.abs(powers[:m]) @ ein_bu
        sums = np.cumsum(terms, axis=0)[2::2]
        radius = np.abs(powers[1:]) @ r0 + sums
        after = sums[-1]
    here, ahead = slice(k0, k0 + m), slice(k0 + 1, k0 + m + 1)
    point_lo[ahead] = centers[1:] - radius
    point_hi[ahead] = centers[1:] + radius
    magnitude = np.maximum(np.abs(point_lo[here]), np.abs(point_hi[here]))
    err = magnitude @ e_omega.T + err_in
    far = moved + hvc
    seg_lo[here] = np.minimum(point_lo[here], far - radius) - err
    seg_hi[here] = np.maximum(point_hi[here], far + radius) + err
    return powers[m], centers[m], after


def flowpipe(
    a: Array,
    b: Array,
    c: Array,
    u_lo: Array,
    u_hi: Array,
    x_lo: Array,
    x_hi: Array,
    h: float,
    steps: int,
    keep: Callable[[int, Array, Array], int] | None = None,
    chunk: int = 256,
) -> Flowpipe:
    """Box hulls of the states reached from ``[x_lo, x_hi]`` in ``steps`` steps of ``h``.

    Parameters
    ----------
    a, b, c
        ``x' = a x + b u + c`` (``n x n``, ``n x m``, ``n``).
    u_lo, u_hi
        The input box (``m``); ``u`` may take any value in it at any time.
    x_lo, x_hi
        The initial box.
    h, steps
        Step and number of steps (the local horizon is ``steps * h``).
    keep
        Called with ``(k, lo, hi)``: the segments ``k, k+1, ...`` computed since
        the last call (every ``chunk`` segments and at the end); it returns how
        many of them to keep, and fewer than given stops the computation there
        (an invariant left for good).

    Returns
    -------
    Flowpipe
        See :class:`Flowpipe`; every bound's justification is in the module docstring.

    Examples
    --------
    The rotation ``x' = y, y' = -x`` from the point ``(1, 0)`` stays on the unit circle.

    >>> rot = np.array([[0.0, 1.0], [-1.0, 0.0]])
    >>> p = flowpipe(rot, np.zeros((2, 0)), np.zeros(2), np.zeros(0), np.zeros(0),
    ...              np.array([1.0, 0.0]), np.array([1.0, 0.0]), 0.01, 157)
    >>> bool(np.all(p.hi[:, 0] >= np.cos(np.linspace(0.0, 1.57, 158)[1:]) - 1e-12))
    True
    """
    n = a.shape[0]
    phi, phi1, _ = exp_matrices(a, h)
    abs_a = np.abs(a)
    _, _, phi2_abs = exp_matrices(abs_a, h)
    grow = 1.0 + FP_MARGIN
    with np.errstate(over="ignore", invalid="ignore"):
        e_in = (abs_a @ phi2_abs) * grow
        e_omega = (phi2_abs @ np.abs(a @ a)) * grow
    if not (
        np.all(np.isfinite(e_in)) and np.all(np.isfinite(e_omega)) and np.all(np.isfinite(phi))
    ):
        raise Overflow("the error bounds of one step overflow")
    u_c = (u_lo + u_hi) / 2.0
    u_r = (u_hi - u_lo) / 2.0 * grow
    v_c = c + b @ u_c
    v_abs = np.abs(v_c) + np.abs(b) @ u_r
    b_u = np.abs(b) @ u_r
    ein_bu = e_in @ b_u
    err_in = e_in @ v_abs
    hvc = h * v_c
    phi1_vc = phi1 @ v_c

    center = (x_lo + x_hi) / 2.0
    r0 = (x_hi - x_lo) / 2.0 * grow
    p = np.eye(n)
    inputs = np.zeros(n)
    point_lo = np.empty((steps + 1, n))
    point_hi = np.empty((steps + 1, n))
    seg_lo = np.empty((steps, n))
    seg_hi = np.empty((steps, n))
    point_lo[0], point_hi[0] = center - r0, center + r0
    has_inputs = b.shape[1] > 0 and bool(np.any(u_r > 0.0))
    block = max(1, min(chunk, BLOCK_ENTRIES // max(1, n * n)))  # steps whose powers of Phi are held
    done = steps
    for first in range(0, steps, chunk):
        last = min(first + chunk, steps)
        for k0 in range(first, last, block):
            p, center, inputs = _steps(
                k0, min(k0 + block, last) - k0, phi, p, center, inputs, r0, phi1_vc, hvc,
                e_omega, err_in, (h, b, u_r, ein_bu) if has_inputs else None,
                point_lo, point_hi, seg_lo, seg_hi,
            )  # fmt: skip
        part = slice(first, last)
        seg_lo[part], seg_hi[part] = _widen(seg_lo[part], seg_hi[part])
        if not (np.all(np.isfinite(seg_lo[part])) and np.all(np.isfinite(seg_hi[part]))):
            raise Overflow("the bounds overflow")
        if keep is not None:
            kept = keep(first, seg_lo[part], seg_hi[part])
            if kept < last - first:
                done = first + kept
                break
    point_lo[: done + 1], point_hi[: done + 1] = _widen(point_lo[: done + 1], point_hi[: done + 1])
    tau = np.arange(done + 1, dtype=np.float64) * h
    return Flowpipe(tau, seg_lo[:done], seg_hi[:done], point_lo[: done + 1], point_hi[: done + 1])
