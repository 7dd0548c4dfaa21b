"""One run of a campaign: a point's values applied, simulated, and summed up in a row.

:func:`run_point` is what every executor calls, in a worker or in this process:
it applies the point (parameters, initial values, constant inputs), simulates
with the campaign's :class:`RunPlan`, and returns the row: the varied values,
how the run ended (``cause``, ``t``, ``j``), its number of ``jumps`` and
``zeno_time``, each requirement's ``holds``/``robustness``/``violated_at``, and
the summaries asked for. A run that raises is a row with cause ``error`` and
the message; a run longer than the plan's ``timeout`` is a row with cause
``timeout``. Nothing a run does ends the campaign.

The plan's ``backend`` is passed to :func:`hybrid.simulate` as it is (``scipy``,
the default, is not passed, so today's engine runs as it always has); with
``compiled``, :func:`run_points` runs a worker's whole batch in one call of
:func:`hybrid.simulate_many` where it can.

Summaries (``KIND:NAME``) read the stored points of the run (``dt`` makes them
denser; a requirement's robustness is the exact extreme):

=============  ==================================================================
``max:x``      the largest value of state variable or signal ``x``
``min:x``      the smallest
``last:x``     the value at the end of the run
``mean:x``     the time average (trapezoids over the stored points)
``jumps:E``    the number of jumps of edge ``E``, or of component ``E``'s edges
``jump_t:K``   the time of the ``K``-th jump (1 is the first); NaN if fewer
=============  ==================================================================

Examples
--------
>>> import hybrid
>>> from hybrid.compose import as_system
>>> ball = as_system(hybrid.load("specs/bouncing_ball.yaml"))  # what a worker is given
>>> plan = RunPlan(t_end=3.0, summaries=(Summary.parse("jump_t:1"), Summary.parse("max:v")))
>>> row = run_point(ball, 0, {"e": 0.5}, plan)
>>> row["run"], row["e"], row["cause"], row["jumps"], round(row["jump_t:1"], 6)
(0, 0.5, 't_end', 2, 1.427843)
"""

from __future__ import annotations

import math
import threading
import time
import warnings
from collections import OrderedDict
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from hybrid.campaigns.targets import Constant, split
from hybrid.compose import System
from hybrid.errors import HybridError, UsageError
from hybrid.simulation.bounds import BoundsWarning
from hybrid.simulation.result import Run
from hybrid.simulation.watched import watched_requirements

__all__ = [
    "OUTCOME_COLUMNS",
    "SUMMARY_KINDS",
    "RunPlan",
    "RunTimeout",
    "Summary",
    "failed_row",
    "load_engine",
    "model_variant",
    "requirement_columns",
    "run_point",
    "run_points",
    "simulate_quietly",
    "watchdog",
]

OUTCOME_COLUMNS = ("cause", "t", "j", "jumps", "zeno_time", "message")
"""How each run ended, after the run number and the varied values."""

SUMMARY_KINDS = ("max", "min", "last", "mean", "jumps", "jump_t")
REQUIREMENT_FIELDS = ("holds", "robustness", "violated_at")


class RunTimeout(Exception):
    """A run went on longer than the campaign's ``run_timeout``."""


@dataclass(frozen=True)
class Summary:
    """A number read off each run: ``KIND:NAME`` (see the module docstring)."""

    kind: str
    name: str

    @classmethod
    def parse(cls, text: str) -> Summary:
        kind, sep, name = text.partition(":")
        if not sep or kind not in SUMMARY_KINDS or not name:
            raise UsageError(
                f"summary '{text}': expected KIND:NAME with KIND one of {', '.join(SUMMARY_KINDS)}"
            )
        if kind == "jump_t" and not (name.isdigit() and int(name) >= 1):
            raise UsageError(f"summary '{text}': jump_t needs a jump number >= 1")
        return cls(kind, name)

    @property
    def column(self) -> str:
        return f"{self.kind}:{self.name}"

    def check(self, system: System) -> None:
        """A :class:`UsageError` if ``system`` has nothing of that name."""
        if self.kind in ("max", "min", "last", "mean"):
            known = [*system.state_names, *system.signal_columns]
            if self.name not in known:
                raise UsageError(
                    f"summary '{self.column}': no state variable or signal '{self.name}' "
                    f"(columns: {', '.join(known)})"
                )
        elif self.kind == "jumps":
            edges = {
                system.qualified(i, e.name)
                for i, c in enumerate(system.components)
                for e in c.automaton.edges
            }
            if self.name not in edges and self.name not in {c.name for c in system.components}:
                raise UsageError(f"summary '{self.column}': no edge or component '{self.name}'")

    def of(self, run: Run) -> float | int:
        """The summary's value on ``run`` (a count for ``jumps:E``, a number otherwise)."""
        if self.kind == "jumps":
            prefix = f"{self.name}."
            return sum(1 for j in run.jumps if j.edge == self.name or j.edge.startswith(prefix))
        if self.kind == "jump_t":
            k = int(self.name)
            return float(run.jumps[k - 1].t) if len(run.jumps) >= k else math.nan
        values = run[self.name]
        if values.size == 0:
            return math.nan
        if self.kind == "max":
            return float(np.max(values))
        if self.kind == "min":
            return float(np.min(values))
        if self.kind == "last":
            return float(values[-1])
        span = float(run.t[-1] - run.t[0])
        if span <= 0.0:
            return float(values[-1])
        return float(np.sum(np.diff(run.t) * (values[1:] + values[:-1]) / 2.0) / span)


@dataclass(frozen=True)
class RunPlan:
    """Everything a run of the campaign needs besides its point (sent to every worker once)."""

    t_end: float
    solver: Mapping[str, Any] = field(default_factory=dict)
    """Keyword arguments of :func:`hybrid.simulate` (``rtol``, ``atol``, ``max_step``...)."""
    summaries: tuple[Summary, ...] = ()
    inputs: tuple[tuple[str, str], ...] = ()
    """Free inputs held by an expression of ``t`` in every run (``--input NAME=EXPR``)."""
    timeout: float | None = None
    backend: str = "scipy"
    requested: str = ""
    """The backend asked for when it was ``auto`` (:mod:`hybrid.campaigns.choosing`), else empty."""


def requirement_columns(system: System) -> list[str]:
    """``name.holds``, ``name.robustness``, ``name.violated_at`` per requirement, in order."""
    names = [w.name for w in watched_requirements(system)]
    return [f"{n}.{f}" for n in names for f in REQUIREMENT_FIELDS]


_VARIANTS: OrderedDict[tuple[int, tuple[tuple[str, float], ...]], tuple[System, System]] = (
    OrderedDict()
)
_VARIANT_CACHE = 16
_VARIANTS_LOCK = threading.Lock()


def model_variant(model: System, parameters: Mapping[str, float]) -> System:
    """``model`` with ``parameters``, the same object for the same values.

    The simulator keeps a compiled model per model object (and thread), so runs that
    differ only in initial values or inputs reuse one compiled model.
    """
    key = (id(model), tuple(sorted(parameters.items())))
    with _VARIANTS_LOCK:
        hit = _VARIANTS.get(key)
        if hit is not None and hit[0] is model:
            _VARIANTS.move_to_end(key)
            return hit[1]
    system = model.with_parameters(dict(parameters)) if parameters else model
    with _VARIANTS_LOCK:
        _VARIANTS[key] = (model, system)
        if len(_VARIANTS) > _VARIANT_CACHE:
            _VARIANTS.popitem(last=False)
    return system


def simulate_quietly(*args: Any, **kwargs: Any) -> Run:
    """:func:`~hybrid.simulation.engine.simulate` without a :class:`BoundsWarning` per run.

    A campaign's runs are rows of a table, not lines of a log: thousands of
    runs would repeat the same warning. The engine is imported here, on the
    first scipy run: a compiled campaign never loads scipy's integrators.
    """
    from hybrid.simulation.engine import simulate

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", BoundsWarning)
        return simulate(*args, **kwargs)


def load_engine(backend: str) -> None:
    """Load the scipy engine now unless the runs are compiled: before a run's clock starts.

    A process loads it on its first scipy run otherwise (0.45 to 0.75 s of scipy's
    integrators), which a run's timeout or a timed run would count as the run's own.
    """
    if backend != "compiled":
        from hybrid.simulation import reference  # noqa: F401


def _load_compiled(model: System) -> None:
    """The compiled loop and ``model``'s compiled code, loaded in this process now (once:
    the structure's code serves every parameter value), so that a run's timeout counts the
    run only (the first compiled run of a process loads for about 2 s from a warm cache)."""
    from hybrid.simulation.native.engine import compiled_native

    compiled_native(model)


def run_point(
    model: System, index: int, point: Mapping[str, float], plan: RunPlan
) -> dict[str, Any]:
    """The row of run ``index`` at ``point`` (see the module docstring)."""
    row: dict[str, Any] = {"run": index, **point}
    over = split(point)
    load_engine(plan.backend)  # its import is not the run's time
    try:
        if plan.backend == "compiled" and plan.timeout is not None:
            _load_compiled(model)  # nor is loading (or compiling) the model's compiled code
    except HybridError as exc:
        return {**row, **failed_row(model, plan, "error", str(exc))}
    deadline = None if plan.timeout is None else time.monotonic() + plan.timeout
    try:
        target = model_variant(model, over.parameters)
        inputs: dict[str, Any] = {}
        if plan.inputs:
            from hybrid.simulation.inputs import ExpressionInput

            inputs.update({n: ExpressionInput(n, s) for n, s in plan.inputs})
        inputs.update({n: Constant(v) for n, v in over.inputs.items()})
        extra: dict[str, Any] = {} if plan.backend == "scipy" else {"backend": plan.backend}
        run = simulate_quietly(
            target,
            t_end=plan.t_end,
            initial=over.initial or None,
            inputs=inputs or None,
            handle_sigint=False,
            progress=None if deadline is None else watchdog(deadline, plan.timeout),
            **plan.solver,
            **extra,
        )
    except RunTimeout as exc:
        return {**row, **failed_row(model, plan, "timeout", str(exc))}
    except HybridError as exc:
        return {**row, **failed_row(model, plan, "error", str(exc))}
    except Exception as exc:  # a bug must not end the campaign: the row says what happened
        return {
            **row,
            **failed_row(model, plan, "error", f"internal error: {type(exc).__name__}: {exc}"),
        }
    return _row_of(row, run, plan)


def _row_of(row: dict[str, Any], run: Run, plan: RunPlan) -> dict[str, Any]:
    """``row`` with how ``run`` ended, its requirements and the plan's summaries."""
    end = run.termination
    row.update(
        cause=end.cause,
        t=float(end.t),
        j=int(end.j),
        jumps=len(run.jumps),
        zeno_time=end.zeno_time,
        message="" if end.cause == "t_end" else end.message,
    )
    for name, result in run.requirements.items():
        row[f"{name}.holds"] = result.holds
        row[f"{name}.robustness"] = result.robustness
        row[f"{name}.violated_at"] = result.violated_at
    for summary in plan.summaries:
        row[summary.column] = summary.of(run)
    return row


def run_points(
    model: System, batch: Sequence[tuple[int, Mapping[str, float]]], plan: RunPlan
) -> list[dict[str, Any]]:
    """The rows of a batch of ``(index, point)``.

    With ``backend="compiled"`` the batch is one call of :func:`hybrid.simulate_many`
    (one compiled loop, threads over runs) when every run can go there: no run
    timeout, no held inputs, only the solver options the ensemble takes. Otherwise,
    or if the ensemble refuses the model, each run is :func:`run_point`.
    """
    if plan.backend == "compiled" and len(batch) > 1 and _fits_ensemble(batch, plan):
        try:
            return _ensemble_rows(model, batch, plan)
        except HybridError:
            pass  # each run says why, in its own row
    return [run_point(model, index, point, plan) for index, point in batch]


_ENSEMBLE_OPTIONS = frozenset(
    ("rtol", "atol", "max_step", "max_jumps", "dt", "zeno", "max_jumps_per_instant", "t_start")
)


def _fits_ensemble(batch: Sequence[tuple[int, Mapping[str, float]]], plan: RunPlan) -> bool:
    return (
        plan.timeout is None
        and not plan.inputs
        and set(plan.solver) - {"method"} <= _ENSEMBLE_OPTIONS
        and plan.solver.get("method", "RK45") == "RK45"
        and not any(split(point).inputs for _, point in batch)
    )


def _ensemble_rows(
    model: System, batch: Sequence[tuple[int, Mapping[str, float]]], plan: RunPlan
) -> list[dict[str, Any]]:
    """The batch's rows from one :func:`hybrid.simulate_many` call."""
    from hybrid.simulation.native.many import simulate_many

    columns: dict[str, list[float]] = {}
    for _, point in batch:
        over = split(point)
        for key, value in [*over.parameters.items(), *(("init." + k, v) for k, v in over.initial.items())]:
            columns.setdefault(key, []).append(float(value))
    if any(len(column) != len(batch) for column in columns.values()):
        raise UsageError("the points of a batch vary different names")
    options = {k: v for k, v in plan.solver.items() if k != "method"}
    with warnings.catch_warnings():  # rows of a table, as simulate_quietly
        warnings.simplefilter("ignore", BoundsWarning)
        runs = simulate_many(
            model, plan.t_end, parameters=columns or None, handle_sigint=False, **options
        )
    return [_row_of({"run": index, **point}, runs[k], plan) for k, (index, point) in enumerate(batch)]


def failed_row(
    model: System, plan: RunPlan, cause: str, message: str
) -> dict[str, Any]:
    """The outcome columns of a run that did not finish (``error``, ``timeout``)."""
    row: dict[str, Any] = dict.fromkeys(OUTCOME_COLUMNS)
    row.update(cause=cause, message=message)
    row.update(dict.fromkeys(requirement_columns(model)))
    row.update({s.column: None for s in plan.summaries})
    return row


def watchdog(deadline: float, limit: float | None) -> Any:
    """A ``progress`` for :func:`hybrid.simulate` that ends the run (``RunTimeout``) after
    ``deadline`` (``time.monotonic``); ``limit`` is the timeout it names."""
    def check(status: object) -> None:
        if time.monotonic() > deadline:
            raise RunTimeout(f"the run took longer than the run timeout of {limit:g} s")

    return check
