"""Quick refutation: the support's maximisers, step by step, before any flowpipe.

For an affine flow ``x' = A x + B u + c`` from a box ``X0`` with inputs held
constant on each step ``[i h, (i+1) h]`` (any value of their box ``U``), the
state at step ``k`` is ``x_k = Phi^k x0 + sum_{i<k} Phi^{k-1-i} (G u_i + g)``
with ``Phi = e^{Ah}``, ``G = Phi1 B``, ``g = Phi1 c``. Its maximum in a direction
``d`` is attained by a concrete run (:func:`hybrid.reach.witness.support_candidate`):
``x0`` at the corner of ``X0`` that ``w_k = (Phi^T)^k d`` points to, ``u_i`` at
the corner of ``U`` that ``G^T w_{k-1-i}`` points to, and its value is

    s_k = w_k . c0 + |w_k| . r0 + sum_{m<k} (G^T w_m . uc + |G^T w_m| . ur + w_m . g)

(``c0, r0``: centre and radius of ``X0``; ``uc, ur`` of ``U``): the sum runs over
the same ``w_m`` for every ``k``, so one sequence ``w_0 = d, w_1, ...`` gives
``s_k`` for every step in ``O(k n^2)``. That is an *under*-approximation of the
reachable set (step-wise constant inputs, step points only), so it can refute
and never prove. :func:`refute` walks it along a forbidden case's own
direction, in blocks of :data:`BLOCK` steps, and stops at the first step whose
maximiser enters the case by a relative margin :data:`ENTER` (so that a replay,
simulated at tolerances a thousand times smaller, enters it too). The run it
returns is checked exactly, without a simulation:

- its step points ``x_0 ... x_k`` are propagated with the same matrices, and the
  last must be inside every row of the case with a margin of
  :data:`MARGIN` relative to the row's magnitude (rounding of ``expm`` and of
  ``k`` products, measured near 1e-13; the margin covers it by five orders);
- it must be a run of the model: between two step points the state lies in the
  box hull of both, bloated by ``E_Omega |x_i| + 2 E_in |v_i|`` (the flowpipe's
  between-step bounds for one point and one input value,
  :mod:`hybrid.reach.flowpipe`; zero on a coordinate whose flow is a constant,
  as a clock's). On every such box the location's invariant holds for every
  input value, up to the simulator's band (a boundary touched, not passed), and
  every guard of an edge out of it fails for every input value, by more than
  that band: no jump is forced and time may pass. Conditions on clocks (``t``
  among them) hold as written too, a strict one strictly. ``cond`` itself must be read ``for all u``
  (:meth:`hybrid.reach.affine.Forms.condition`): the end point is in it
  whatever the input's value there. A
  location that is urgent, or a run that may meet a guard, is left to the
  simulated search.

Examples
--------
>>> import hybrid
>>> from hybrid.reach.affine import Forms
>>> from hybrid.reach.engine import initial_boxes, mode_of
>>> m = hybrid.load_text('''
... automaton: heater
... state: {x: {initial: [18, 19]}}
... inputs: {u: {range: [0, 1]}}
... locations: {on: {flow: {x: -0.1 * x + 2 + u}}}
... properties: {forbidden: [{when: x > 25}]}
... ''')
>>> from hybrid.compose import as_system
>>> forms = Forms(as_system(m))
>>> key, lo, hi = initial_boxes(forms)[0]
>>> cond = forms.condition(m.properties.forbidden[0].when, 0, key, m.position, "x > 25")
>>> found = refute(forms, mode_of(forms, key), lo, hi, cond, t_end=10.0, step=0.05)
>>> found is not None and found.point[0] >= 25.0 and found.candidate.initial["x"] == 19.0
True
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from hybrid.reach.affine import TIME, Condition, Forms, Rows
from hybrid.reach.boxes import band
from hybrid.reach.engine import Mode
from hybrid.reach.flowpipe import FP_MARGIN, exp_matrices
from hybrid.reach.witness import Candidate
from hybrid.simulation.inputs import PiecewiseConstant

__all__ = ["BLOCK", "ENTER", "MARGIN", "Refutation", "entry_time", "refute"]

Array = NDArray[np.float64]
BLOCK = 32
"""Steps of the support computed at once (one matrix product per block)."""
MARGIN = 1e-8
"""Relative margin by which the propagated end point must be inside the forbidden case."""
ENTER = 1e-6
"""Relative margin of the support over the case's bound at the step aimed at: a hundred
times :data:`MARGIN`, and a thousand times the tolerances a replay is simulated with."""
GUARD_TOL = 1e-9
"""Relative widening of a guard's bound, on top of the simulator's band, before a run's
segment counts as failing it (rounding of the propagated points)."""


@dataclass(frozen=True)
class Refutation:
    """A run into a forbidden case: the candidate to replay, its step count and end point.

    ``points`` are its step points ``x_0 ... x_k`` (the reach vector, time at
    ``k h``), ``inputs`` the input values held on each step (rows), ``h`` the step:
    what :func:`entry_time` follows between them.
    """

    candidate: Candidate
    steps: int
    at: float
    point: Array
    points: Array = field(repr=False)
    inputs: Array = field(repr=False)
    h: float


def _transition_matrices(a: Array, h: float) -> tuple[Array, Array]:
    """``(e^{Ah}, Phi1)`` from one ``expm`` of ``[[A, I], [0, 0]] h``."""
    from scipy.linalg import expm

    n = a.shape[0]
    big = np.zeros((2 * n, 2 * n))
    big[:n, :n] = a * h
    big[:n, n:] = np.eye(n) * h
    with np.errstate(over="ignore", invalid="ignore"):
        e = expm(big)
    return e[:n, :n], e[:n, n:]


def refute(
    forms: Forms,
    mode: Mode,
    x_lo: Array,
    x_hi: Array,
    cond: Condition,
    *,
    t_end: float,
    step: float,
) -> Refutation | None:
    """A run from ``[x_lo, x_hi]`` in ``mode`` into ``cond`` within ``t_end``, or ``None``.

    ``cond`` is over the reach vector (time last). Only a case with one row on
    the state is tried (with any rows on time and on clocks that start at a
    point: a step meets those or not, whichever the run); ``None`` means nothing was
    found this way, not that the case is unreachable.
    """
    if mode.urgent or not (math.isfinite(t_end) and t_end > 0.0 and step > 0.0):
        return None
    t_index = forms.index[TIME]
    # coordinates every run has at the same value at a given time: clocks from a point
    fixed = np.all(mode.a == 0.0, axis=1) & np.all(mode.b == 0.0, axis=1) & (x_lo == x_hi)
    fixed[t_index] = True
    matrices: dict[float, tuple[Array, Array]] = {}
    for case in cond:
        split = _split(case, fixed)
        if split is None:
            continue
        row, limit, side = split
        clocks = _Clocks(side, x_lo, mode.c)
        h = clocks.landing_step(step, t_end)
        total = math.floor(t_end / h + 1e-9)
        if total < 1:
            continue
        if h not in matrices:
            matrices[h] = _transition_matrices(mode.a, h)
        phi, phi1 = matrices[h]
        if not (np.all(np.isfinite(phi)) and np.all(np.isfinite(phi1))):
            continue
        found = _walk(forms, mode, phi, phi1, x_lo, x_hi, row, limit, clocks, total, h)
        if found is not None:
            return found
    return None


def _split(case: Rows, fixed: NDArray[np.bool_]) -> tuple[Array, float, Rows] | None:
    """The case's one row on the state, its bound, and its rows on ``fixed`` coordinates alone."""
    side = np.all(case.mat[:, ~fixed] == 0.0, axis=1)
    state = np.flatnonzero(~side)
    if len(state) != 1:
        return None
    strict = None if case.strict is None else case.strict[side]
    return case.mat[state[0]], float(case.vec[state[0]]), Rows(case.mat[side], case.vec[side], strict)


@dataclass(frozen=True)
class _Clocks:
    """Rows on the clocks that start at a point (time among them): their value at time ``t``
    is ``x0 + c t`` on every run, so a step either meets them or not."""

    rows: Rows
    x0: Array
    rate: Array

    def window(self) -> tuple[float, float]:
        """The times ``[a, b]`` the rows allow (their closure; ``a > b``: none)."""
        slope = self.rows.mat @ self.rate
        room = self.rows.vec - self.rows.mat @ self.x0
        a, b = 0.0, math.inf
        for s, r in zip(slope.tolist(), room.tolist(), strict=True):
            if s > 0.0:
                b = min(b, r / s)
            elif s < 0.0:
                a = max(a, r / s)
            elif r < 0.0:
                return math.inf, -math.inf
        return a, b

    def landing_step(self, step: float, t_end: float) -> float:
        """``step``, or a little less when the rows allow a window of time shorter than a
        step: then a step point falls on its end (``t == 20`` is met by no point of
        the steps of ``20.1 / 4000``; it is by those of ``20 / 3981``).

        >>> from hybrid.reach.affine import Rows
        >>> at_20 = _Clocks(Rows(np.array([[1.0], [-1.0]]), np.array([20.0, -20.0])),
        ...                 np.array([0.0]), np.array([1.0]))
        >>> h = at_20.landing_step(20.1 / 4000, 20.1)
        >>> round(20.0 / h, 9), h <= 20.1 / 4000
        (3981.0, True)
        """
        a, b = self.window()
        b = min(b, t_end)
        if not (a <= b and b > 0.0 and b - a < step):
            return step
        return b / math.ceil(b / step - 1e-9)

    def hold(self, t: Array) -> NDArray[np.bool_]:
        """Which times ``t`` satisfy the rows as written (a strict row strictly: ``c > 1``
        with ``c`` held at 1 never holds, nor ``t > 3`` at ``t = 3``)."""
        if len(self.rows.vec) == 0:
            return np.ones(len(t), dtype=bool)
        values = self.x0[None, :] + t[:, None] * self.rate[None, :]
        ok: NDArray[np.bool_] = np.all(self.rows.bound(values @ self.rows.mat.T), axis=1)
        return ok


def _walk(
    forms: Forms,
    mode: Mode,
    phi: Array,
    phi1: Array,
    x_lo: Array,
    x_hi: Array,
    row: Array,
    limit: float,
    clocks: _Clocks,
    total: int,
    h: float,
) -> Refutation | None:
    """Support of ``-row`` step by step; the first step whose maximiser has ``row . x <= limit``."""
    gain = phi1 @ mode.b
    drift = phi1 @ mode.c
    u_c = (forms.u_lo + forms.u_hi) / 2.0
    u_r = (forms.u_hi - forms.u_lo) / 2.0
    x_c = (x_lo + x_hi) / 2.0
    x_r = (x_hi - x_lo) / 2.0
    phi_t = phi.T
    powers = [np.eye(len(x_c))]
    for _ in range(BLOCK - 1):
        powers.append(powers[-1] @ phi_t)
    stack = np.stack(powers)  # stack[j] = (Phi^T)^j
    jump = powers[-1] @ phi_t  # (Phi^T)^BLOCK
    ws: list[Array] = []  # w_m = (Phi^T)^m d, blocks of BLOCK rows
    w = -row
    summed = 0.0
    first = 0
    while first <= total:
        block = stack @ w  # rows: w_first ... w_first+BLOCK-1
        ws.append(block)
        g = block @ gain
        terms = g @ u_c + np.abs(g) @ u_r + block @ drift
        before = summed + np.concatenate([[0.0], np.cumsum(terms)[:-1]])  # sum over m < k
        support = block @ x_c + np.abs(block) @ x_r + before  # s_k, k = first + j
        summed += float(terms.sum())
        w = jump @ w
        ks = first + np.arange(BLOCK)
        ok = (ks >= 1) & (ks <= total) & clocks.hold(ks.astype(np.float64) * h)
        gap = support + limit  # > 0: the maximiser has row . x < limit
        scale = np.abs(block) @ (np.abs(x_c) + x_r) + abs(limit)
        hits = np.flatnonzero(ok & (gap > ENTER * (1.0 + scale)))
        if len(hits):
            k = int(ks[hits[0]])
            break
        first += BLOCK
    else:
        return None
    matrices = (phi, gain, drift)
    return _concrete(forms, mode, matrices, (x_lo, x_hi), np.concatenate(ws), k, h, row, limit)


def _concrete(
    forms: Forms,
    mode: Mode,
    matrices: tuple[Array, Array, Array],
    box: tuple[Array, Array],
    w_all: Array,
    k: int,
    h: float,
    row: Array,
    limit: float,
) -> Refutation | None:
    """The maximiser aiming at step ``k``, propagated and checked (``None``: it fails a check)."""
    phi, gain, drift = matrices
    t_index = forms.index[TIME]
    x0 = np.where(w_all[k] > 0.0, box[1], box[0])
    coefs = w_all[:k] @ gain  # row m: G^T w_m, for the input at step k - 1 - m
    u = np.where(coefs[::-1] > 0.0, forms.u_hi, forms.u_lo)  # row i: the input on step i
    pushes = u @ gain.T + drift
    pts = np.empty((k + 1, len(x0)))
    pts[0] = x0
    for i in range(k):
        pts[i + 1] = phi @ pts[i] + pushes[i]
    end = pts[k].copy()
    end[t_index] = k * h
    margin = MARGIN * (1.0 + float(np.abs(row) @ np.abs(end)) + abs(limit))
    if not float(row @ end) <= limit - margin:
        return None
    if not _legal(mode, pts, u, h, t_index):
        return None
    starts = np.arange(k, dtype=np.float64) * h
    inputs: dict[str, Callable[[float], float]] = {}
    for j, name in enumerate(forms.inputs):
        keep = np.concatenate([[True], u[1:, j] != u[:-1, j]])  # switches only
        inputs[name] = PiecewiseConstant(starts[keep], u[keep, j].astype(np.float64))
    names = forms.system.state_names
    initial = {v: float(x0[i]) for i, v in enumerate(names)}
    candidate = Candidate(initial, inputs, k * h, "support, propagated exactly")
    return Refutation(candidate, k, k * h, end, pts, u, h)


def entry_time(found: Refutation, mode: Mode, condition: Condition, t_index: int) -> float:
    """When the run of ``found`` first enters ``condition`` (rows as written, a strict row
    strictly), followed exactly: no later than ``found.at``, where the walk saw it inside.

    Each step is looked at in its step points and at :data:`~hybrid.reach.witness.BETWEEN`
    parts between them (the state there propagated from the step's start with the step's
    input: ``e^{A d} x_i + Phi1(d) (B u_i + c)``, one matrix pair for all steps); the time
    is then bisected after the last sample seen outside, each middle propagated from the
    step's start by its own ``expm``. A visit shorter than a part may be missed, as a
    simulated witness's between its points (:func:`hybrid.reach.witness.reaches`).

    Examples
    --------
    >>> import hybrid
    >>> from hybrid.compose import as_system
    >>> from hybrid.reach.affine import Forms
    >>> from hybrid.reach.engine import initial_boxes, mode_of
    >>> m = hybrid.load_text('''
    ... automaton: ramp
    ... state: {x: {initial: [0.5, 0.6]}}
    ... locations: {l: {flow: {x: 1}}}
    ... properties: {forbidden: [{when: x >= 1}]}
    ... ''')
    >>> forms = Forms(as_system(m))
    >>> key, lo, hi = initial_boxes(forms)[0]
    >>> mode = mode_of(forms, key)
    >>> cond = forms.condition(m.properties.forbidden[0].when, 0, key, m.position, "x >= 1")
    >>> found = refute(forms, mode, lo, hi, cond, t_end=2.0, step=0.3)
    >>> found.at, entry_time(found, mode, cond, forms.index["t"])  # from 0.6: x = 1 at 0.4
    (0.6, 0.4)
    """
    from hybrid.reach.witness import BETWEEN, bisect_entry, inside

    pts, u, h, k = found.points.copy(), found.inputs, found.h, found.steps
    pts[:, t_index] = np.arange(k + 1) * h  # the walk's times, as it tested its clocks
    if inside(pts[:1], condition)[0]:
        return 0.0
    sub_phi, sub_phi1 = _transition_matrices(mode.a, h / BETWEEN)
    forcing = u @ mode.b.T + mode.c  # row i: B u_i + c, held on step i
    sub_push = forcing @ sub_phi1.T
    samples = [pts[:-1]]
    for part in range(1, BETWEEN):
        samples.append(samples[-1] @ sub_phi.T + sub_push)
        samples[-1][:, t_index] = (np.arange(k) + part / BETWEEN) * h
    samples.append(pts[1:])
    grid = np.stack(samples[1:], axis=1)  # [step, sample]: its parts, then its end
    hits = inside(grid.reshape(k * BETWEEN, -1), condition).reshape(k, BETWEEN)
    if not hits.any():
        return found.at
    i, part = divmod(int(np.argmax(hits.ravel())), BETWEEN)  # inside at sample part + 1 of step i
    before = i * h + part * h / BETWEEN
    after = (i + 1) * h if part + 1 == BETWEEN else i * h + (part + 1) * h / BETWEEN
    start, push = pts[i], forcing[i]

    def state(t: float) -> Array:  # the run at time t of step i (time, the last column, left out)
        e, e1 = _transition_matrices(mode.a, t - i * h)
        x: Array = e @ start + e1 @ push
        return x[:t_index]

    return bisect_entry(before, after, condition, state)


def _legal(mode: Mode, pts: Array, u: Array, h: float, t_index: int) -> bool:
    """Whether the run through ``pts`` keeps ``mode``'s invariant and meets none of its guards
    (the state is in the columns before ``t_index``)."""
    a, b, c = mode.a, mode.b, mode.c
    clock = np.all(a == 0.0, axis=1) & np.all(b == 0.0, axis=1)
    conditions = [*mode.invariant_all, *(case for tr in mode.transitions for case in tr.guard)]
    lo = np.minimum(pts[:-1], pts[1:])
    hi = np.maximum(pts[:-1], pts[1:])
    if any(bool(np.any(rows.mat[:, ~clock] != 0.0)) for rows in conditions):
        abs_a = np.abs(a)
        _, _, phi2_abs = exp_matrices(abs_a, h)
        grow = 1.0 + FP_MARGIN
        e_in = (abs_a @ phi2_abs) * grow
        e_omega = (phi2_abs @ np.abs(a @ a)) * grow
        v = np.abs(u @ b.T + c)
        err = np.abs(pts[:-1]) @ e_omega.T + 2.0 * v @ e_in.T
        if not np.all(np.isfinite(err)):
            return False
        lo, hi = lo - err, hi + err
    pad = FP_MARGIN * np.maximum(np.abs(lo), np.abs(hi))
    lo, hi = lo - pad, hi + pad
    # the simulator decides the invariant and the guards within its band of their boundary:
    # a run that touches the invariant's boundary (within the band) holds it there, one
    # that goes further is blocked; a guard failing by more than the band is failing
    near = band(lo, hi, t_index)[:, None]
    if not any(bool(np.all(_top(r, lo, hi) <= r.vec[None, :] + near)) for r in mode.invariant_all):
        return False  # the invariant may fail on some segment
    for tr in mode.transitions:
        for rows in tr.guard:
            # every segment needs a row of the case that fails throughout it
            false = np.any(_bottom(rows, lo, hi) > _bound(rows, lo, hi) + near, axis=1)
            if not bool(np.all(false)):
                return False
    return True


def _top(rows: Rows, lo: Array, hi: Array) -> Array:
    """Per box and row, the largest ``mat . x`` over the box."""
    pos, neg = np.maximum(rows.mat, 0.0), np.minimum(rows.mat, 0.0)
    return hi @ pos.T + lo @ neg.T


def _bottom(rows: Rows, lo: Array, hi: Array) -> Array:
    """Per box and row, the smallest ``mat . x`` over the box."""
    pos, neg = np.maximum(rows.mat, 0.0), np.minimum(rows.mat, 0.0)
    return lo @ pos.T + hi @ neg.T


def _bound(rows: Rows, lo: Array, hi: Array) -> Array:
    """Per box and row, ``vec`` widened by :data:`GUARD_TOL` relative to the row's magnitude."""
    size = np.maximum(np.abs(lo), np.abs(hi)) @ np.abs(rows.mat).T
    return rows.vec[None, :] + GUARD_TOL * (1.0 + size + np.abs(rows.vec)[None, :])
