"""``hybrid.sweep``: many runs of one model over a grid or seeded samples, on any executor.

The points are made here, in run order (:mod:`~hybrid.campaigns.space`), and
never depend on the executor; each run's row comes back whenever it finishes
and is kept by run number (:mod:`~hybrid.campaigns.resumable` writes it to disk in
chunks when the campaign has an ``out`` file), so the table is the same with
one worker, many, or a Dask cluster. Ctrl-C stops the campaign cleanly: the
rows finished are kept (on disk with ``out``), the table says it is
incomplete, and ``resume=True`` runs only the rest.
"""

from __future__ import annotations

import hashlib
import json
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from hybrid.campaigns.choosing import settle
from hybrid.campaigns.executors import Executor, InProcess, LocalPool, default_workers
from hybrid.campaigns.payload import Payload, pack
from hybrid.campaigns.resumable import LOST, ChunkStore
from hybrid.campaigns.runs import (
    OUTCOME_COLUMNS,
    RunPlan,
    Summary,
    failed_row,
    requirement_columns,
)
from hybrid.campaigns.space import (
    Axis,
    Point,
    checked_seed,
    combine,
    grid_axes,
    grid_points,
    ranges_axes,
    sample_points,
)
from hybrid.campaigns.table import FAILED, SweepTable
from hybrid.campaigns.targets import INPUT, check_names
from hybrid.compose import System, as_system, expect_model
from hybrid.errors import UsageError
from hybrid.files import writable_target
from hybrid.keywords import keywords_of, named_keywords, refused_argument
from hybrid.model import Automaton
from hybrid.progress import Progress, Tracker, reporter
from hybrid.simulation.interrupts import sigint_watch
from hybrid.simulation.settings import DEFAULTS, Settings, merged
from hybrid.simulation.watched import watched_requirements

__all__ = ["SOLVER_OPTIONS", "campaign_settings", "executor_for", "hard_limit", "sweep"]

SOLVER_OPTIONS = (
    "rtol",
    "atol",
    "max_step",
    "method",
    "max_jumps",
    "dt",
    "zeno",
    "max_jumps_per_instant",
    "t_start",
)
"""The keywords of :func:`hybrid.simulate` a campaign passes to every run."""


def campaign_settings(
    what: str,
    settings: Settings | None,
    t_end: float | None,
    solver: Mapping[str, Any],
    taken: Sequence[str] = (),
) -> tuple[Settings, dict[str, Any]]:
    """The settings of a campaign's runs, and the options of them that are not the defaults.

    ``solver`` are the keywords given to ``what`` (an unknown one is refused as
    Python refuses it); those given override ``settings``. The options returned
    are what every run passes to :func:`hybrid.simulate` (and what the
    campaign's fingerprint records): the same runs give the same options,
    whether keywords or a :class:`~hybrid.simulation.settings.Settings` said them.

    Examples
    --------
    >>> s, options = campaign_settings("sweep", None, 2.0, {"rtol": 1e-9, "atol": 1e-9})
    >>> s.rtol, options
    (1e-09, {'rtol': 1e-09})
    """
    unknown = sorted(set(solver) - set(SOLVER_OPTIONS))
    if unknown:  # named with the keyword meant (``taken``: the campaign's own too)
        raise refused_argument(what, unknown[0], (*taken, *SOLVER_OPTIONS))
    chosen = merged(settings, t_end, **solver)
    options = {k: getattr(chosen, k) for k in SOLVER_OPTIONS}
    return chosen, {k: v for k, v in options.items() if v != DEFAULTS[k]}


def campaign_backend(backend: str | None, chosen: Settings) -> tuple[str, bool]:
    """The backend of a campaign's runs, and whether it was asked for.

    The keyword wins, then the settings' backend; neither gives ``"auto"``, the
    default, whose choice is then not announced (``table.backend`` says it).

    Examples
    --------
    >>> s = Settings(t_end=1.0)
    >>> campaign_backend(None, s), campaign_backend("auto", s)
    (('auto', False), ('auto', True))
    >>> campaign_backend("numba", s)
    Traceback (most recent call last):
    hybrid.errors.UsageError: unknown backend 'numba'; choose one of scipy, compiled, auto
    """
    asked = backend or chosen.backend
    if asked is not None:  # checked here, not by every run: a campaign of failed rows
        Settings(t_end=1.0, backend=asked)  # its checks: the same message as simulate's
    return asked or "auto", asked is not None


@named_keywords
def sweep(
    model: Automaton | System,
    t_end: float | None = None,
    *,
    settings: Settings | None = None,
    grid: Mapping[str, Sequence[float] | int] | Sequence[Axis | tuple[str, int]] | None = None,
    vary: Mapping[str, tuple[float, float] | None] | Sequence[Axis | str] | None = None,
    samples: int | None = None,
    seed: int = 0,
    sampler: str = "lhs",
    points: Sequence[Mapping[str, float]] | None = None,
    parameters: Mapping[str, float] | None = None,
    inputs: Mapping[str, str] | None = None,
    summaries: Sequence[str] = (),
    workers: int | None = None,
    scheduler: Any = None,
    run_timeout: float | None = None,
    out: str | Path | None = None,
    resume: bool = False,
    progress: Progress = None,
    handle_sigint: bool = True,
    backend: str | None = None,
    batch: int | None = None,
    **solver: Any,
) -> SweepTable:
    """Simulate ``model`` at every point of a grid and/or of seeded samples; one row per run.

    Parameters
    ----------
    model : Automaton or System
        From :func:`hybrid.load`.
    t_end : float, optional
        End time of every run; needed unless ``settings`` gives it.
    settings : Settings, optional
        The options of every run (:class:`hybrid.Settings`: ``t_end``, the
        solver's options, ``backend``), overridden by the keywords given;
        its ``dense`` is not read.
    grid : mapping or sequence of Axis, optional
        ``{name: values}``: every combination of the values is run, the first
        name slowest. A name is a parameter (``comp.name`` in a system),
        ``init.x`` (the initial value of ``x``) or ``input.u`` (a free input held
        at that value). A count instead of values (``{"init.x": 5}``) spreads that
        many values across the set the spec declares (ends included).
    vary : mapping or sequence of Axis or str, optional
        ``{name: (low, high)}``: the ranges ``samples`` are drawn from. An
        ``init.x`` or ``input.u`` with the range ``None`` (or a bare name in a
        sequence) takes the range its spec declares (``x: {initial: [lo, hi]}``,
        ``u: {range: [lo, hi]}``). Not given: every range the spec declares
        (:func:`~hybrid.campaigns.space.declared_ranges`) but the grid's names.
    samples : int, optional
        Draw this many points of the ``vary`` box from ``seed`` (each combined
        with every grid point).
    seed : int
        The seed of the samples: the same seed, the same points.
    sampler : {"lhs", "sobol", "random"}
        Latin hypercube, scrambled Sobol or uniform samples.
    points : sequence of mappings, optional
        Explicit points instead of a grid or samples, each giving a value to the same
        names (a design made elsewhere, a list of cases).
    parameters : mapping, optional
        Parameter overrides held in every run.
    inputs : mapping, optional
        Free inputs held by an expression of ``t`` in every run (``{"u": "sin(t)"}``).
    summaries : sequence of str
        ``KIND:NAME`` columns read off each run: ``max:x``, ``min:x``, ``last:x``,
        ``mean:x``, ``jumps:EDGE``, ``jump_t:K`` (:mod:`hybrid.campaigns.runs`).
    workers : int, optional
        Local worker processes (default: every core; 0: in this process).
    scheduler : dask.distributed.Client or str, optional
        Run on a Dask cluster instead (a client, or a scheduler's address).
    run_timeout : float, optional
        Seconds a run may take; a longer one is a row with cause ``timeout``.
    out : str or Path, optional
        Write the table there (``.csv`` or ``.parquet``); finished rows are kept
        in ``<out>.parts/`` meanwhile, so an interrupted campaign can resume.
    resume : bool
        Finish the campaign whose rows are in ``<out>.parts/``: run only the rest.
    progress : callable or bool, optional
        A :class:`hybrid.progress.Status` receiver (runs done, violations, failed), or
        True/False: a tqdm bar or none (default: a bar in Jupyter; docs/campaigns.md).
    handle_sigint : bool
        Turn Ctrl-C into a clean stop (rows kept, ``table.complete`` False).
    backend : str, optional
        ``"scipy"``, ``"compiled"`` or ``"auto"`` (:mod:`hybrid.campaigns.choosing`:
        compiled when it pays for its compile, else scipy, with a note saying which);
        default: that of ``settings``, ``"auto"`` when neither gives one.
    batch : int, optional
        Runs per batch sent to a worker (default: chosen from the counts).
    **solver
        ``rtol``, ``atol``, ``max_step``, ``method``, ``max_jumps``, ``dt``,
        ``zeno``, ``max_jumps_per_instant``, ``t_start``, as
        :func:`hybrid.simulate` takes them (overriding ``settings``).

    Returns
    -------
    SweepTable
        ``.rows`` (one dict per run, in run order), ``.to_pandas()``, ``.write(path)``.

    Examples
    --------
    >>> import hybrid
    >>> ball = hybrid.load("specs/bouncing_ball.yaml")
    >>> table = hybrid.sweep(ball, t_end=2.0, grid={"e": [0.5, 0.9]}, workers=0,
    ...                      summaries=["jump_t:1"])
    >>> [(row["e"], row["cause"], row["jumps"]) for row in table.rows]
    [(0.5, 't_end', 1), (0.9, 't_end', 1)]
    """
    expect_model(model, "sweep")
    seed = checked_seed(seed)
    if resume and out is None:
        raise UsageError("resume=True finishes the campaign writing out=: give out")
    chosen, solver = campaign_settings("sweep", settings, t_end, solver, keywords_of(sweep))
    t_end, (backend, announce) = chosen.t_end, campaign_backend(backend, chosen)
    if parameters:
        model = model.with_parameters(dict(parameters))
    system = as_system(model)  # the one model type below; the user's model goes to the workers
    if points is not None:
        if grid or vary or samples is not None:
            raise UsageError("give points, or a grid and/or samples, not both")
        names, listed = _listed(points)
        check_names(system, names, parameters or ())
        return _finish(system, pack(model), t_end, listed, names, solver, summaries, inputs, run_timeout,
                       backend, executor_for(workers, scheduler, batch), out, resume, progress,
                       handle_sigint, announce)  # fmt: skip
    on_grid = grid_axes(system, grid)
    if samples is not None:
        gridded = {a.name for a in on_grid}
        vary_axes = [a for a in ranges_axes(system, vary) if vary or a.name not in gridded]
        sampled: list[Point] | None = sample_points(vary_axes, samples, seed, sampler)
    else:
        if vary:
            raise UsageError("ranges to vary need a number of samples (--sample N)")
        vary_axes, sampled = [], None
    names = [a.name for a in on_grid] + [a.name for a in vary_axes]
    check_names(system, names, parameters or ())
    if not names:
        raise UsageError("nothing to vary: give a grid (--grid NAME=LO:HI:N) or samples")
    made = combine(grid_points(on_grid), sampled)
    executor = executor_for(workers, scheduler, batch)
    return _finish(system, pack(model), t_end, made, names, solver, summaries, inputs, run_timeout, backend,
                   executor, out, resume, progress, handle_sigint, announce)  # fmt: skip


def _finish(
    model: System,
    payload: Payload,
    t_end: float,
    points: Sequence[Point],
    names: Sequence[str],
    solver: Mapping[str, Any],
    summaries: Sequence[str],
    inputs: Mapping[str, str] | None,
    run_timeout: float | None,
    backend: str,
    executor: Executor,
    out: str | Path | None,
    resume: bool,
    progress: Progress,
    handle_sigint: bool,
    announce: bool = True,
) -> SweepTable:
    """Check the run settings, then run the campaign of ``points``."""
    if isinstance(summaries, str | bytes):  # "max:v" would be read letter by letter
        raise UsageError(f"summaries is a list of KIND:NAME, got the string {summaries!r}: "
                         f"write [{summaries!r}]")  # fmt: skip
    wanted = [Summary.parse(s) for s in summaries]
    for s in wanted:
        s.check(model)
    _check_inputs(model, names, inputs or {})
    if run_timeout is not None and not (run_timeout > 0):
        raise UsageError(f"run_timeout must be > 0 seconds, got {run_timeout}")
    _check_out(out)  # before auto's choice, which runs the first point
    plan, executor = settle(model, points, RunPlan(  # auto resolved; compiled: in process
        t_end=float(t_end),
        solver=dict(solver),
        summaries=tuple(wanted),
        inputs=tuple(sorted((inputs or {}).items())),
        timeout=run_timeout,
        backend=backend,
    ), executor, announce=announce)
    return run_campaign(
        model, payload, points, names, plan, executor, out, resume, progress, handle_sigint
    )


def _check_out(out: str | Path | None) -> None:
    """A results file the table can be written to: .csv or .parquet, in a folder that exists."""
    if out is None:
        return
    if Path(out).suffix.lower() not in (".csv", ".parquet"):
        raise UsageError(f"results go to a .csv or .parquet file, got '{out}'")
    writable_target(out)  # a directory, a missing folder: a CannotWrite


def run_campaign(
    model: System,
    payload: Payload,
    points: Sequence[Point],
    names: Sequence[str],
    plan: RunPlan,
    executor: Executor,
    out: str | Path | None,
    resume: bool,
    progress: Progress,
    handle_sigint: bool,
) -> SweepTable:
    """Run ``points`` of ``model`` (sent as ``payload``) on ``executor``; the table."""
    requirements = [w.name for w in watched_requirements(model)]
    columns = [
        "run",
        *names,
        *OUTCOME_COLUMNS,
        *requirement_columns(model),
        *(s.column for s in plan.summaries),
    ]
    _check_out(out)
    store = None
    if out is not None:
        fingerprint, parts = _fingerprint(payload.digest, plan, columns, points)
        store = ChunkStore(out, fingerprint, resume=resume, parts=parts)
    try:  # the results folder stays locked until the table is written
        rows: dict[int, dict[str, Any]] = dict(store.done) if store is not None else {}
        resumed = len(rows)
        jobs = [(i, "run", p) for i, p in enumerate(points) if i not in rows]
        tracker = Tracker("sweep", total=len(points), unit="runs", report=reporter(progress))
        counts = {"violations": 0, "failed": 0}
        for row in rows.values():
            _count(row, requirements, counts)

        def on_result(index: int, row: dict[str, Any]) -> None:
            rows[index] = row
            _count(row, requirements, counts)
            if store is not None:
                store.add(row)
            tracker.update(len(rows), **counts)

        def failed(job: tuple[int, str, Any], cause: str, message: str) -> dict[str, Any]:
            row = {"run": job[0], **job[2], **failed_row(model, plan, cause, message)}
            if cause == "error":  # the executor lost the run (a worker died): not the run's end
                row[LOST] = True
            return row

        with sigint_watch(handle_sigint) as interrupts, executor:
            if jobs:
                executor.start(payload, plan)
                stop = lambda: interrupts.requested  # noqa: E731
                limit = hard_limit(plan.timeout)
                complete = executor.run(jobs, on_result, failed, stop, limit)
                lost = [job for job in jobs if rows.get(job[0], {}).get(LOST)] if complete else []
                if lost:  # once more, on the workers that are left (or new ones)
                    complete = executor.run(lost, on_result, failed, stop, limit)
            else:
                complete = True
        lost_rows = sum(1 for row in rows.values() if row.get(LOST))
        if store is not None:
            store.flush()
        tracker.finish(len(rows), **counts)
        table = SweepTable(
            columns,
            list(rows.values()),
            names,
            requirements,
            complete=complete and not lost_rows,
            total=len(points),
            resumed=resumed,
            lost=lost_rows,
            backend=plan.backend,
        )
        if table.complete and out is not None and store is not None:
            table.write(out)
            store.remove()
        return table
    finally:
        if store is not None:
            store.close()


def executor_for(workers: int | None, scheduler: Any, batch: int | None = None) -> Executor:
    """The executor of the arguments: Dask with a scheduler, else local processes (0: here)."""
    if batch is not None and (isinstance(batch, bool) or not isinstance(batch, int) or batch < 1):
        raise UsageError(f"batch must be a whole number >= 1, got {batch!r}")
    if scheduler is not None:
        if workers is not None:
            raise UsageError("give workers (local processes) or a scheduler (Dask), not both")
        from hybrid.campaigns.cluster import DaskPool

        return DaskPool(scheduler, batch=batch)
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)):
        raise UsageError(f"workers must be a whole number, got {workers!r}")
    if workers is not None and workers < 0:
        raise UsageError(f"workers must be >= 0, got {workers}")
    if workers == 0:
        return InProcess()
    return LocalPool(workers or default_workers(), batch=batch)


def hard_limit(timeout: float | None) -> float | None:
    """How long a local worker may stay silent on one run before it is stopped."""
    return None if timeout is None else 1.5 * timeout + 2.0


def _listed(points: Sequence[Mapping[str, float]]) -> tuple[list[str], list[Point]]:
    """The names and points of an explicit list (every point gives the same names)."""
    if isinstance(points, Mapping | str | bytes) or not isinstance(points, Sequence) or not points:
        raise UsageError("points must be a non-empty list of {name: value} mappings")
    if not isinstance(points[0], Mapping):
        raise UsageError(f"point 0 must be a mapping {{name: value}}, got {points[0]!r}")
    names = [str(n) for n in points[0]]
    listed: list[Point] = []
    for k, point in enumerate(points):
        if not isinstance(point, Mapping) or sorted(map(str, point)) != sorted(names):
            raise UsageError(f"point {k} must give a value to each of {', '.join(names)}")
        try:
            values = {n: float(point[n]) for n in names}
        except (TypeError, ValueError):
            raise UsageError(f"point {k}: values must be numbers, got {dict(point)!r}") from None
        if not all(map(math.isfinite, values.values())):
            raise UsageError(f"point {k}: values must be finite numbers, got {values}")
        listed.append(values)
    return names, listed


def _check_inputs(
    model: System, names: Sequence[str], inputs: Mapping[str, str]
) -> None:
    declared = model.free_inputs
    for name in inputs:
        if name not in declared:
            raise UsageError(
                f"'{name}' is not a free input of {model.name} (inputs: {', '.join(declared) or 'none'})"
            )
        if f"{INPUT}{name}" in names:
            raise UsageError(f"input '{name}' is both varied and given")
    given = set(inputs) | {n[len(INPUT) :] for n in names if n.startswith(INPUT)}
    ranged = model.input_ranges()  # held at its nominal value when not given
    missing = [n for n in declared if n not in given and n not in ranged]
    if missing:
        raise UsageError(
            f"input '{missing[0]}' needs a value in every run: vary it (input.{missing[0]}) "
            f"or give it (--input {missing[0]}=EXPR)",
            at=model.input_position(missing[0]),
        )
    from hybrid.simulation.inputs import ExpressionInput

    for name, source in inputs.items():
        ExpressionInput(name, source)  # a bad expression is refused here, once


def _count(row: dict[str, Any], requirements: Sequence[str], counts: dict[str, int]) -> None:
    if row.get("cause") in FAILED:
        counts["failed"] += 1
    if any(row.get(f"{r}.holds") is False for r in requirements):
        counts["violations"] += 1


def _fingerprint(
    digest: str, plan: RunPlan, columns: Sequence[str], points: Sequence[Point]
) -> tuple[str, dict[str, str]]:
    """The campaign's fingerprint, and a digest of each of its parts (to say which differs
    when a resume is refused; the fingerprint is that of the campaigns before them)."""
    fields: dict[str, Any] = {
        "model": digest,
        "t_end": plan.t_end,
        "solver": sorted((k, repr(v)) for k, v in plan.solver.items()),
        "inputs": plan.inputs,
        "backend": plan.requested or plan.backend,
        "timeout": plan.timeout,  # a row ends 'timeout' or not by it
        "columns": list(columns),
        "points": [[(k, repr(v)) for k, v in p.items()] for p in points],
    }
    texts = {k: json.dumps(v) for k, v in fields.items()}  # each dumped once (the points!)
    text = "{" + ", ".join(f"{json.dumps(k)}: {v}" for k, v in texts.items()) + "}"  # json.dumps(fields)
    parts = {k: hashlib.sha256(v.encode()).hexdigest()[:16] for k, v in texts.items()}
    return hashlib.sha256(text.encode()).hexdigest(), parts
