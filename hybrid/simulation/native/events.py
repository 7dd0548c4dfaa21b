"""Kernel source: the watch of a stay, as :class:`hybrid.simulation.events.Watch` keeps it.

The watch is the smallest of every guard's rho and every invariant's ``-rho``;
``inf`` when the mode has neither. An *armed* guard takes part in its
*oriented* form (each equality atom ``a == b`` read one-sided, ``S * (a - b) <= 0``,
``S`` the sign of ``a - b`` when the guard armed: the sign slots of the run's
parameter vector; ``S = 0``, a state exactly on the level then, reads the atom
itself, ``|a - b|``), an armed invariant with its ``-rho``. A *disarmed* term
is watched from the far edge of the band (docs/semantics.md, "Re-arming"): a
guard as its plain rho plus ``b0`` (its sign slots 0, so its oriented form is
its plain rho), an invariant as ``-rho + b0``, ``b0`` the band at the start of
the stay (``S_B0``). A term that cannot be evaluated is left out (the failure
is recorded). Function by function:

- :func:`watch_start` is ``Watch.__init__``: the guards armed at entry
  (``tr_armed``, set by ``enabled_at_entry``) oriented at the start point (a
  level within the band by the side the flow moves to, :func:`orient_by_slope`);
  invariants armed when their rho is below the band; ``b0``;
- :func:`watch_terms` and :func:`watch_value` are the watch function (one
  call of the model's ``OP_WATCH`` for every term, then the minimum);
- :func:`arm_at` is ``Watch.arm``: a disarmed guard whose plain rho is beyond
  the band is armed with the orientation there; a level of an armed guard read
  on it (``S = 0``) is oriented once the state is beyond the band of it; a
  disarmed invariant whose ``-rho`` is beyond the band is armed;
- :func:`pending` is ``Watch.pending``. The generation counter ``S_GEN``
  (``Watch.generation``) changes each time the watch does.

Copied into the kernel module (below the ``kernel`` marker).
"""

from __future__ import annotations

import math

from hybrid.simulation.native.boundary import band, note_failure, step_ahead, value_checked
from hybrid.simulation.native.buffers import (
    F_GUARD,
    F_INVARIANT,
    OP_ARM,
    OP_WATCH,
    S_B0,
    S_GEN,
    T_INV_RHO,
    T_MODE_INV,
    T_MODE_TR,
    T_N_PARAMS,
    T_TR_LV,
    W_AHEAD,
    W_ARMV,
    W_D,
    W_ENABLED,
    W_INVARMED,
    W_PE,
    W_SCAL,
    W_TERMS,
    W_TRARMED,
)
from hybrid.simulation.native.kernel_types import Array, Fns, Ints, at

__all__ = ["arm_at", "far_edge_guards", "far_edge_left", "orient_by_slope", "orientation", "pending", "watch_at", "watch_min", "watch_start", "watch_terms",
           "watch_value"]

# --- kernel ---


def orientation(value: float, tr: int, m: int, t: float, x: Array, wf: Array, wi: Ints) -> float:
    """The side of a level ``a - b = value``: 1, -1, or 0 exactly on it (a NaN is recorded)."""
    if value > 0.0:
        return 1.0
    if value < 0.0:
        return -1.0
    if value != value:
        note_failure(F_GUARD, tr, m, t, x, wf, wi)
    return 0.0


def orient_by_slope(fns: Fns, tab: Ints, m: int, k: int, t: float, x: Array, width: float,
                    wf: Array, wi: Ints) -> None:  # fmt: skip
    """Each level of armed guard ``k`` within ``width`` of ``(t, x)`` takes the side the flow
    moves it to when its slope is beyond ``width`` (``events.orientation``).

    ``armv`` must hold the model's ``OP_ARM`` values at ``(t, x)``, and holds them again after.
    """
    first = tab[tab[T_MODE_TR] + m]
    n_tr = tab[tab[T_MODE_TR] + m + 1] - first
    lv0 = tab[tab[T_TR_LV] + first]
    tr = first + k
    signs = wi[W_PE] + tab[T_N_PARAMS]
    armv = wf[wi[W_ARMV] :]
    h = 0.0  # the slope test's step, and its point in `ahead`, once a level needs them
    for a in range(tab[tab[T_TR_LV] + tr] - lv0, tab[tab[T_TR_LV] + tr + 1] - lv0):
        value = armv[n_tr + a]
        if not abs(value) <= width:
            continue
        if h == 0.0:
            h = step_ahead(fns, m, t, x, wf, wi)
        ahead = wf[wi[W_AHEAD] : wi[W_AHEAD] + wi[W_D]]
        fns(OP_ARM, m, t + h, at(ahead, 0), at(wf, wi[W_PE]), at(wf, wi[W_ARMV]))
        later = armv[n_tr + a]
        fns(OP_ARM, m, t, at(x, 0), at(wf, wi[W_PE]), at(wf, wi[W_ARMV]))
        rate = (later - value) / h
        if rate > width:
            wf[signs + a] = 1.0
        elif rate < -width:
            wf[signs + a] = -1.0


def watch_start(fns: Fns, tab: Ints, m: int, t: float, x: Array, wf: Array,
                wi: Ints) -> None:  # fmt: skip
    """The watch of a stay starting at ``(t, x)`` (``Watch.__init__``)."""
    width = band(x)
    first = tab[tab[T_MODE_TR] + m]
    n_tr = tab[tab[T_MODE_TR] + m + 1] - first
    lv0 = tab[tab[T_TR_LV] + first]
    signs = wi[W_PE] + tab[T_N_PARAMS]
    armv = wf[wi[W_ARMV] :]
    if tab[tab[T_TR_LV] + first + n_tr] > lv0:  # some guard has levels: orient them
        fns(OP_ARM, m, t, at(x, 0), at(wf, wi[W_PE]), at(wf, wi[W_ARMV]))
    for k in range(n_tr):
        tr = first + k
        armed = wi[wi[W_TRARMED] + k] != 0
        for a in range(tab[tab[T_TR_LV] + tr] - lv0, tab[tab[T_TR_LV] + tr + 1] - lv0):
            wf[signs + a] = orientation(armv[n_tr + a], tr, m, t, x, wf, wi) if armed else 0.0
        if armed:
            orient_by_slope(fns, tab, m, k, t, x, width, wf, wi)
    inv0 = tab[tab[T_MODE_INV] + m]
    for k in range(tab[tab[T_MODE_INV] + m + 1] - inv0):
        inv = inv0 + k
        rho = value_checked(fns, tab[tab[T_INV_RHO] + inv], F_INVARIANT, inv, m, t, x, wf, wi)
        wi[wi[W_INVARMED] + k] = 1 if rho < -width else 0
    wf[wi[W_SCAL] + S_B0] = width
    wf[wi[W_SCAL] + S_GEN] += 1.0


def pending(tab: Ints, m: int, wf: Array, wi: Ints) -> bool:
    """Whether some guard or invariant of the watch is disarmed, or a level read on it (0)."""
    first = tab[tab[T_MODE_TR] + m]
    lv0 = tab[tab[T_TR_LV] + first]
    signs = wi[W_PE] + tab[T_N_PARAMS]
    for k in range(tab[tab[T_MODE_TR] + m + 1] - first):
        if wi[wi[W_TRARMED] + k] == 0:
            return True
        tr = first + k
        for a in range(tab[tab[T_TR_LV] + tr] - lv0, tab[tab[T_TR_LV] + tr + 1] - lv0):
            if wf[signs + a] == 0.0:
                return True
    inv0 = tab[tab[T_MODE_INV] + m]
    for k in range(tab[tab[T_MODE_INV] + m + 1] - inv0):  # noqa: SIM110 (compiled: a plain loop)
        if wi[wi[W_INVARMED] + k] == 0:
            return True
    return False


def watch_terms(fns: Fns, m: int, t: float, x: Array, wf: Array, wi: Ints) -> None:
    """Every term of the watch at ``(t, x)`` into ``terms``: oriented rhos, then invariants' rhos."""
    fns(OP_WATCH, m, t, at(x, 0), at(wf, wi[W_PE]), at(wf, wi[W_TERMS]))


def watch_value(tab: Ints, m: int, t: float, x: Array, wf: Array, wi: Ints) -> float:
    """The watch from ``terms`` (``inf``: no term); the first failing term is recorded."""
    first = tab[tab[T_MODE_TR] + m]
    n_tr = tab[tab[T_MODE_TR] + m + 1] - first
    inv0 = tab[tab[T_MODE_INV] + m]
    n_inv = tab[tab[T_MODE_INV] + m + 1] - inv0
    terms = wi[W_TERMS]
    tr_armed, inv_armed = wi[W_TRARMED], wi[W_INVARMED]
    b0 = wf[wi[W_SCAL] + S_B0]
    v = math.inf
    for k in range(n_tr):
        w = wf[terms + k] if wi[tr_armed + k] != 0 else wf[terms + k] + b0
        if w < v:
            v = w
        elif w != w:
            note_failure(F_GUARD, first + k, m, t, x, wf, wi)
    for k in range(n_inv):
        w = -wf[terms + n_tr + k] if wi[inv_armed + k] != 0 else b0 - wf[terms + n_tr + k]
        if w < v:
            v = w
        elif w != w:
            note_failure(F_INVARIANT, inv0 + k, m, t, x, wf, wi)
    return v


def watch_min(wf: Array, wi: Ints, terms: int, tr_armed: int, n_tr: int, inv_armed: int,
              n_inv: int, b0: float) -> float:  # fmt: skip
    """:func:`watch_value`'s minimum from offsets found once per stay; NaN if a term is NaN.

    The hot path of the search (every sample, every root-finding step): small
    enough to be inlined. On NaN the caller asks :func:`watch_value`, which
    records the failure and returns the minimum of the other terms.
    """
    v = math.inf
    for k in range(n_tr):
        w = wf[terms + k] if wi[tr_armed + k] != 0 else wf[terms + k] + b0
        if w < v:
            v = w
        elif w != w:
            return math.nan
    for k in range(n_inv):
        w = -wf[terms + n_tr + k] if wi[inv_armed + k] != 0 else b0 - wf[terms + n_tr + k]
        if w < v:
            v = w
        elif w != w:
            return math.nan
    return v


def watch_at(fns: Fns, tab: Ints, m: int, t: float, x: Array, wf: Array, wi: Ints) -> float:
    """The watch at ``(t, x)``: :func:`watch_terms` then :func:`watch_value` (its fast path first)."""
    fns(OP_WATCH, m, t, at(x, 0), at(wf, wi[W_PE]), at(wf, wi[W_TERMS]))
    first = tab[tab[T_MODE_TR] + m]
    inv0 = tab[tab[T_MODE_INV] + m]
    v = watch_min(wf, wi, wi[W_TERMS], wi[W_TRARMED], tab[tab[T_MODE_TR] + m + 1] - first,
                  wi[W_INVARMED], tab[tab[T_MODE_INV] + m + 1] - inv0,
                  wf[wi[W_SCAL] + S_B0])  # fmt: skip
    if v != v:
        return watch_value(tab, m, t, x, wf, wi)
    return v


def _least(fns: Fns, tab: Ints, m: int, t: float, x: Array, wf: Array, wi: Ints) -> float:
    """The watch at ``(t, x)``, at least 0 (the root finder may land on either side of 0)."""
    watch_terms(fns, m, t, x, wf, wi)
    least = watch_value(tab, m, t, x, wf, wi)
    return least if least > 0.0 else 0.0


def far_edge_guards(fns: Fns, tab: Ints, m: int, t: float, x: Array, wf: Array, wi: Ints) -> bool:
    """``Watch.far_edge_guards``: flag (``W_ENABLED``) each disarmed guard whose far-edge term
    ``rho + b0`` is the watch's least at ``(t, x)`` (a crossing stopped the stay there, nothing
    else enabled); True if one was. The terms are left in ``W_TERMS``."""
    least = _least(fns, tab, m, t, x, wf, wi)
    n_tr = tab[tab[T_MODE_TR] + m + 1] - tab[tab[T_MODE_TR] + m]
    b0 = wf[wi[W_SCAL] + S_B0]
    found = False
    for k in range(n_tr):
        if wi[wi[W_TRARMED] + k] == 0 and wf[wi[W_TERMS] + k] + b0 <= least:
            wi[wi[W_ENABLED] + k] = 1
            found = True
    return found


def far_edge_left(fns: Fns, tab: Ints, m: int, t: float, x: Array, wf: Array, wi: Ints) -> int:
    """``Watch.far_edge_left``: the place in its mode of a disarmed invariant whose far-edge term
    ``b0 - rho`` is the watch's least at ``(t, x)`` (a crossing stopped the stay there); -1: none."""
    least = _least(fns, tab, m, t, x, wf, wi)
    n_tr = tab[tab[T_MODE_TR] + m + 1] - tab[tab[T_MODE_TR] + m]
    inv0 = tab[tab[T_MODE_INV] + m]
    b0 = wf[wi[W_SCAL] + S_B0]
    for k in range(tab[tab[T_MODE_INV] + m + 1] - inv0):
        if wi[wi[W_INVARMED] + k] == 0 and b0 - wf[wi[W_TERMS] + n_tr + k] <= least:
            return k
    return -1


def arm_at(fns: Fns, tab: Ints, m: int, t: float, x: Array, wf: Array, wi: Ints) -> bool:
    """Arm the disarmed terms beyond the band on their safe side at ``(t, x)``, and orient the
    levels read on them (0) that the state is beyond the band of; True if one was.

    ``terms`` must hold the watch's terms at ``(t, x)`` (the invariants' rho are read there).
    """
    width = band(x)
    first = tab[tab[T_MODE_TR] + m]
    n_tr = tab[tab[T_MODE_TR] + m + 1] - first
    lv0 = tab[tab[T_TR_LV] + first]
    signs = wi[W_PE] + tab[T_N_PARAMS]
    tr_armed = wi[W_TRARMED]
    changed = False
    evaluated = False
    armv = wf[wi[W_ARMV] :]
    for k in range(n_tr):
        tr = first + k
        lo, hi = tab[tab[T_TR_LV] + tr] - lv0, tab[tab[T_TR_LV] + tr + 1] - lv0
        if wi[tr_armed + k] != 0:  # armed: orient a level read on it (0) once beyond the band
            for a in range(lo, hi):
                if wf[signs + a] == 0.0:
                    if not evaluated:
                        fns(OP_ARM, m, t, at(x, 0), at(wf, wi[W_PE]), at(wf, wi[W_ARMV]))
                        evaluated = True
                    value = armv[n_tr + a]
                    if abs(value) > width:
                        wf[signs + a] = 1.0 if value > 0.0 else -1.0
                        changed = True
            continue
        if not evaluated:
            fns(OP_ARM, m, t, at(x, 0), at(wf, wi[W_PE]), at(wf, wi[W_ARMV]))
            evaluated = True
        rho = armv[k]
        if rho != rho:
            note_failure(F_GUARD, tr, m, t, x, wf, wi)
        if not rho > width:
            continue
        for a in range(lo, hi):
            wf[signs + a] = orientation(armv[n_tr + a], tr, m, t, x, wf, wi)
        orient_by_slope(fns, tab, m, k, t, x, width, wf, wi)
        wi[tr_armed + k] = 1
        changed = True
    inv0 = tab[tab[T_MODE_INV] + m]
    terms = wi[W_TERMS]
    for k in range(tab[tab[T_MODE_INV] + m + 1] - inv0):
        if wi[wi[W_INVARMED] + k] == 0:
            rho = wf[terms + n_tr + k]
            if rho != rho:
                note_failure(F_INVARIANT, inv0 + k, m, t, x, wf, wi)
            if -rho > width:
                wi[wi[W_INVARMED] + k] = 1
                changed = True
    if changed:
        wf[wi[W_SCAL] + S_GEN] += 1.0
    return changed
