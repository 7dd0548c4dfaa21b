"""``backend="auto"`` for a campaign: compiled when it pays for its compile, and a note saying so.

:func:`resolve_backend` turns a plan's ``auto`` into ``scipy`` or ``compiled``
(:func:`hybrid.simulation.native.choice.choose`: compiled when the model and the
kernel are in the compiled cache, or when the campaign's runs save more than
compiling costs, one scipy run of its first point timed to know), and warns a
:class:`BackendNote` with the choice and its reason (the command line prints
it as ``hybrid: note: backend auto: ...``). A resumed campaign's fingerprint
keeps ``auto``: a campaign resumed once the model is cached may finish on the
other backend. ``table.backend`` says which one ran.

Examples
--------
>>> import hybrid, warnings
>>> from hybrid.campaigns.runs import RunPlan
>>> ball = hybrid.load("specs/bouncing_ball.yaml")
>>> plan = RunPlan(t_end=3.0, solver={"method": "LSODA"}, backend="auto")
>>> with warnings.catch_warnings(record=True) as notes:
...     warnings.simplefilter("always")
...     chosen = resolve_backend(ball, [{"e": 0.5}], plan)
>>> chosen.backend, chosen.requested, str(notes[0].message)
('scipy', 'auto', "backend auto: scipy (method 'LSODA' is the scipy backend's)")
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Sequence
from dataclasses import replace
from typing import Any

from hybrid.campaigns.executors import Executor, InProcess, LocalPool
from hybrid.campaigns.runs import RunPlan, load_engine, run_point
from hybrid.campaigns.targets import split
from hybrid.errors import Note, UsageError, users_stacklevel

__all__ = ["BackendNote", "refuse_compiled", "resolve_backend", "settle"]


class BackendNote(Note):
    """Which backend ``auto`` chose for a campaign, and why."""


def resolve_backend(model: Any, points: Sequence[dict[str, float]], plan: RunPlan,
                    runs: int | None = None, announce: bool = True) -> RunPlan:  # fmt: skip
    """``plan`` with ``backend="auto"`` resolved (others as they are); ``runs``: how many
    the campaign makes (default: one per point); ``announce``: warn the choice (a
    :class:`BackendNote`; off when ``auto`` is the default nobody asked for:
    ``table.backend`` still says which ran)."""
    if plan.backend != "auto":
        return plan
    from hybrid.simulation.native.choice import choose

    held = bool(plan.inputs) or any(split(point).inputs for point in points)

    def run_s() -> float:  # one scipy run of the first point (its row is not kept)
        load_engine("scipy")  # counted in 1,000 runs, its import would choose compiled
        start = time.process_time()
        run_point(model, 0, points[0], replace(plan, backend="scipy"))
        return time.process_time() - start

    choice = choose(model, len(points) if runs is None else runs,
                    method=str(plan.solver.get("method", "RK45")), inputs=held,
                    run_s=run_s if points else None)  # fmt: skip
    if announce:
        warnings.warn(BackendNote(f"backend auto: {choice.backend} ({choice.reason})"),
                      stacklevel=users_stacklevel())
    return replace(plan, backend=choice.backend, requested="auto")


def refuse_compiled(model: Any, points: Sequence[dict[str, float]], plan: RunPlan) -> None:
    """Refuse, before any run, a campaign asked for on the compiled backend that every one of
    its runs would refuse: another method, inputs driven by expressions, points that hold
    an input (``auto`` chooses scipy for these).

    Examples
    --------
    >>> import hybrid
    >>> from hybrid.campaigns.runs import RunPlan
    >>> ball = hybrid.load("specs/bouncing_ball.yaml")
    >>> refuse_compiled(ball, [{"e": 0.5}], RunPlan(t_end=3.0, solver={"method": "RK23"}))
    Traceback (most recent call last):
    ...
    hybrid.errors.UsageError: the compiled backend integrates with RK45 (Dormand–Prince 5(4)); method 'RK23' needs backend 'scipy' (or 'auto', which chooses it)
    """
    from hybrid.compose import as_system
    from hybrid.simulation.native.features import METHOD, refuse_method, refuse_unsupported

    instead = "backend 'scipy' (or 'auto', which chooses it)"
    refuse_method(str(plan.solver.get("method", METHOD)), instead)
    if plan.inputs:
        raise UsageError(
            f"the compiled backend cannot drive input '{plan.inputs[0][0]}' with an expression "
            f"(--input, inputs=): use {instead}"
        )
    held = next((name for point in points for name in split(point).inputs), None)
    if held is not None:
        raise UsageError(
            f"the compiled backend cannot hold input '{held}' at a point's value "
            f"(input.{held}): use {instead}"
        )
    refuse_unsupported(as_system(model))


def settle(model: Any, points: Sequence[dict[str, float]], plan: RunPlan, executor: Executor,
           runs: int | None = None, announce: bool = True) -> tuple[RunPlan, Executor]:  # fmt: skip
    """The plan (``auto`` resolved, :func:`resolve_backend`) and the executor that runs it.

    A compiled campaign on local worker processes runs in this process
    instead: its batches are ensembles (:func:`hybrid.simulate_many`) that use
    every core already, and each worker process would import numba and load the
    compiled code first (a sweep of 1,000 thermostat points took 2.9 s on two
    warm workers, 0.24 s of CPU here). A Dask scheduler is kept as it is.
    """
    if plan.backend == "compiled":
        refuse_compiled(model, points, plan)
    plan = resolve_backend(model, points, plan, runs, announce)
    if plan.backend == "compiled" and isinstance(executor, LocalPool):
        return plan, InProcess()
    return plan, executor
