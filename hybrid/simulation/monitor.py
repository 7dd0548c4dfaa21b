"""The requirements of a run: their margins, the monitor, and components simulated apart.

**Margins.** A requirement's **margin** is the negative of its condition's rho
(:func:`hybrid.expr.rho.guard_to_rho`): ``margin(t, x) >= 0`` where the condition
holds, and its value is the usual robustness of signal temporal logic for an
atomic predicate (``x >= 15`` has margin ``x - 15``; ``and`` is the smaller of two
margins, ``or`` the larger, ``not`` the negation). It is compiled, like a guard,
once per mode in which the requirement is in scope (its ``in:`` location), with
the signal definitions in force there and the owning component's parameters
bound. Evaluation errors are recorded in :attr:`MarginTable.failure`, never in
the compiled model's own records: a requirement never changes the run.

**The monitor**: robustness and the first violation, found inside every step.

The monitor watches a run as the recorder stores it: every point that is not
inside a stay (the initial point, each post-jump point) and every accepted
solver step of each stay, as the solver's interpolant over the part of the
step that belongs to the trajectory. It never changes the run. For each
requirement in scope (its ``in:`` location, cut to its ``within`` window) it
evaluates the requirement's margin (the margins above) the way
the search for events evaluates the watch (:mod:`~hybrid.simulation.crossing`):

1. **Samples.** The part ``[a, b]`` of a step is cut into
   ``m = parts(b - a, spacing)`` equal parts (the same rule and spacing as the
   search for events); the margin is evaluated at every sample, the ends
   included, on the interpolant (the step end on the solver's own state).
2. **Extremes.** A sample that is a local minimum of the sampled values (of the
   margin for ``always``, of its negative for ``eventually``), and the first
   and last samples of a stretch in scope when the values fall towards them,
   are refined by bounded Brent minimisation between their neighbours, unless
   the dip cannot reach below the smallest value seen (its depth is bounded by
   twice the differences to the neighbours). The robustness is the smallest
   value found, so an extreme that falls on a sample, a jump or the end of the
   run is exact.
3. **Violation** (``always``). The first sample, or refined minimum, whose
   margin is below minus the band of :func:`~hybrid.simulation.crossing.band`
   is a violation; its time is the zero of the margin between the sample
   before (where the margin was positive) and it, located by Brent's method to
   about machine precision: the exact crossing, as for a guard.

What it cannot see is what the search for events cannot: a dip that lies
between two samples and leaves no local minimum in the sampled values.
``max_step`` bounds the parts.

**Components simulated apart.** :mod:`~hybrid.simulation.apart` runs each group of components that share no
label and read no signal of each other on its own, and merges the runs. A
requirement is monitored inside the run of the group it belongs to, exactly as
in a run of the whole system:

- a component's requirement, or a system file's requirement that reads (and is
  scoped to) one group only, is monitored in that group's run;
- a system file's requirement that reads state variables or signals of several
  groups (or is scoped to a location of another group) joins those groups:
  they are simulated together (:func:`join_groups`), never approximated.

The merged run can end before a group's own run does (another group ended
early, or the system's ``max_jumps`` was reached): the group's requirements
are then monitored again over its own run cut at the system's end, on the
interpolants the group kept (:func:`cut_results`), with the same samples and
the same rules as while it ran.

Examples
--------
>>> import hybrid, numpy as np
>>> from hybrid.simulation.compiled import CompiledModel
>>> heater = hybrid.load_text('''
... automaton: heater
... state: {x: {initial: 20.0}}
... locations: {cooling: {flow: {x: -0.1*x}}}
... requirements: [{name: warm, always: "x >= 15"}]
... ''')
>>> from hybrid.compose import as_system
>>> compiled = CompiledModel(as_system(heater))
>>> table = MarginTable(compiled, watched_requirements(compiled.system))
>>> [(k, float(fn(0.0, np.array([20.0])))) for k, fn in table.of(compiled.mode(compiled.initial_key))]
[(0, 5.0)]

>>> import hybrid, math
>>> heater = hybrid.load_text('''
... automaton: heater
... state: {x: {initial: 20.0}}
... locations: {cooling: {flow: {x: -0.1*x}}}
... requirements:
...   - {name: warm, always: "x >= 15"}
...   - {name: mild, always: "x >= 12"}
... ''')
>>> run = hybrid.simulate(heater, t_end=5.0, rtol=1e-10, atol=1e-12)
>>> warm, mild = run.requirements["warm"], run.requirements["mild"]
>>> warm.holds, abs(warm.robustness - (20 * math.exp(-0.5) - 15)) < 1e-9
(False, True)
>>> abs(warm.violated_at - 10 * math.log(20 / 15)) < 1e-7   # x = 15 there
True
>>> mild.holds, round(mild.robustness, 6), mild.violated_at
(True, 0.130613, None)

>>> import hybrid
>>> ball = hybrid.load("specs/bouncing_ball.yaml")
>>> heater = hybrid.load_text('''
... automaton: heater
... state: {x: {initial: 20.0}}
... locations: {cooling: {flow: {x: -0.1*x}}}
... requirements: [{name: warm, always: "x >= 15"}]
... ''')
>>> run = hybrid.simulate(hybrid.compose(ball, heater), t_end=2.0)
>>> sorted(run.requirements), run.requirements["heater.warm"].holds
(['heater.warm'], True)
"""

from __future__ import annotations

import math
import threading
import weakref
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any, Protocol

import numpy as np

from hybrid.compose import System
from hybrid.expr import ir
from hybrid.expr.codegen import CodeContext, EvalFailure, compile_function
from hybrid.expr.dependencies import signals_read
from hybrid.expr.rho import guard_to_rho
from hybrid.modes import Binder, Mode, mode_of
from hybrid.simulation.compiled import CompiledModel, Source
from hybrid.simulation.crossing import HORIZON_SAMPLES, band, parts
from hybrid.simulation.dense import StepCurve
from hybrid.simulation.failures import describe_failure
from hybrid.simulation.result import RequirementResult, Run
from hybrid.simulation.settings import Settings
from hybrid.simulation.watched import Watched, watched_requirements

__all__ = [
    "DIP_REACH",
    "Keyed",
    "MarginTable",
    "Monitor",
    "Watched",
    "cut_results",
    "join_groups",
    "margin_table",
    "monitor_for",
    "owners",
    "watched_requirements",
    "with_group_requirements",
]


Fn = Callable[[float, Any], Any]


def owners(system: System, watched: Watched) -> set[int]:
    """The components a requirement depends on: its own, or those owning what it reads."""
    if watched.component is not None:
        return {watched.component}
    read = ir.names_in(watched.requirement.predicate)
    found = {
        i
        for i, c in enumerate(system.components)
        if read & {*c.automaton.state_names, *c.automaton.signal_names}
    }
    if watched.location is not None:
        found.add(watched.location[0])
    return found


class Keyed(Protocol):
    """What the monitor reads of a mode: its key (a compiled mode is one; so is a bare key
    holder, when the run was computed elsewhere and only its margins are needed)."""

    @property
    def key(self) -> Mode: ...


class MarginTable:
    """The margin function of each requirement in scope, per mode (compiled on first use)."""

    def __init__(self, compiled: CompiledModel, watched: Sequence[Watched]) -> None:
        self.compiled = compiled
        self.watched = list(watched)
        self.failure = EvalFailure()
        self._binder = Binder(compiled.system)
        self._modes: dict[Mode, list[tuple[int, Fn]]] = {}
        self._functions: dict[tuple[int, tuple[tuple[str, int], ...]], Fn] = {}

    def of(self, mode: Keyed) -> list[tuple[int, Fn]]:
        """``(requirement index, margin)`` of every requirement in scope in ``mode``."""
        found = self._modes.get(mode.key)
        if found is None:
            found = self._compile(mode)
            self._modes[mode.key] = found
        return found

    def _compile(self, mode: Keyed) -> list[tuple[int, Fn]]:
        system = self.compiled.system
        view = None
        found: list[tuple[int, Fn]] = []
        for k, w in enumerate(self.watched):
            if w.location is not None and mode.key[w.location[0]] != w.location[1]:
                continue
            if view is None:
                view = mode_of(system, mode.key, binder=self._binder)
            predicate = w.requirement.predicate
            if w.component is not None:
                predicate = self._binder(w.component, predicate)
            margin = ir.Unary("-", guard_to_rho(predicate))
            reads = signals_read([margin], view.signals)
            key = (k, tuple((s, id(view.signals[s])) for s in reads))
            fn = self._functions.get(key)
            if fn is None:
                ctx = CodeContext(
                    states=self.compiled.state_names,
                    signals=view.signals,
                    inputs=self.compiled.inputs,
                    functions=system.functions,
                    failure=self.failure,
                )
                name = f"margin_{k}_{len(self._functions)}"
                fn = compile_function(name, [margin], ctx, shape="scalar")
                what = f"the condition of requirement '{w.name}'"
                self.compiled.sources[name] = Source(what, (margin,), ctx)
                self._functions[key] = fn
            found.append((k, fn))
        return found


_LOCK = threading.Lock()
_TABLES: weakref.WeakKeyDictionary[CompiledModel, MarginTable | None] = weakref.WeakKeyDictionary()


def monitor_for(compiled: CompiledModel, settings: Settings) -> Monitor | None:
    """A requirement monitor for one run of ``compiled`` (None if it has no requirement)."""
    table = margin_table(compiled)
    return None if table is None else Monitor(table, settings)


def margin_table(compiled: CompiledModel) -> MarginTable | None:
    """The margins of ``compiled``'s requirements (None without any), kept as long as it lives.

    The simulator reuses a compiled model across runs of the same model in a
    thread; its requirements' margins are compiled once with it.
    """
    with _LOCK:
        if compiled in _TABLES:
            return _TABLES[compiled]
        watched = watched_requirements(compiled.system)
        table = MarginTable(compiled, watched) if watched else None
        _TABLES[compiled] = table
        return table


DIP_REACH = 2.0
"""A local minimum is refined unless its value minus this many times the differences
to its neighbours stays above the smallest value seen (it cannot matter)."""

_EPS = float(np.finfo(float).eps)
_TOL = 4 * _EPS

Sample = tuple[float, float, Any, Any]
"""``(t, value, x, curve)``: a sample of a stretch in scope (``curve`` None for a lone point)."""


class _Track:
    """The running result of one requirement."""

    __slots__ = (
        "always",
        "best",
        "best_x",
        "failed",
        "fn",
        "hi",
        "lo",
        "piece",
        "seen",
        "sign",
        "started",
        "violated_at",
    )

    def __init__(self, kind: str, window: tuple[float, float] | None) -> None:
        self.always = kind == "always"
        self.sign = 1.0 if self.always else -1.0
        self.lo, self.hi = window if window is not None else (-math.inf, math.inf)
        self.best = math.inf
        self.best_x: Any = None  # the state at the best value (its band read at the end)
        self.violated_at: float | None = None
        self.seen = False
        self.failed: tuple[float, str] | None = None
        self.piece: list[Sample] = []
        self.started = False
        self.fn: Fn | None = None


class Monitor:
    """Monitors the requirements of a :class:`MarginTable` over one run.

    The recorder calls :meth:`point` for each point not inside a stay and
    :meth:`segment` for each accepted step; :meth:`results` gives the outcome.
    """

    def __init__(self, table: MarginTable, settings: Settings) -> None:
        self.table = table
        self.spacing = (settings.t_end - settings.t_start) / HORIZON_SAMPLES
        self.tracks = [_Track(w.requirement.kind, w.requirement.within) for w in table.watched]

    # --- what the recorder sees ---------------------------------------------------------

    def point(self, mode: Keyed, t: float, x: np.ndarray) -> None:
        """A point of the run not inside a stay (the start, the point after a jump)."""
        for k, fn in self.table.of(mode):
            tr = self.tracks[k]
            if tr.failed is not None or not tr.lo <= t <= tr.hi:
                continue
            self._close(tr)
            value = self._value(tr, fn, t, x)
            if value is not None:
                self._observe(tr, t, value, x)
                if tr.always and tr.violated_at is None and value < -band(x):
                    tr.violated_at = t

    def segment(self, mode: Keyed, curve: StepCurve, stop: float | None) -> None:
        """An accepted step of a stay in ``mode``, up to ``stop`` (None: its end)."""
        entries = self.table.of(mode)
        if not entries:
            return
        ta, tb = curve.t0, (curve.t1 if stop is None else stop)
        grids: dict[tuple[float, float], tuple[list[float], list[Any]]] = {}
        for k, fn in entries:
            tr = self.tracks[k]
            if tr.failed is not None:
                continue
            a, b = max(ta, tr.lo), min(tb, tr.hi)
            if a > b:
                continue
            last = tr.piece[-1] if tr.piece else None
            if last is None or tr.fn is not fn or last[0] != a:
                self._close(tr)
                tr.fn = fn
                tr.started = True
                x = curve.at(a)
                value = self._value(tr, fn, a, x)
                if value is None:
                    continue
                self._push(tr, (a, value, x, curve))
            if b == a:
                continue
            grid = grids.get((a, b))
            if grid is None:
                grid = grids[(a, b)] = _grid(curve, a, b, self.spacing)
            self._samples(tr, fn, curve, *grid)

    def _samples(
        self, tr: _Track, fn: Fn, curve: StepCurve, times: list[float], rows: list[Any]
    ) -> None:
        """Push the samples ``times`` (states ``rows``) of ``curve``'s step in order.

        The margin is evaluated at all of them first; where an evaluation fails
        (or a failure is pending) the samples from there on go one by one
        through :meth:`_value`, which ends the track as it would have.
        """
        failure = self.table.failure
        start = 0
        if failure.error is None:
            values = [fn(t, x) for t, x in zip(times, rows, strict=True)]
            if failure.error is not None:
                failure.clear()  # met again, at its sample, below
                values = []
            if self._quiet(tr, curve, times, rows, values):
                return
            sign, push, isfinite = tr.sign, self._push, math.isfinite
            for v in values:
                if failure.error is not None:  # left by a refinement: the next sample fails
                    break
                margin = float(v)
                if not isfinite(margin):
                    t = times[start]
                    tr.failed = (t, f"its margin is {margin} (at t={t:.9g})")
                    tr.piece = []
                    return
                push(tr, (times[start], sign * margin, rows[start], curve))
                start += 1
        for t, x in zip(times[start:], rows[start:], strict=True):
            value = self._value(tr, fn, t, x)
            if value is None:
                break
            self._push(tr, (t, value, x, curve))

    def results(self, t_final: float) -> dict[str, RequirementResult]:
        """Each requirement's result, the run having ended at ``t_final``."""
        found: dict[str, RequirementResult] = {}
        for w, tr in zip(self.table.watched, self.tracks, strict=True):
            self._close(tr)
            closes = min(tr.hi, t_final)
            if tr.failed is not None:
                found[w.name] = RequirementResult(
                    w.name, False, math.nan, tr.failed[0], f"cannot be evaluated: {tr.failed[1]}"
                )
            elif tr.always:
                robustness = tr.best if tr.seen else math.inf
                found[w.name] = RequirementResult(
                    w.name, tr.violated_at is None, robustness, tr.violated_at
                )
            else:
                peak = -tr.best if tr.seen else -math.inf
                best_band = band(tr.best_x) if tr.best_x is not None else 0.0
                holds = tr.seen and peak >= -best_band
                found[w.name] = RequirementResult(w.name, holds, peak, None if holds else closes)
        return found

    # --- one requirement ----------------------------------------------------------------

    def _value(self, tr: _Track, fn: Fn, t: float, x: Any) -> float | None:
        """``sign * margin`` at ``(t, x)``; None (and the track failed) if it cannot be computed."""
        value = float(fn(t, x))
        failure = self.table.failure
        if failure.error is not None or not math.isfinite(value):
            if failure.error is not None:
                why = describe_failure(self.table.compiled, failure).split(" failed: ", 1)[-1]
            else:
                why = f"its margin is {value}"
            tr.failed = (t, f"{why} (at t={t:.9g})")
            failure.clear()
            tr.piece = []
            return None
        return tr.sign * value

    def _quiet(
        self, tr: _Track, curve: StepCurve, times: list[float], rows: list[Any], values: list[Any]
    ) -> bool:
        """Take the samples at once if pushing them one by one would only keep the lowest.

        That is when the stretch is under way (two samples kept), every value is
        finite, none is a local minimum of the values with the two kept before
        them (nothing to refine) and none is below 0 (no violation); otherwise
        False, and nothing is changed.
        """
        piece = tr.piece
        if len(piece) != 2 or tr.started or not values:
            return False
        sign = tr.sign
        signed = [sign * float(v) for v in values]
        if not all(map(math.isfinite, signed)):
            return False
        low = min(signed)
        if tr.always and tr.violated_at is None and not low >= 0.0:
            return False
        seq = [piece[0][1], piece[1][1], *signed]
        for i in range(1, len(seq) - 1):
            left, mid, right = seq[i - 1], seq[i], seq[i + 1]
            if mid <= left and mid <= right and (mid < left or mid < right):
                return False
        tr.seen = True
        if low < tr.best:
            tr.best = low
            tr.best_x = rows[signed.index(low)]
        last = (times[-1], signed[-1], rows[-1], curve)
        if len(signed) >= 2:
            tr.piece = [(times[-2], signed[-2], rows[-2], curve), last]
        else:
            tr.piece = [piece[1], last]
        return True

    def _observe(self, tr: _Track, t: float, value: float, x: Any) -> None:
        tr.seen = True
        if value < tr.best:
            tr.best = value
            tr.best_x = x

    def _push(self, tr: _Track, sample: Sample) -> None:
        value = sample[1]
        tr.seen = True
        if value < tr.best:
            tr.best = value
            tr.best_x = sample[2]
        piece = tr.piece
        if len(piece) == 1 and tr.started:
            tr.started = False
            if piece[0][1] < value:
                self._refine(tr, piece[0], None, sample)  # the stretch starts rising
        if len(piece) == 2:
            left, mid = piece
            if mid[1] <= left[1] and mid[1] <= value and (mid[1] < left[1] or mid[1] < value):
                self._refine(tr, left, mid, sample)
        if tr.always and tr.violated_at is None and value < 0.0 and value < -band(sample[2]):
            if piece:
                before = piece[-1]
                tr.violated_at = self._crossing(tr, before, sample, sample[3])
            else:
                tr.violated_at = sample[0]
        if len(piece) == 2:
            piece.pop(0)
        piece.append(sample)

    def _close(self, tr: _Track) -> None:
        """End the open stretch: refine its last part if the values fall towards its end."""
        piece = tr.piece
        if len(piece) == 2 and piece[1][1] < piece[0][1] and piece[1][3] is not None:
            self._refine(tr, piece[0], None, piece[1])
        tr.piece = []
        tr.started = False

    def _refine(self, tr: _Track, left: Sample, mid: Sample | None, right: Sample) -> None:
        """Minimise between ``left`` and ``right`` (around ``mid``, or over one part)."""
        fn = tr.fn
        if fn is None:
            return
        values = [left[1], right[1]] if mid is None else [left[1], mid[1], right[1]]
        low = min(values)
        reach = sum(abs(v - low) for v in values)
        if low - DIP_REACH * reach > tr.best:
            return
        split = mid[0] if mid is not None else right[0]
        before = (mid if mid is not None else right)[3]
        after = right[3]
        sign, failure = tr.sign, self.table.failure

        def phi(t: float) -> float:
            curve = before if t <= split else after
            return sign * float(fn(t, curve.at(t)))

        t_min, v_min = _minimise(phi, left, mid, right)
        if failure.error is not None:
            failure.clear()  # at a point between samples: only the samples count for failures
            return
        if not math.isfinite(v_min):
            return
        x_min = (before if t_min <= split else after).at(t_min)
        self._observe(tr, t_min, v_min, x_min)
        if tr.always and tr.violated_at is None and v_min < -band(x_min):
            tr.violated_at = self._crossing(tr, left, (t_min, v_min, x_min, after), before, phi)

    def _crossing(
        self, tr: _Track, before: Sample, after: Sample, curve: Any, phi: Any = None
    ) -> float:
        """Where the margin crosses 0 between ``before`` (>= 0 side) and ``after`` (< 0)."""
        ta, va = before[0], before[1]
        tb, vb = after[0], after[1]
        if not va > 0.0:
            return ta
        fn = tr.fn
        if phi is None:
            assert fn is not None
            sign = tr.sign

            def phi(t: float) -> float:
                return sign * float(fn(t, curve.at(t)))

        def bracketed(t: float) -> float:
            if t == ta:
                return va
            if t == tb:
                return vb
            value: float = phi(t)
            return value

        from scipy.optimize import brentq  # here, not with the module: see _minimise

        try:
            root: float = brentq(bracketed, ta, tb, xtol=_TOL, rtol=_TOL)
        except (ValueError, RuntimeError):
            return tb
        self.table.failure.clear()
        return root


def _minimise(phi: Any, left: Sample, mid: Sample | None, right: Sample) -> tuple[float, float]:
    """The smallest value of ``phi`` between ``left`` and ``right`` (times and values known).

    Brent's method on a bracket ``a < b < c`` with ``phi(b)`` below both ends, to
    about 1e-11 in time, so that a minimum at a kink (a compound condition, an
    ``abs``) is found as well as a smooth one. Without such a bracket (a part at
    the start or end of a stretch, a tie) a bounded search looks for a point that
    makes one first.
    """
    # imported here, as brentq in Monitor._crossing: importing the monitor (a compiled run
    # replays requirements through it) loads no scipy until a margin is refined
    from scipy.optimize import minimize_scalar

    ta, va, tc, vc = left[0], left[1], right[0], right[1]
    if mid is not None and mid[1] < va and mid[1] < vc:
        tb, vb = mid[0], mid[1]
    else:
        coarse = minimize_scalar(
            phi, bounds=(ta, tc), method="bounded", options={"xatol": 1e-10 * (tc - ta)}
        )
        tb, vb = float(coarse.x), float(coarse.fun)
        if not (vb < va and vb < vc) or not ta < tb < tc:
            return (ta, va) if va <= vc else (tc, vc)
    fine = minimize_scalar(
        phi, bracket=(ta, tb, tc), method="brent", options={"xtol": 1e-12, "maxiter": 200}
    )
    t_fine, v_fine = float(fine.x), float(fine.fun)
    if ta <= t_fine <= tc and v_fine < vb:
        return t_fine, v_fine
    return tb, vb


def _grid(curve: StepCurve, a: float, b: float, spacing: float) -> tuple[list[float], list[Any]]:
    """The samples after ``a`` up to ``b`` (included) of the part ``[a, b]`` of ``curve``'s step."""
    m = parts(b - a, spacing)
    if a == curve.t0 and b == curve.t1:
        samples = curve.samples
        if samples is not None and samples[0] == m:  # the search's: the same times and states
            return samples[1], samples[2]
        times = [a + (b - a) * k / m for k in range(1, m)]
        rows: list[Any] = list(curve.parts(m)) if m > 1 else []
    else:
        times = [a + (b - a) * k / m for k in range(1, m)]
        rows = list(curve.many(np.array(times))) if times else []
    times.append(b)
    rows.append(curve.x1 if b == curve.t1 else curve.at(b))
    return times, rows


def join_groups(system: System, groups: Sequence[tuple[int, ...]]) -> list[tuple[int, ...]]:
    """``groups`` with those a system requirement spans merged into one (sorted tuples)."""
    merged = [set(g) for g in groups]
    for w in watched_requirements(system):
        if w.component is not None:
            continue
        needed = owners(system, w)
        touched = [g for g in merged if g & needed]
        if len(touched) > 1:
            union = set().union(*touched)
            merged = [g for g in merged if not g & needed] + [union]
    return sorted(tuple(sorted(g)) for g in merged)


def with_group_requirements(system: System, sub: System) -> System:
    """``sub`` (a group of ``system``'s components) with the system requirements it owns."""
    members = {i for i, c in enumerate(system.components) if any(c is s for s in sub.components)}
    own = tuple(
        w.requirement
        for w in watched_requirements(system)
        if w.component is None and owners(system, w) <= members
    )
    return replace(sub, requirements=own) if own else sub


def cut_results(
    parts: Sequence[tuple[Run, CompiledModel]], merged: Run, settings: Settings
) -> dict[str, RequirementResult]:
    """The requirements of every group, each over its run cut at the end of ``merged``."""
    found: dict[str, RequirementResult] = {}
    t_stop = merged.termination.t
    taken = {(jump.t, jump.edge) for jump in merged.jumps}
    for run, compiled in parts:
        if not run.requirements:
            continue
        j_stop = sum(1 for jump in run.jumps if (jump.t, jump.edge) in taken)
        end = run.termination
        if (end.t, end.j) == (t_stop, j_stop):
            found.update(run.requirements)
        else:
            found.update(_replay(run, compiled, settings, t_stop, j_stop))
    return found


def _replay(
    run: Run, compiled: CompiledModel, settings: Settings, t_stop: float, j_stop: int
) -> dict[str, RequirementResult]:
    """Monitor ``run`` again up to hybrid time ``(t_stop, j_stop)``, on its kept interpolants."""
    table = margin_table(compiled)
    assert table is not None
    monitor = Monitor(table, settings)
    modes = {m.name: m for m in compiled._modes.values()}
    first: dict[int, int] = {}
    for k, j in enumerate(run.j.tolist()):
        first.setdefault(j, k)
    stays: dict[int, list[tuple[float, float, Any]]] = {}
    for j, t0, t1, solution in run.segments:
        stays.setdefault(j, []).append((t0, t1, solution))
    for j in range(j_stop + 1):
        k = first[j]
        mode = modes[str(run.location[k])]
        monitor.point(mode, float(run.t[k]), run.states[k])
        for t0, t1, solution in sorted(stays.get(j, []), key=lambda s: s[0]):
            end = min(t1, t_stop) if j == j_stop else t1
            ends = solution.ts
            for i, piece in enumerate(solution.interpolants):
                a, b = float(ends[i]), float(ends[i + 1])
                if b <= t0 or a >= end:
                    continue
                curve = _Curve(a, b, piece)
                monitor.segment(mode, curve, None if b <= end else end)
    return monitor.results(t_stop)


class _Curve(StepCurve):
    """A step of a kept interpolant (a scipy ``DenseOutput``) as the monitor reads a step."""

    __slots__ = ("dense",)

    def __init__(self, t0: float, t1: float, dense: Any) -> None:
        super().__init__(
            t0, t1, np.asarray(dense(t0), dtype=float), np.asarray(dense(t1), dtype=float)
        )
        self.dense = dense

    def at(self, t: float) -> np.ndarray:
        if t == self.t0:
            return self.x0
        if t == self.t1:
            return self.x1
        return np.asarray(self.dense(t), dtype=float)

    def many(self, ts: np.ndarray) -> np.ndarray:
        return np.asarray(self.dense(ts), dtype=float).reshape(len(self.x0), -1).T
