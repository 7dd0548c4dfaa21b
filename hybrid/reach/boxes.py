"""Boxes against linear conditions and affine maps: the set operations of a jump.

Every function here over-approximates: a box contracted by a condition holds
every point of the box that satisfies it (interval constraint propagation), and
the image of a box by an affine map holds the image of every point (interval
arithmetic of ``R x + S u + r``, exact for one map of a box).

Conditions are widened by :data:`SLACK` relative to their magnitude over the
box: the simulator decides a guard or an invariant up to a band and finds event
points up to its tolerance (docs/semantics.md), so a run may jump or stop a
hair outside the exact condition. Widening a condition only adds states: the
over-approximation stays sound. The simulator's band grows with the largest
``|x_i|`` of the whole state, not only of the variables a condition reads
(``1e-10 (1 + max_i |x_i|)``): a run with one variable near 1e9 takes a guard
``y >= 0`` at ``y = -0.05``. The caller gives that band (:func:`band`) of each
box; it is added to every row.

Examples
--------
>>> import numpy as np
>>> from hybrid.reach.affine import Rows
>>> x_plus_y_le_1 = Rows(np.array([[1.0, 1.0]]), np.array([1.0]))
>>> lo, hi = contract(np.array([0.0, 0.5]), np.array([2.0, 2.0]), x_plus_y_le_1)
>>> [round(v, 6) for v in hi.tolist()]
[0.5, 1.0]
>>> contract(np.array([2.0, 2.0]), np.array([3.0, 3.0]), x_plus_y_le_1) is None
True
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from hybrid.expr.rho import BAND
from hybrid.reach.affine import Condition, Rows

__all__ = [
    "BAND",
    "SLACK",
    "affine_image",
    "band",
    "contract",
    "contract_many",
    "meets",
    "meets_many",
]

Array = NDArray[np.float64]
SLACK = 1e-7
"""Relative widening of a condition's right-hand side (see the module docstring)."""


def band(lo: Array, hi: Array, columns: int) -> Array:
    """The simulator's band ``BAND (1 + max_i |x_i|)`` over each box's first ``columns``
    columns (the state; later ones, such as time, are not in it), at least.

    Examples
    --------
    >>> band(np.array([[-1e9, 0.0, 5.0]]), np.array([[2.0, 1.0, 6.0]]), 2).round(12).tolist()
    [0.1000000001]
    """
    if columns == 0:
        return np.full(lo.shape[:-1], BAND)
    big: Array = np.maximum(np.abs(lo[..., :columns]), np.abs(hi[..., :columns])).max(axis=-1)
    return BAND * (1.0 + big) * (1.0 + 4e-16)


def contract(
    lo: Array, hi: Array, rows: Rows, passes: int = 3, widen: float = 0.0
) -> tuple[Array, Array] | None:
    """The box ``[lo, hi]`` narrowed to the rows ``mat @ x <= vec + widen``; ``None`` if none
    meets them.

    Each pass bounds every variable of every row by the row's right-hand side
    minus the least value of the row's other terms over the box: a point of
    the box satisfying the row satisfies that bound, so no such point is lost.
    """
    if rows.mat.shape[0] == 0:
        return lo, hi
    lo, hi = lo.copy(), hi.copy()
    mat = rows.mat
    pos = mat > 0.0
    neg = mat < 0.0
    for _ in range(passes):
        scale = np.abs(mat) @ np.maximum(np.abs(lo), np.abs(hi))
        vec = rows.vec + SLACK * (1.0 + scale + np.abs(rows.vec)) + widen
        low_terms = np.where(pos, mat * lo, np.where(neg, mat * hi, 0.0))
        least = low_terms.sum(axis=1)
        if np.any(least > vec):
            return None
        rest = least[:, None] - low_terms
        with np.errstate(divide="ignore", invalid="ignore"):
            bound = (vec[:, None] - rest) / np.where(mat != 0.0, mat, 1.0)
        upper = np.where(pos, bound, np.inf).min(axis=0)
        lower = np.where(neg, bound, -np.inf).max(axis=0)
        lo = np.maximum(lo, lower)
        hi = np.minimum(hi, upper)
        if np.any(lo > hi):
            return None
    return lo, hi


def contract_many(
    lo: Array, hi: Array, rows: Rows, passes: int = 3, widen: Array | float = 0.0
) -> tuple[Array, Array, Array]:
    """:func:`contract` of each box ``lo[k], hi[k]`` at once (widened by ``widen[k]``):
    ``(lo, hi, nonempty)``.

    Examples
    --------
    >>> from hybrid.reach.affine import Rows
    >>> x_le_1 = Rows(np.array([[1.0]]), np.array([1.0]))
    >>> lo, hi, ok = contract_many(np.array([[0.0], [2.0]]), np.array([[3.0], [3.0]]), x_le_1)
    >>> ok.tolist(), round(float(hi[0, 0]), 6)
    ([True, False], 1.0)
    """
    ok = np.ones(lo.shape[0], dtype=bool)
    if rows.mat.shape[0] == 0:
        return lo, hi, ok
    cols = np.flatnonzero(np.any(rows.mat != 0.0, axis=0))
    extra = np.broadcast_to(np.asarray(widen, dtype=float), lo.shape[:1])
    c_lo, c_hi, ok = _contract_columns(
        lo[:, cols], hi[:, cols], rows.mat[:, cols], rows.vec, passes, extra
    )
    lo, hi = lo.copy(), hi.copy()
    lo[:, cols], hi[:, cols] = c_lo, c_hi
    return lo, hi, ok


def _contract_columns(
    lo: Array, hi: Array, full: Array, rhs: Array, passes: int, widen: Array
) -> tuple[Array, Array, Array]:
    """:func:`contract_many` on the columns the rows read (the others do not change)."""
    ok = np.ones(lo.shape[0], dtype=bool)
    rows = Rows(full, rhs)
    mat = full[None, :, :]
    pos = mat > 0.0
    neg = mat < 0.0
    safe = np.where(mat != 0.0, mat, 1.0)
    for _ in range(passes):
        scale = np.maximum(np.abs(lo), np.abs(hi)) @ np.abs(rows.mat).T
        vec = rows.vec[None, :] + SLACK * (1.0 + scale + np.abs(rows.vec)[None, :])
        vec = vec + widen[:, None]
        low_terms = np.where(pos, mat * lo[:, None, :], np.where(neg, mat * hi[:, None, :], 0.0))
        least = low_terms.sum(axis=2)
        ok &= ~np.any(least > vec, axis=1)
        bound = (vec[:, :, None] - (least[:, :, None] - low_terms)) / safe
        upper = np.where(pos, bound, np.inf).min(axis=1)
        lower = np.where(neg, bound, -np.inf).max(axis=1)
        lo = np.maximum(lo, lower)
        hi = np.minimum(hi, upper)
        ok &= ~np.any(lo > hi, axis=1)
    return lo, hi, ok


def meets_many(
    lo: Array, hi: Array, condition: Condition, widen: Array | float = 0.0
) -> tuple[Array, Array, Array]:
    """:func:`meets` of each box at once (widened by ``widen[k]``): ``(lo, hi, nonempty)``."""
    out_lo = np.full_like(lo, np.inf)
    out_hi = np.full_like(hi, -np.inf)
    any_ok = np.zeros(lo.shape[0], dtype=bool)
    for case in condition:
        c_lo, c_hi, ok = contract_many(lo, hi, case, widen=widen)
        out_lo = np.where(ok[:, None], np.minimum(out_lo, c_lo), out_lo)
        out_hi = np.where(ok[:, None], np.maximum(out_hi, c_hi), out_hi)
        any_ok |= ok
    return out_lo, out_hi, any_ok


def meets(
    lo: Array, hi: Array, condition: Condition, widen: float = 0.0
) -> tuple[Array, Array] | None:
    """The hull of the box contracted by each case of ``condition`` (its rows widened by
    ``widen``); ``None`` if no case meets it."""
    found: tuple[Array, Array] | None = None
    for case in condition:
        box = contract(lo, hi, case, widen=widen)
        if box is None:
            continue
        found = (
            box if found is None else (np.minimum(found[0], box[0]), np.maximum(found[1], box[1]))
        )
    return found


def affine_image(
    lo: Array, hi: Array, rmat: Array, smat: Array, rvec: Array, u_lo: Array, u_hi: Array
) -> tuple[Array, Array]:
    """The box hull of ``{R x + S u + r : x in [lo, hi], u in [u_lo, u_hi]}``, widened for rounding.

    Examples
    --------
    >>> r = np.array([[0.0, 1.0], [-1.0, 0.0]])
    >>> lo, hi = affine_image(np.array([0.0, 1.0]), np.array([1.0, 2.0]), r, np.zeros((2, 0)),
    ...                       np.array([0.0, 0.5]), np.zeros(0), np.zeros(0))
    >>> [round(v, 9) for v in lo.tolist()], [round(v, 9) for v in hi.tolist()]
    ([1.0, -0.5], [2.0, 0.5])
    """
    xc, xr = (lo + hi) / 2.0, (hi - lo) / 2.0
    uc, ur = (u_lo + u_hi) / 2.0, (u_hi - u_lo) / 2.0
    center = rmat @ xc + smat @ uc + rvec
    radius = np.abs(rmat) @ xr + np.abs(smat) @ ur
    pad = 1e-12 * (np.abs(center) + radius) + 1e-300
    return center - radius - pad, center + radius + pad
