"""``hybrid.falsify``: search the varied ranges for a run that violates a requirement.

Falsification minimises the requirement's robustness over the box of the
varied ranges, within a budget of simulations, in two phases on the same
executors as a sweep:

1. **Global.** ``global_share`` of the budget goes to a seeded space-filling
   design of the box (a Latin hypercube by default, or scrambled Sobol:
   ``scipy.stats.qmc``), run in rounds of :data:`ROUND` points. After each
   round, the lowest-numbered violating point, if any, ends the search.
2. **Local.** The rest of the budget is shared by ``starts`` bounded
   Nelder-Mead searches (:mod:`~hybrid.campaigns.local_search`) from the lowest
   robustness points of the global phase, run side by side (one job each); each
   stops at its first violation.

The result is the counterexample (the violating point of the lowest-numbered
phase and start) or, when none is found, the point of lowest robustness, with
its run simulated again here (``result.run``: the trajectory and events to
look at). The search depends only on the seed, the budget and the model, not
on the executor or the number of workers.
"""

from __future__ import annotations

import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from hybrid.campaigns.choosing import settle
from hybrid.campaigns.executors import Executor
from hybrid.campaigns.local_search import evaluation, objective
from hybrid.campaigns.payload import pack
from hybrid.campaigns.runs import (
    RunPlan,
    failed_row,
    model_variant,
    requirement_columns,
    simulate_quietly,
    watchdog,
)
from hybrid.campaigns.space import SAMPLERS, Axis, checked_seed, ranges_axes, unit_samples
from hybrid.campaigns.sweep import campaign_backend, campaign_settings, executor_for, hard_limit
from hybrid.campaigns.targets import Constant, check_names, split
from hybrid.compose import System, as_system, expect_model
from hybrid.errors import UsageError
from hybrid.keywords import keywords_of, named_keywords
from hybrid.model import Automaton
from hybrid.progress import Progress, Tracker, reporter
from hybrid.simulation.interrupts import sigint_watch
from hybrid.simulation.result import Run
from hybrid.simulation.settings import Settings

__all__ = ["ROUND", "Falsification", "falsify"]

ROUND = 16
"""Points of the global phase run between two looks for a violation."""


@dataclass
class Falsification:
    """What a falsification found.

    ``found`` says whether a run violates ``requirement``; ``values`` is that
    run's point (or, when none was found, the point of lowest robustness), with
    its ``robustness``; ``run`` is its run, simulated again. ``history`` holds
    every evaluation in order (``phase``: ``global`` or ``local <k>``).
    """

    requirement: str
    found: bool
    values: dict[str, float]
    robustness: float
    evaluations: int
    budget: int
    seed: int
    run: Run | None = None
    history: list[dict[str, Any]] = field(default_factory=list)
    complete: bool = True

    @property
    def failed(self) -> list[dict[str, Any]]:
        """The evaluations whose run failed (raised, timed out, a worker lost): their points
        were not judged, so no violation found among them is no evidence of none."""
        return [h for h in self.history if h.get("failed")]

    @property
    def violated_at(self) -> float | None:
        """When the counterexample's run first violates the requirement."""
        if self.run is None or self.requirement not in self.run.requirements:
            return None
        return self.run.requirements[self.requirement].violated_at

    def as_dict(self) -> dict[str, Any]:
        """The JSON document ``hybrid falsify`` writes (``falsification.json``)."""
        return {
            "requirement": self.requirement,
            "found": self.found,
            "values": self.values,
            "robustness": self.robustness,
            "violated_at": self.violated_at,
            "evaluations": self.evaluations,
            "budget": self.budget,
            "seed": self.seed,
            "complete": self.complete,
            "failed": len(self.failed),
            "history": self.history,
        }

    def __repr__(self) -> str:
        """What was found, and what the search could not judge.

        Examples
        --------
        >>> Falsification("cool", False, {"a": 0.05}, float("inf"), 8, 40, 0,
        ...               history=[{"failed": True}] * 8, complete=False)
        <Falsification of cool: no violation; lowest robustness inf at a=0.05 (8 of 40 runs; 8 failed, not judged; stopped early)>
        """
        what = "counterexample" if self.found else "no violation; lowest robustness"
        shown = ", ".join(f"{k}={v:.6g}" for k, v in self.values.items())
        failed = len(self.failed)
        notes = (f"; {failed} failed, not judged" if failed else "") + (
            "" if self.complete else "; stopped early")  # fmt: skip
        return (
            f"<Falsification of {self.requirement}: {what} {self.robustness:.6g} at {shown} "
            f"({self.evaluations} of {self.budget} runs{notes})>"
        )


@named_keywords
def falsify(
    model: Automaton | System,
    requirement: str,
    vary: Mapping[str, tuple[float, float] | None] | Sequence[Axis | str] | None = None,
    *,
    t_end: float | None = None,
    settings: Settings | None = None,
    budget: int = 100,
    seed: int = 0,
    sampler: str = "lhs",
    global_share: float = 0.5,
    starts: int = 2,
    parameters: Mapping[str, float] | None = None,
    inputs: Mapping[str, str] | None = None,
    workers: int | None = None,
    scheduler: Any = None,
    run_timeout: float | None = None,
    progress: Progress = None,
    handle_sigint: bool = True,
    backend: str | None = None,
    **solver: Any,
) -> Falsification:
    """Search ``vary`` for a run of ``model`` that violates ``requirement``.

    Parameters
    ----------
    model : Automaton or System
        From :func:`hybrid.load`.
    requirement : str
        The requirement's name (``comp.name`` for a component's, in a system).
    vary : mapping or sequence of Axis or str, optional
        ``{name: (low, high)}``: parameters, ``init.x``, ``input.u``. An ``init.x``
        or ``input.u`` with the range ``None`` (or a bare name in a sequence) is
        searched over the range its spec declares; not given: every range the
        spec declares (initial sets and input ranges, as :func:`hybrid.sweep`).
    t_end : float, optional
        End time of every run; needed unless ``settings`` gives it.
    settings : Settings, optional
        The options of every run (:class:`hybrid.Settings`), overridden by the
        keywords given, as for :func:`hybrid.sweep`.
    budget : int
        Simulations at most, both phases together.
    seed : int
        Seed of the global phase (everything else is deterministic).
    sampler : {"lhs", "sobol", "random"}
        The design of the global phase.
    global_share : float
        Share of the budget for the global phase, in (0, 1].
    starts : int
        Local searches, from the best points of the global phase.
    parameters, inputs, workers, scheduler, run_timeout, progress, handle_sigint, backend
        As for :func:`hybrid.sweep`.
    **solver
        ``rtol``, ``atol``, ``max_step``... as :func:`hybrid.simulate` takes them
        (overriding ``settings``).

    Returns
    -------
    Falsification
        ``found``, ``values``, ``robustness``, ``run`` (the run at ``values``).

    Examples
    --------
    >>> import hybrid
    >>> heater = hybrid.load_text('''
    ... automaton: heater
    ... parameters: {k: 0.1}
    ... state: {x: {initial: 20.0}}
    ... locations: {cooling: {flow: {x: -k*x}}}
    ... requirements: [{name: warm, always: "x >= 15"}]
    ... ''')
    >>> result = hybrid.falsify(heater, "warm", {"k": (0.0, 0.1)}, t_end=5.0, budget=20,
    ...                         seed=1, workers=0)
    >>> result.found, result.values["k"] > 0.0575, result.robustness < 0
    (True, True, True)
    """
    expect_model(model, "falsify")
    seed = checked_seed(seed)
    chosen, solver = campaign_settings("falsify", settings, t_end, solver, keywords_of(falsify))
    t_end, (backend, announce) = chosen.t_end, campaign_backend(backend, chosen)
    if isinstance(budget, bool) or not isinstance(budget, int) or budget < 1:
        raise UsageError(f"budget must be a whole number >= 1, got {budget!r}")
    if not 0.0 < global_share <= 1.0:
        raise UsageError(f"global_share must be in (0, 1], got {global_share}")
    if sampler not in SAMPLERS:
        raise UsageError(f"unknown sampler '{sampler}' (choose from {', '.join(SAMPLERS)})")
    if isinstance(starts, bool) or not isinstance(starts, int) or starts < 1:
        raise UsageError(f"starts must be a whole number >= 1, got {starts!r}")
    if parameters:
        model = model.with_parameters(dict(parameters))
    system = as_system(model)  # the one model type below; the user's model goes to the workers
    axes = ranges_axes(system, vary)
    if not axes:
        raise UsageError(
            "nothing to vary: give --vary NAME=LO:HI (the spec declares no initial set or "
            "input range)"
        )
    names = [a.name for a in axes]
    check_names(system, names, parameters or ())
    if f"{requirement}.holds" not in requirement_columns(system):
        known = [c[: -len(".holds")] for c in requirement_columns(system)[::3]]
        raise UsageError(
            f"no requirement '{requirement}' in {model.name} "
            f"(requirements: {', '.join(known) or 'none'})"
        )
    ranged = system.input_ranges()  # held at its nominal value when not varied
    missing = [
        n
        for n in system.free_inputs
        if n not in (inputs or {}) and f"input.{n}" not in names and n not in ranged
    ]
    if missing:
        raise UsageError(
            f"input '{missing[0]}' needs a value: vary it or give it",
            at=system.input_position(missing[0]),
        )
    plan = RunPlan(
        t_end=float(t_end),
        solver=dict(solver),
        inputs=tuple(sorted((inputs or {}).items())),
        timeout=run_timeout,
        backend=backend,
    )
    executor = executor_for(workers, scheduler)
    search = _Search(system, requirement, axes, plan, budget, seed, sampler, global_share, starts)
    middle = search.values_of([0.5] * len(axes))  # what auto times one scipy run of
    search.plan, executor = settle(system, [middle], plan, executor, runs=budget, announce=announce)
    with sigint_watch(handle_sigint) as interrupts, executor:
        executor.start(pack(model), search.plan)
        search.run(executor, lambda: interrupts.requested, progress)
    return search.result()


class _Search:
    """The two phases of one falsification (see the module docstring)."""

    def __init__(
        self,
        model: System,
        requirement: str,
        axes: Sequence[Axis],
        plan: RunPlan,
        budget: int,
        seed: int,
        sampler: str,
        global_share: float,
        starts: int,
    ) -> None:
        self.model, self.requirement, self.axes, self.plan = model, requirement, axes, plan
        self.budget, self.seed, self.sampler = budget, seed, sampler
        self.n_global = max(1, min(budget, round(budget * global_share)))
        self.starts = max(1, starts)
        self.history: list[dict[str, Any]] = []
        self.found: dict[str, Any] | None = None
        self.complete = True

    def values_of(self, unit: Sequence[float]) -> dict[str, float]:
        return {
            a.name: a.low + float(u) * (a.high - a.low)
            for a, u in zip(self.axes, unit, strict=True)
        }

    def run(self, executor: Executor, stop: Any, progress: Progress) -> None:
        tracker = Tracker("falsify", total=self.budget, unit="runs", report=reporter(progress))
        units = unit_samples(len(self.axes), self.n_global, self.seed, self.sampler)
        points = [self.values_of(u) for u in units]
        rows: dict[int, dict[str, Any]] = {}

        def failed(job: tuple[int, str, Any], cause: str, message: str) -> dict[str, Any]:
            return {"run": job[0], **job[2], **failed_row(self.model, self.plan, cause, message)}

        violations = [0]

        def keep(index: int, row: dict[str, Any]) -> None:
            rows[index] = row  # every run of the global phase so far
            violations[0] += objective(row, self.requirement)[1]
            tracker.update(len(rows), violations=violations[0])

        limit = hard_limit(self.plan.timeout)
        for start in range(0, len(points), ROUND):
            jobs = [(i, "run", points[i]) for i in range(start, min(len(points), start + ROUND))]
            if not executor.run(jobs, keep, failed, stop, limit):
                self.complete = False
                break
            for i, _, values in jobs:
                self.history.append({**evaluation(values, rows[i], self.requirement), "phase": "global"})
                if self.history[-1]["violated"] and self.found is None:
                    self.found = self.history[-1]
            if self.found is not None:
                break
        left = self.budget - len(self.history)
        if self.found is None and self.complete and left > 0:
            self._local(executor, stop, left, tracker)
        done = len(self.history)  # a counterexample found early: the runs made were the work
        tracker.finish(done, total=done if self.found is not None else None, violations=self.violations())

    def _local(self, executor: Executor, stop: Any, left: int, tracker: Tracker) -> None:
        ranked = sorted(range(len(self.history)), key=lambda i: (self.history[i]["robustness"], i))
        seeds = ranked[: min(self.starts, left)]
        shares = [
            left // len(seeds) + (1 if k < left % len(seeds) else 0) for k in range(len(seeds))
        ]
        jobs = []
        for k, (i, share) in enumerate(zip(seeds, shares, strict=True)):
            point = self.history[i]
            unit = [
                (point[a.name] - a.low) / (a.high - a.low) if a.high > a.low else 0.0
                for a in self.axes
            ]
            task = {
                "names": [a.name for a in self.axes],
                "lows": [a.low for a in self.axes],
                "highs": [a.high for a in self.axes],
                "start": unit,
                "budget": share,
                "requirement": self.requirement,
                "step": 0.1,
            }
            jobs.append((k, "search", task))
        results: dict[int, dict[str, Any]] = {}

        def keep(index: int, result: dict[str, Any]) -> None:
            results[index] = result

        def failed(job: tuple[int, str, Any], cause: str, message: str) -> dict[str, Any]:
            return {
                "found": False,
                "values": None,
                "robustness": math.inf,
                "evaluations": 0,
                "history": [],
            }

        # a job is up to its share of runs, each bounded like a run of the global phase
        per_run = hard_limit(self.plan.timeout)
        limit = None if per_run is None else per_run * max(shares)
        if not executor.run(jobs, keep, failed, stop, limit):
            self.complete = False
        for k in sorted(results):
            for entry in results[k]["history"]:
                self.history.append({**entry, "phase": f"local {k}"})
                if entry["violated"] and self.found is None:
                    self.found = self.history[-1]
        tracker.update(len(self.history), violations=self.violations())

    def violations(self) -> int:
        """The runs so far that violate the requirement."""
        return sum(1 for h in self.history if h["violated"])

    def result(self) -> Falsification:
        names = [a.name for a in self.axes]
        if self.found is not None:
            chosen = self.found
        elif self.history:
            chosen = min(self.history, key=lambda h: h["robustness"])
        else:
            chosen = {**self.values_of([0.0] * len(self.axes)), "robustness": math.inf}
        values = {n: float(chosen[n]) for n in names}
        run = None
        if self.history and not chosen.get("failed"):  # a point whose run failed: not again
            over = split(values)
            from hybrid.simulation.inputs import ExpressionInput

            inputs: dict[str, Any] = {n: ExpressionInput(n, s) for n, s in self.plan.inputs}
            inputs.update({n: Constant(v) for n, v in over.inputs.items()})
            timeout = self.plan.timeout
            bound = None if timeout is None else watchdog(time.monotonic() + timeout, timeout)
            try:
                run = simulate_quietly(
                    model_variant(self.model, over.parameters),
                    t_end=self.plan.t_end,
                    initial=over.initial or None,
                    inputs=inputs or None,
                    handle_sigint=False,
                    progress=bound,  # the run timeout holds here too
                    **self.plan.solver,
                )
            except Exception:  # the run failed in the search too: no trajectory to show
                run = None
        return Falsification(
            self.requirement,
            self.found is not None,
            values,
            float(chosen["robustness"]),
            len(self.history),
            self.budget,
            self.seed,
            run,
            self.history,
            self.complete,
        )
