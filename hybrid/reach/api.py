"""``hybrid.reach``: flowpipes of an affine model and a verdict on each forbidden entry.

Examples
--------
>>> import hybrid
>>> heater = hybrid.load_text('''
... automaton: heater
... state: {x: {initial: [18, 19]}}
... inputs: {u: {range: [0, 1]}}
... locations: {on: {flow: {x: -0.1 * x + 2 + u}}}
... properties:
...   forbidden:
...     - {when: x > 40}
...     - {when: x > 25}
... ''')
>>> r = hybrid.reach(heater, t_end=10.0, step=0.05)
>>> [(p.verdict, p.witness is not None) for p in r.properties]
[('proved', False), ('refuted', True)]
>>> r.verdict
'refuted'
"""

from __future__ import annotations

import math
import time
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hybrid.compose import System, as_system, expect_model
from hybrid.errors import UsageError
from hybrid.expr import ir
from hybrid.frames import in_frame_room
from hybrid.keywords import named_keywords
from hybrid.model import Automaton, Forbidden
from hybrid.progress import Reporter, Tracker
from hybrid.reach.affine import TIME, Condition, Forms, Rows
from hybrid.reach.boxes import meets_many
from hybrid.reach.engine import ReachSet, explore, forms_of, initial_boxes, mode_of
from hybrid.reach.falsify import entry_time, refute
from hybrid.reach.result import PropertyResult, ReachResult
from hybrid.reach.witness import (
    Candidate,
    corner_candidates,
    random_candidates,
    reaches,
    simulate_candidate,
    support_candidate,
)
from hybrid.simulation.result import Run
from hybrid.simulation.settings import Settings

__all__ = ["DEFAULT_STEPS", "reach"]

Array = NDArray[np.float64]
DEFAULT_STEPS = 4000
"""Steps over the horizon when no step is given (``step = t_end / DEFAULT_STEPS``)."""
RANDOM_RUNS = 4
"""Seeded random runs tried for a witness after the support and corner candidates."""
INITIAL_MODES = 16
"""Initial modes a witness is searched from (in ``initial_boxes`` order): the support and
corner candidates of each, the random runs from the first."""


@in_frame_room
@named_keywords
def reach(
    model: Automaton | System,
    t_end: float | None = None,
    *,
    settings: Settings | None = None,
    max_jumps: int = 10,
    step: float | None = None,
    witness: bool = True,
    refute_first: bool = False,
    progress: Reporter | None = None,
) -> ReachResult:
    """Over-approximate every state ``model`` reaches within ``t_end`` and ``max_jumps`` jumps.

    Parameters
    ----------
    model : Automaton or System
        Flows affine in the state and inputs (``x' = A x + B u + c``), resets
        affine, guards and invariants linear (conjunctions and disjunctions of
        comparisons). Every input a flow or reset reads needs a range; it may
        take any value in it at any time.
    t_end : float, optional
        Horizon; needed unless ``settings`` gives it.
    settings : Settings, optional
        A :class:`hybrid.Settings`, of which reach reads ``t_end`` only (when
        ``t_end`` is not given): its flowpipes have their own ``step`` and jump
        bound, and its witnesses are simulated at their own tolerances.
    max_jumps : int
        Jump bound.
    step : float, optional
        Time step of the flowpipes (default ``t_end / 4000``): smaller is tighter and slower.
    witness : bool
        Search a simulated run into each forbidden entry the sets meet.
    refute_first : bool
        Look for a run into each forbidden entry before computing any set
        (:mod:`hybrid.reach.falsify`: the support's maximisers along the
        entry's direction, step by step, stopping at the first that enters
        it). When every entry is refuted so, no flowpipe is computed:
        ``.sets`` is empty, ``.complete`` false and ``first_contact`` ``None``
        (a gate's answer, as a falsifier stops at the first concrete error).
        A proof still needs the whole flowpipe.
    progress : callable, optional
        Called with a :class:`hybrid.progress.Status` (``flowpipes`` begun, with
        the ``sets`` computed and the entry boxes ``waiting``) at most five times
        a second while the flowpipes are computed, and once when they are done.

    Returns
    -------
    ReachResult
        ``.verdict``, ``.properties`` (per forbidden entry), ``.sets``, ``.hull()``, ``.plot()``.

    Raises
    ------
    SpecError
        Dynamics reach cannot handle, at ``file:line:column`` naming the expression.
    UsageError
        A horizon, step or jump bound that is not valid.

    Examples
    --------
    >>> import hybrid
    >>> ball = hybrid.load("specs/bouncing_ball.yaml")
    >>> r = hybrid.reach(ball, t_end=2.0, max_jumps=3, step=0.001)
    >>> lo, hi = r.hull()
    >>> bool(hi[0] >= 10.0 and lo[0] <= 0.0)
    True
    >>> hybrid.reach(ball, settings=hybrid.Settings(t_end=2.0), max_jumps=3, step=0.001).t_end
    2.0
    """
    expect_model(model, "reach")
    if settings is not None and not isinstance(settings, Settings):
        raise UsageError(f"settings must be a hybrid.Settings, got {settings!r}")
    if t_end is None and settings is not None:
        t_end = settings.t_end
    if (isinstance(t_end, bool) or not isinstance(t_end, int | float) or not math.isfinite(t_end)
            or not t_end > 0):  # fmt: skip
        raise UsageError(f"t_end must be a finite number > 0, got {t_end!r}")
    if step is None:
        step = t_end / DEFAULT_STEPS if t_end > 0 else 1.0
    if isinstance(step, bool) or not isinstance(step, int | float):
        raise UsageError(f"step must be a finite number > 0, got {step!r}")
    if isinstance(max_jumps, bool) or not isinstance(max_jumps, int):
        raise UsageError(f"max_jumps must be an integer >= 0, got {max_jumps!r}")
    if progress is not None and not callable(progress):
        raise UsageError(f"progress must be a function of a status, got {progress!r}")
    started = time.process_time()
    system = as_system(model)  # the flowpipes' model; the witnesses run the user's
    forms = forms_of(system)
    entries = [
        (e, _condition(forms, e, forms.system.initial_mode)) for e in model.properties.forbidden
    ]
    early: list[PropertyResult | None] = [None] * len(entries)
    if refute_first and witness:
        early = [_quick(model, forms, entry, t_end, max_jumps, step, None) for entry, _ in entries]
    sets: list[ReachSet] = []
    complete, cut = False, None
    if not (early and all(e is not None for e in early)):
        pipes = None if progress is None else _Flowpipes(progress)
        sets, complete, cut = explore(system, t_end=t_end, max_jumps=max_jumps, step=step,
                                      forms=forms, progress=pipes)  # fmt: skip
        if pipes is not None:
            pipes.finish(len(sets), complete)
    grouped: dict[tuple[str, ...], list[ReachSet]] = {}
    for s in sets:  # once: each entry then looks at the modes, not at every set
        grouped.setdefault(s.mode, []).append(s)
    results = [
        found
        or _decide(
            model, forms, entry, cond, sets, grouped, complete, t_end, max_jumps, step, witness,
            cut,
        )
        for found, (entry, cond) in zip(early, entries, strict=True)
    ]
    return ReachResult(
        model=model.name,
        variables=tuple(model.state_names),
        sets=tuple(sets),
        properties=tuple(results),
        t_end=float(t_end),
        max_jumps=max_jumps,
        step=float(step),
        complete=complete,
        jump_bound_from=cut,
        seconds=time.process_time() - started,
        file=model.file,
        source=model,
    )


class _Flowpipes:
    """The flowpipes' progress: :func:`explore`'s callback, feeding a :class:`Tracker`."""

    def __init__(self, report: Reporter) -> None:
        self.tracker = Tracker("reach", unit="flowpipes", report=report)
        self.counts = (0, 0, 0)

    def __call__(self, pipes: int, sets: int, waiting: int) -> None:
        self.counts = (pipes, sets, waiting)
        self.tracker.update(pipes, sets=sets, waiting=waiting)

    def finish(self, sets: int, complete: bool) -> None:
        pipes, _, waiting = self.counts
        self.tracker.finish(pipes, sets=sets, waiting=0 if complete else waiting)


def _condition(
    forms: Forms, entry: Forbidden, mode: tuple[str, ...], for_all: bool = False
) -> Condition:
    """The entry's condition in ``mode`` over the reach vector (``true`` without ``when``).

    Signals are read as ``mode``'s locations define them (a location may override one);
    inputs projected out as ``exists u`` (``for_all``: for every value).
    """
    n = len(forms.variables)
    if entry.when is None:
        return (Rows(np.zeros((0, n)), np.zeros(0)),)
    comp = 0
    names = forms.component_names
    for name in entry.locations:
        if name in names:
            comp = names.index(name)
            break
    what = f"the forbidden set '{entry.text()}'"
    return forms.condition(entry.when, comp, mode, entry.position, what, for_all=for_all)


def _matches(forms: Forms, entry: Forbidden, mode: tuple[str, ...]) -> bool:
    names = forms.component_names
    for comp, loc in entry.locations.items():
        index = 0 if comp == "" else names.index(comp) if comp in names else -1
        if index < 0 or mode[index] != loc:
            return False
    return True


def _within(cond: Condition, forms: Forms, t_end: float) -> Condition:
    """The condition cut to ``t <= t_end`` (contact beyond the horizon does not count)."""
    row = np.zeros(len(forms.variables))
    row[forms.index[TIME]] = 1.0
    cut = Rows(row[None, :], np.array([t_end]))
    return tuple(c.conjoin(cut) for c in cond)


def bound_note(cut: float | None, max_jumps: int) -> str:
    """What a bounded proof leaves out: runs past the jump bound, from when they may be.

    >>> bound_note(33.57, 10)
    ' (a run may take jump 11 from t = 33.57 on; what it does then is not covered: raise max_jumps)'
    >>> bound_note(None, 10)
    ''
    """
    if cut is None:
        return ""
    return (f" (a run may take jump {max_jumps + 1} from t = {cut:.4g} on; what it does then is "
            "not covered: raise max_jumps)")  # fmt: skip


def _decide(
    model: Automaton | System,
    forms: Forms,
    entry: Forbidden,
    cond: Condition,
    sets: list[ReachSet],
    grouped: dict[tuple[str, ...], list[ReachSet]],
    complete: bool,
    t_end: float,
    max_jumps: int,
    step: float,
    witness: bool,
    bound_from: float | None = None,
) -> PropertyResult:
    by_mode = {mode: chosen for mode, chosen in grouped.items() if _matches(forms, entry, mode)}
    hits: set[int] = set()
    for mode, chosen in by_mode.items():
        cut = _within(_condition(forms, entry, mode), forms, t_end)
        times = np.array([s.t for s in chosen])
        lo = np.column_stack([np.array([s.lo for s in chosen]), times[:, 0]])
        hi = np.column_stack([np.array([s.hi for s in chosen]), times[:, 1]])
        ok = meets_many(lo, hi, cut)[2]
        hits.update(id(s) for s, hit in zip(chosen, ok.tolist(), strict=True) if hit)
    contacts = [s for s in sets if id(s) in hits]
    name = entry.text()
    horizon = f"within t <= {t_end:g} and {max_jumps} jumps"
    if not contacts and complete:
        message = f"forbidden state '{name}' is never reached {horizon}{bound_note(bound_from, max_jumps)}"
        return PropertyResult(entry, "proved", message, condition=cond)
    # a set's time span is widened by rounding below 0, where no run is
    first = max(0.0, min(s.t[0] for s in contacts)) if contacts else None
    reads_inputs = entry.when is not None and bool(ir.names_in(entry.when, ir.INPUT))
    if witness and contacts and not reads_inputs:
        quick = _quick(model, forms, entry, t_end, max_jumps, step, first)
        if quick is not None:
            return quick
        conditions = {
            chosen[0].location: _condition(forms, entry, mode) for mode, chosen in by_mode.items()
        }
        found = _witness(model, forms, conditions, cond, contacts, t_end, max_jumps, step)
        if found is not None:
            run, at, candidate = found
            return PropertyResult(
                entry,
                "refuted",
                f"forbidden state '{name}' is reached at t = {at:.9g} "
                f"by a simulated run ({candidate.how})",
                first_contact=first,
                simulated=run,
                witness_time=at,
                witness_initial=candidate.initial,
                witness_inputs=dict(candidate.inputs),
                witness_location=_location_of(model, candidate.location),
                condition=cond,
            )
    if first is None:
        message = f"forbidden state '{name}' was not proved unreachable: the search stopped early"
    else:
        message = (
            f"forbidden state '{name}' may be reached {horizon}: the over-approximation "
            f"meets it from t = {first:.9g}, and no simulated run was found that reaches it"
            + step_hint([mode_of(forms, key) for key in {s.mode: None for s in contacts}], step)
        )
    return PropertyResult(entry, "unknown", message, first_contact=first, condition=cond)


LONG_STEP = 0.2
"""``|A| h`` above which an unknown verdict suggests a smaller step (the sets of a step
grow by about that factor of the state's size)."""


def step_hint(modes: list[Any], step: float) -> str:
    """A hint to shorten the step when it is long against the dynamics of ``modes``.

    ``|A|`` is the largest row sum of the flow matrix: a step of ``h`` lets a box
    grow by about ``|A| h`` of itself (a stiff mode's ``x' = -1000 x`` at
    ``h = 0.0025`` by 2.5, where the flow itself shrinks it).

    >>> class M:  # a mode's flow matrix and name
    ...     a, name = np.array([[-1000.0, 1.0], [0.0, -0.1]]), "l"
    >>> step_hint([M()], 0.0025)
    '; the step is long against the dynamics (|A| h = 2.5 in l): a smaller step (--step, step=) tightens the sets'
    >>> step_hint([M()], 1e-5)
    ''
    """
    worst, where = 0.0, ""
    for mode in modes:
        size = float(np.abs(mode.a).sum(axis=1).max()) if mode.a.size else 0.0
        if size * step > worst:
            worst, where = size * step, mode.name
    if worst <= LONG_STEP:
        return ""
    return (f"; the step is long against the dynamics (|A| h = {worst:.2g} in {where}): a "
            "smaller step (--step, step=) tightens the sets")  # fmt: skip


def _quick(
    model: Automaton | System,
    forms: Forms,
    entry: Forbidden,
    t_end: float,
    max_jumps: int,
    step: float,
    first: float | None,
) -> PropertyResult | None:
    """The entry refuted from an initial mode by :func:`hybrid.reach.falsify.refute`, or ``None``."""
    if entry.when is not None and ir.names_in(entry.when, ir.INPUT):
        return None
    for key, lo, hi in initial_boxes(forms):
        if not _matches(forms, entry, key):
            continue
        every = _within(_condition(forms, entry, key, for_all=True), forms, t_end)
        mode = mode_of(forms, key)
        found = refute(forms, mode, lo, hi, every, t_end=t_end, step=step)
        if found is None:
            continue
        candidate = replace(found.candidate, location=key)
        condition = _condition(forms, entry, key)
        at = entry_time(found, mode, condition, forms.index[TIME])  # exactly: no simulation

        def replay(candidate: Candidate = candidate) -> Run | None:
            return simulate_candidate(model, forms, candidate, max_jumps)

        return PropertyResult(
            entry,
            "refuted",
            f"forbidden state '{entry.text()}' is reached at t = {at:.9g} "
            f"by a run of the model ({candidate.how})",
            first_contact=first,
            witness_time=at,
            witness_initial=candidate.initial,
            witness_inputs=dict(candidate.inputs),
            witness_location=_location_of(model, candidate.location),
            condition=condition,
            replay=replay,
        )
    return None


def _location_of(
    model: Automaton | System, key: tuple[str, ...] | None
) -> str | dict[str, str] | None:
    """A witness's initial location as a spec gives it: a name (an automaton), or a name per
    component (a system)."""
    if key is None:
        return None
    if isinstance(model, Automaton):
        return key[0]
    return {c.name: name for c, name in zip(model.components, key, strict=True)}


def _witness(
    model: Automaton | System,
    forms: Forms,
    conditions: dict[str, Condition],
    cond: Condition,
    contacts: list[ReachSet],
    t_end: float,
    max_jumps: int,
    step: float,
) -> tuple[Run, float, Candidate] | None:
    candidates: list[Candidate] = []
    for k, (mode, x_lo, x_hi) in enumerate(initial_boxes(forms)[:INITIAL_MODES]):
        # from each initial mode (the first one's candidates first, as many random runs
        # from it only): a set may be reached from one initial mode and not another
        direct = [s for s in contacts if s.jumps == 0 and s.mode == mode]
        here: list[Candidate] = []
        if direct:
            a, b, _ = forms.flow(mode)
            for direction in _directions(cond, forms):
                for target in _target_steps(direct, direction, step, t_end):
                    here.append(support_candidate(forms, a, b, x_lo, x_hi, direction, step, target))
        here = here[:6]
        here.extend(corner_candidates(forms, x_lo[:-1], x_hi[:-1], t_end))
        if k == 0:
            here.extend(random_candidates(forms, x_lo[:-1], x_hi[:-1], t_end, RANDOM_RUNS))
        candidates.extend(replace(c, location=mode) for c in here)
    for candidate in candidates:
        run = simulate_candidate(model, forms, candidate, max_jumps)
        if run is None:
            continue
        at = reaches(run, forms, conditions)
        if at is not None:
            return run, at, candidate
    return None


def _directions(cond: Condition, forms: Forms) -> list[Array]:
    """Per case, the direction that lowers its rows' left-hand sides (time left out)."""
    t = forms.index[TIME]
    found = []
    for case in cond:
        mat = case.mat.copy()
        mat[:, t] = 0.0
        norms = np.linalg.norm(mat, axis=1)
        keep = norms > 0.0
        if not keep.any():
            continue
        d = -(mat[keep] / norms[keep, None]).sum(axis=0)
        if np.linalg.norm(d) > 0.0:
            found.append(d)
    return found


def _target_steps(direct: list[ReachSet], direction: Array, step: float, t_end: float) -> list[int]:
    """Step counts to aim at: the ends of the set where the contact goes furthest, then of the first."""
    d = direction[:-1]
    first = min(direct, key=lambda s: s.t[0])
    best = max(direct, key=lambda s: float(np.where(d > 0, s.hi, s.lo) @ d))
    targets = []
    for s in (best, first):
        for t in reversed(s.t):
            k = round(min(t, t_end) / step)
            if k >= 1 and k not in targets:
                targets.append(k)
    return targets
