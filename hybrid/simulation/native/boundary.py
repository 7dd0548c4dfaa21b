"""Kernel source: the decisions at a point, as :mod:`hybrid.simulation.boundary` makes them.

Function by function (docs/semantics.md, "Deciding a guard at a point"):

- :func:`band` is ``boundary.band``; :func:`step_ahead` is ``boundary.ahead``
  (the point the slope test looks at); :func:`slope` is ``boundary.slope``;
- :func:`holds_now` is ``boundary.holds_now`` (band, slope test, boolean form;
  a rho that is not 0 but is exactly 0 at the point ahead, a flat zero, is
  decided by the boolean form there; a guard that sits on its boundary, by its
  form within the band). The boolean forms are generated within the band
  (:func:`hybrid.expr.rho.within_band`), its width read from the band slot of
  the parameter vector (:func:`truth_within`): the band where a guard sits,
  0 for the exact form;
- :func:`enabled_at_entry` is ``boundary.enabled_at_entry``: at the instant the
  last stay stopped (its state kept in ``W_REACHED``), a guard that does not
  hold is decided again with its equality atoms snapped (at their level both
  here and there, and the level not used: :func:`is_used`);
- :func:`enabled_at_event` is ``boundary.enabled_at_event``: an armed guard is
  decided *snapped* (each equality atom true where its two sides differ by at
  most the band: the snap slots of the model's parameter vector are set, then
  the snapped form is decided), a disarmed one counts only at or below its
  boundary;
- :func:`invariant_left_at` is ``boundary.invariant_left_at``;
- :func:`choose` is ``boundary.choose`` (highest priority, then file order;
  ``boundary.chosen_by`` is computed in Python from the recorded flags).

A change of these rules in ``boundary.py`` is made here the same way, function
for function; the forms they read (raw, snapped) come from the generator
(:mod:`~hybrid.simulation.native.source`), which uses the reference's own
rewrites of guards.

Indices: ``m`` a mode; ``k`` a transition's place in its mode (the
``enabled`` and ``tr_armed`` flags in ``wi``); ``tr = MODE_TR[m] + k`` its
global index. ``pe`` is the run's parameter vector with the level slots after
the parameters. An evaluation failure (NaN) is recorded once, the first, like
:class:`hybrid.expr.codegen.EvalFailure`: what failed in ``wi``, where in
``wf``.

Copied into the kernel module (below the ``kernel`` marker).
"""

from __future__ import annotations

from hybrid.simulation.native.buffers import (
    F_FLOW,
    F_GUARD,
    F_INVARIANT,
    OP_ARM,
    OP_RHS,
    OP_TRUTH,
    OP_VALUE,
    S_FAIL_T,
    S_REACHED_T,
    T_INV_BOOL,
    T_INV_RHO,
    T_LV_KEY,
    T_MAX_LV,
    T_MODE_INV,
    T_MODE_TR,
    T_N_PARAMS,
    T_TR_BOOL,
    T_TR_LV,
    T_TR_PRIORITY,
    T_TR_RHO,
    T_TR_SBOOL,
    T_TR_SRHO,
    W_AHEAD,
    W_ARMV,
    W_D,
    W_ENABLED,
    W_FAILI,
    W_FAILX,
    W_PE,
    W_RATE,
    W_REACHED,
    W_SCAL,
    W_TRARMED,
    W_USED,
)
from hybrid.simulation.native.kernel_types import Array, Fns, Ints, at

__all__ = [
    "band",
    "choose",
    "enabled_at_entry",
    "enabled_at_event",
    "holds_now",
    "invariant_left_at",
    "is_used",
    "note_failure",
    "slope",
    "step_ahead",
    "truth_within",
    "value_checked",
]

# --- kernel ---


def band(x: Array) -> float:
    """Values of rho within this of 0 count as on the boundary."""
    big = 0.0
    for i in range(x.shape[0]):
        a = abs(x[i])
        if a > big:
            big = a
    return 1e-10 * (1.0 + big)


def note_failure(kind: int, index: int, m: int, t: float, x: Array, wf: Array, wi: Ints) -> None:
    """Record an evaluation failure at ``(t, x)`` unless one is recorded already."""
    fi = wi[W_FAILI]
    if wi[fi] != 0:
        return
    wi[fi] = kind
    wi[fi + 1] = index
    wi[fi + 2] = m
    wf[wi[W_SCAL] + S_FAIL_T] = t
    fx = wi[W_FAILX]
    for i in range(x.shape[0]):
        wf[fx + i] = x[i]


def value_checked(
    fns: Fns, f: int, kind: int, index: int, m: int, t: float, x: Array, wf: Array, wi: Ints,
) -> float:  # fmt: skip
    """Form ``f`` at ``(t, x)``, a NaN recorded as a failure of ``kind``/``index``."""
    x_c = at(x, 0)
    v: float = fns(OP_VALUE, f, t, x_c, at(wf, wi[W_PE]), x_c)
    if v != v:
        note_failure(kind, index, m, t, x, wf, wi)
    return v


def step_ahead(fns: Fns, m: int, t: float, x: Array, wf: Array, wi: Ints) -> float:
    """The step ``h`` of the slope test; the point ``x + h x'`` it looks at into ``ahead``."""
    d = wi[W_D]
    rate = wf[wi[W_RATE] : wi[W_RATE] + d]
    ahead = wf[wi[W_AHEAD] : wi[W_AHEAD] + d]
    h = 1e-7 * max(1.0, abs(t))
    fns(OP_RHS, m, t, at(x, 0), at(wf, wi[W_PE]), at(rate, 0))
    for i in range(d):
        if rate[i] != rate[i]:
            note_failure(F_FLOW, m, m, t, x, wf, wi)
        ahead[i] = x[i] + h * rate[i]
    return h


def slope(
    fns: Fns, f: int, kind: int, index: int, m: int, t: float, x: Array, wf: Array, wi: Ints,
) -> float:  # fmt: skip
    """d/dt of form ``f`` along the flow of mode ``m``, by a small forward difference."""
    h = step_ahead(fns, m, t, x, wf, wi)
    ahead = wf[wi[W_AHEAD] : wi[W_AHEAD] + wi[W_D]]
    later = value_checked(fns, f, kind, index, m, t + h, ahead, wf, wi)
    return (later - value_checked(fns, f, kind, index, m, t, x, wf, wi)) / h


def truth_within(
    fns: Fns, f: int, t: float, x: Array, width: float, tab: Ints, wf: Array, wi: Ints,
) -> bool:  # fmt: skip
    """Boolean form ``f`` at ``(t, x)``, each comparison within ``width`` of its boundary
    decided as on it (``width`` 0: the form itself)."""
    wf[wi[W_PE] + tab[T_N_PARAMS] + 2 * tab[T_MAX_LV]] = width
    x_c = at(x, 0)
    return fns(OP_TRUTH, f, t, x_c, at(wf, wi[W_PE]), x_c) != 0.0


def holds_now(
    fns: Fns, tab: Ints, rho_f: int, bool_f: int, kind: int, index: int, m: int, t: float,
    x: Array, armed: bool, width: float, wf: Array, wi: Ints,
) -> tuple[bool, bool]:  # fmt: skip
    """``(enabled now, armed)`` for a condition given by its rho and boolean forms."""
    value = value_checked(fns, rho_f, kind, index, m, t, x, wf, wi)
    if value < -width:
        return True, True
    if value > width:
        return False, True
    if not armed:
        return False, False
    h = step_ahead(fns, m, t, x, wf, wi)
    ahead = wf[wi[W_AHEAD] : wi[W_AHEAD] + wi[W_D]]
    further = value_checked(fns, rho_f, kind, index, m, t + h, ahead, wf, wi)
    if further == 0.0 and value != 0.0:
        # rho comes down to exactly 0 (a flat zero: `max(h, v, 0)`, `x - x > 0 and ...`):
        # its slope says nothing about the guard; the boolean form where the flow goes does
        now = truth_within(fns, bool_f, t + h, ahead, 0.0, tab, wf, wi)
        return now, now
    rate = (further - value) / h
    if rate < -width:
        return True, True
    if rate > width:
        return False, False  # on the boundary, moving away: disarm until strictly false
    return truth_within(fns, bool_f, t, x, width, tab, wf, wi), False


def choose(tab: Ints, m: int, wi: Ints) -> int:
    """The global index of the transition that fires among the enabled ones (-1: none)."""
    first = tab[tab[T_MODE_TR] + m]
    count = tab[tab[T_MODE_TR] + m + 1] - first
    priority = tab[T_TR_PRIORITY]
    enabled = wi[W_ENABLED]
    best = -1
    for k in range(count):
        if wi[enabled + k] != 0:
            tr = first + k
            if best < 0 or tab[priority + tr] > tab[priority + best]:
                best = tr
    return best


def is_used(tab: Ints, lv: int, wi: Ints) -> bool:
    """Whether level ``lv`` (global) is used at this instant (its key is among ``W_USED``)."""
    used = wi[W_USED]
    key = tab[tab[T_LV_KEY] + lv]
    for i in range(wi[used]):  # noqa: SIM110 (compiled: a plain loop)
        if wi[used + 1 + i] == key:
            return True
    return False


def enabled_at_entry(fns: Fns, tab: Ints, m: int, t: float, x: Array, wf: Array,
                     wi: Ints) -> int:  # fmt: skip
    """At a point where a stay starts: the transition that fires (-1: none); flags in ``wi``.

    At the instant the last stay stopped (``S_REACHED_T``), a guard that does
    not hold here is decided again with its equality atoms snapped: each true
    where its two sides are within the band both here and where the stay
    stopped (``W_REACHED``), and its level not used (:func:`is_used`).
    """
    width = band(x)
    first = tab[tab[T_MODE_TR] + m]
    n_tr = tab[tab[T_MODE_TR] + m + 1] - first
    lv0 = tab[tab[T_TR_LV] + first]
    snaps = wi[W_PE] + tab[T_N_PARAMS] + tab[T_MAX_LV]
    armv = wf[wi[W_ARMV] :]
    reached = wf[wi[W_REACHED] : wi[W_REACHED] + x.shape[0]]
    same_instant = wf[wi[W_SCAL] + S_REACHED_T] == t
    width_then = band(reached)
    for k in range(n_tr):
        tr = first + k
        rho_f, bool_f = tab[tab[T_TR_RHO] + tr], tab[tab[T_TR_BOOL] + tr]
        now, armed = holds_now(fns, tab, rho_f, bool_f, F_GUARD, tr, m, t, x, True, width, wf, wi)
        lv_from, lv_to = tab[tab[T_TR_LV] + tr] - lv0, tab[tab[T_TR_LV] + tr + 1] - lv0
        if not now and same_instant and lv_to > lv_from:
            # the levels of the mode's guards where the stay stopped, then here
            fns(OP_ARM, m, t, at(reached, 0), at(wf, wi[W_PE]), at(wf, wi[W_ARMV]))
            for a in range(lv_from, lv_to):
                level = armv[n_tr + a]
                if level != level:
                    note_failure(F_GUARD, tr, m, t, reached, wf, wi)
                wf[snaps + a] = -1.0 if abs(level) <= width_then else 1.0
            fns(OP_ARM, m, t, at(x, 0), at(wf, wi[W_PE]), at(wf, wi[W_ARMV]))
            any_level = False
            for a in range(lv_from, lv_to):
                level = armv[n_tr + a]
                if level != level:
                    note_failure(F_GUARD, tr, m, t, x, wf, wi)
                if wf[snaps + a] < 0.0 and abs(level) <= width and not is_used(tab, lv0 + a, wi):
                    any_level = True
                else:
                    wf[snaps + a] = 1.0
            if any_level:
                rho_f, bool_f = tab[tab[T_TR_SRHO] + tr], tab[tab[T_TR_SBOOL] + tr]
                now = holds_now(fns, tab, rho_f, bool_f, F_GUARD, tr, m, t, x, True, width, wf, wi)[0]
        wi[wi[W_TRARMED] + k] = 1 if armed else 0
        wi[wi[W_ENABLED] + k] = 1 if now else 0
    return choose(tab, m, wi)


def enabled_at_event(fns: Fns, tab: Ints, m: int, t: float, x: Array, wf: Array,
                     wi: Ints) -> int:  # fmt: skip
    """Where the search stopped: every transition decided; the one that fires (-1: none).

    ``tr_armed`` says which guards were in the watch. An armed guard is
    decided with its equality atoms snapped; a disarmed one only if it is at or
    below its boundary here. A crossing the search found still has to pass the
    boundary rule (a strict guard whose rho reaches 0 and stays there never holds).
    """
    width = band(x)
    first = tab[tab[T_MODE_TR] + m]
    n_tr = tab[tab[T_MODE_TR] + m + 1] - first
    lv0 = tab[tab[T_TR_LV] + first]
    snaps = wi[W_PE] + tab[T_N_PARAMS] + tab[T_MAX_LV]
    armv = wf[wi[W_ARMV] :]
    fns(OP_ARM, m, t, at(x, 0), at(wf, wi[W_PE]), at(wf, wi[W_ARMV]))
    for k in range(n_tr):
        tr = first + k
        wi[wi[W_ENABLED] + k] = 0
        if wi[wi[W_TRARMED] + k] != 0:
            for a in range(tab[tab[T_TR_LV] + tr] - lv0, tab[tab[T_TR_LV] + tr + 1] - lv0):
                level = armv[n_tr + a]
                if level != level:
                    note_failure(F_GUARD, tr, m, t, x, wf, wi)
                wf[snaps + a] = -1.0 if abs(level) <= width else 1.0
            rho_f, bool_f = tab[tab[T_TR_SRHO] + tr], tab[tab[T_TR_SBOOL] + tr]
        else:
            rho = armv[k]
            if rho != rho:
                note_failure(F_GUARD, tr, m, t, x, wf, wi)
            if not rho <= width:
                continue
            rho_f, bool_f = tab[tab[T_TR_RHO] + tr], tab[tab[T_TR_BOOL] + tr]
        if holds_now(fns, tab, rho_f, bool_f, F_GUARD, tr, m, t, x, True, width, wf, wi)[0]:
            wi[wi[W_ENABLED] + k] = 1
    return choose(tab, m, wi)


def invariant_left_at(fns: Fns, tab: Ints, m: int, t: float, x: Array, wf: Array,
                      wi: Ints) -> int:  # fmt: skip
    """The place in its mode of an invariant that does not hold or is being left (-1: none)."""
    width = band(x)
    first = tab[tab[T_MODE_INV] + m]
    for k in range(tab[tab[T_MODE_INV] + m + 1] - first):
        inv = first + k
        rho_f = tab[tab[T_INV_RHO] + inv]
        value = value_checked(fns, rho_f, F_INVARIANT, inv, m, t, x, wf, wi)
        if value > width:
            return k
        if value >= -width:
            rate = slope(fns, rho_f, F_INVARIANT, inv, m, t, x, wf, wi)
            if rate > width or (
                abs(rate) <= width
                and not truth_within(fns, tab[tab[T_INV_BOOL] + inv], t, x, width, tab, wf, wi)
            ):
                return k
    return -1
