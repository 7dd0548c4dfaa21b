"""``hybrid.simulate_many``: many runs of one model in one compiled, multithreaded loop.

Each row of a table gives one run its parameter values and initial values;
all runs share the model's structure (compiled once), the settings and the
initial location, and each has its own events and termination. Runs go to
numba's threads in chunks (:func:`hybrid.simulation.native.ensemble.run_many`);
a run whose trajectory outgrows its row is run again alone, with room. The
result, an :class:`Ensemble`, has a summary per run as arrays (cause, end
time, jumps) and builds each run's :class:`~hybrid.simulation.result.Run` on
access. Declared ``bounds:`` are watched as :func:`hybrid.simulate` watches
them, over every run's stored points: ``ensemble.out_of_bounds`` lists the runs
that left them, and one :class:`~hybrid.simulation.bounds.BoundsWarning` per
variable counts them and names the first (:func:`~hybrid.simulation.bounds.warn_ensemble`).
"""

from __future__ import annotations

import bisect
import numbers
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import replace
from typing import Any, overload

import numpy as np
from numpy.typing import NDArray

from hybrid.compose import System, as_system, expect_model
from hybrid.errors import OutOfRange, UsageError
from hybrid.keywords import named_keywords
from hybrid.model import Automaton
from hybrid.simulation.bounds import (
    BoundExcursion,
    bound_excursions,
    bound_limits,
    warn_ensemble,
)
from hybrid.simulation.interrupts import immediate, sigint_watch
from hybrid.simulation.native import buffers as b
from hybrid.simulation.native.assemble import run_from
from hybrid.simulation.native.cache import require_numba
from hybrid.simulation.native.engine import (
    CompiledNative,
    compiled_native,
    config,
    idle_threads_sleep_soon,
    run_arrays,
)
from hybrid.simulation.native.features import check_supported, refuse_requirements
from hybrid.simulation.native.interruptible import run_in_worker
from hybrid.simulation.result import Run
from hybrid.simulation.settings import Settings, merged
from hybrid.simulation.start import state_slot

__all__ = ["Ensemble", "simulate_many"]

CHUNK = 1024
"""Runs handed to the threads at once (their arrays are allocated together)."""

Table = Mapping[str, Sequence[float]] | Sequence[Mapping[str, float]] | Any


def _columns(table: Table, what: str) -> dict[str, NDArray[np.float64]]:
    """A table as columns: a mapping of columns, a list of rows, or a data frame."""
    if table is None:
        return {}
    if hasattr(table, "to_dict") and hasattr(table, "columns"):
        table = table.to_dict("list")
    if isinstance(table, Mapping):
        columns = {str(k): _column(what, str(k), v) for k, v in table.items()}
    elif isinstance(table, Sequence) and all(isinstance(row, Mapping) for row in table):
        keys = list(table[0]) if table else []
        for k, row in enumerate(table):
            if set(row) != set(keys):  # the same names, in any order
                raise UsageError(
                    f"{what}: every row must name the same columns: row {k} has "
                    f"{sorted(map(str, row))}, row 0 {sorted(map(str, keys))}"
                )
        columns = {str(k): _column(what, str(k), [row[k] for row in table]) for k in keys}
    else:
        raise UsageError(f"{what}: give a mapping of columns, a list of rows or a data frame")
    if not columns:  # given, but no rows: no run to make (None means the spec's values)
        raise UsageError(f"{what}: the table is empty (no columns, no rows); leave it out "
                         "for one run with the spec's values")  # fmt: skip
    lengths = {name: len(v) for name, v in columns.items()}
    if len(set(lengths.values())) > 1:
        shown = ", ".join(f"{name}: {size}" for name, size in lengths.items())
        raise UsageError(f"{what}: columns of different lengths ({shown})")
    return columns


def _column(what: str, name: str, values: object) -> NDArray[np.float64]:
    """One column of a table: a non-empty list of finite numbers (a UsageError naming it if not)."""
    if isinstance(values, str | bytes):
        raise UsageError(f"{what}: column '{name}' must be a list of numbers, got {values!r}")
    try:
        column = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise UsageError(f"{what}: column '{name}' must be numbers, got {values!r}"[:200]) from None
    if column.ndim != 1:
        raise UsageError(f"{what}: column '{name}' must be one list of numbers, got shape {column.shape}")
    if column.size == 0:
        raise UsageError(f"{what}: column '{name}' is empty")
    bad = np.flatnonzero(~np.isfinite(column))
    if bad.size:
        k = int(bad[0])
        raise UsageError(f"{what}: column '{name}' must be finite numbers, got {column[k]} in row {k}")
    return column


def _slot(system: System, compiled: CompiledNative, key: str) -> int:
    """The parameter slot a user's name (``name`` or ``comp.name``) refers to."""
    system.with_parameters({key: 0.0})  # the reference's errors for unknown or ambiguous names
    if system.single or "." not in key:
        owners = [i for i, c in enumerate(system.components) if key in c.automaton.parameters]
        return compiled.native.slots[(owners[0], key)]
    comp, name = key.split(".", 1)
    index = [c.name for c in system.components].index(comp)
    return compiled.native.slots[(index, name)]


class Ensemble(Sequence[Run]):
    """The runs of :func:`simulate_many`, in table order.

    ``ensemble[i]`` is run ``i`` as a :class:`~hybrid.simulation.result.Run`
    (built on access); ``causes``, ``t``, ``j`` and ``n_jumps`` summarise every
    run as arrays; ``parameters`` and ``initial`` are the table's columns;
    ``out_of_bounds`` maps the number of each run that left its declared
    ``bounds:`` to where it did (its ``run.out_of_bounds``), and is empty when
    every run stayed within them.
    """

    def __init__(self, model: System, compiled: CompiledNative, settings: Settings,
                 params: NDArray[np.float64], parameters: dict[str, NDArray[np.float64]],
                 initial: dict[str, NDArray[np.float64]]) -> None:  # fmt: skip
        self.model, self.compiled, self.settings = model, compiled, settings
        self.params = params
        self.parameters, self.initial = parameters, initial
        self._chunks: list[b.RunArrays] = []
        self._firsts: list[int] = []
        """The number of each chunk's first run (chunks in order, each a run per row)."""
        self._n = 0
        self._alone: dict[int, Run] = {}
        self.out_of_bounds: dict[int, tuple[BoundExcursion, ...]] = {}

    def _add(self, chunk: b.RunArrays, rows: int) -> None:
        self._chunks.append(chunk)
        self._firsts.append(self._n)
        self._n += rows

    def _where(self, i: int) -> tuple[int, int]:
        """The chunk of run ``i`` and its row there."""
        c = bisect.bisect_right(self._firsts, i) - 1
        return c, i - self._firsts[c]

    def _summary(self, slot: int, floats: bool) -> NDArray[Any]:
        parts = [(chunk.of[:, slot] if floats else chunk.oi[:, slot]) for chunk in self._chunks]
        values: NDArray[Any] = np.concatenate(parts) if parts else np.zeros(0)
        values = values.astype(float if floats else np.int64)  # a copy, in the summary's type
        for i, run in self._alone.items():
            term = run.termination
            values[i] = (
                {b.F_T: term.t, b.I_J: term.j, b.I_JUMPS: len(run.jumps)}[slot]
                if slot != b.I_CAUSE
                else b.CAUSE_CODES.index(term.cause)
            )
        return values

    @property
    def causes(self) -> NDArray[np.str_]:
        """The termination cause of each run."""
        names: NDArray[np.str_] = np.array(b.CAUSE_CODES, dtype=np.str_)
        causes: NDArray[np.str_] = names[self._summary(b.I_CAUSE, False)]
        return causes

    @property
    def t(self) -> NDArray[np.float64]:
        """The time each run ended."""
        return self._summary(b.F_T, True)

    @property
    def j(self) -> NDArray[np.int64]:
        """The hybrid time (jumps taken) at each run's end."""
        return self._summary(b.I_J, False)

    @property
    def n_jumps(self) -> NDArray[np.int64]:
        """The number of jumps of each run."""
        return self._summary(b.I_JUMPS, False)

    def __len__(self) -> int:
        return self._n

    def __repr__(self) -> str:
        """How many runs of which model, how they ended, and how many left their bounds.

        Examples
        --------
        >>> import hybrid
        >>> ball = hybrid.load("specs/bouncing_ball.yaml")
        >>> hybrid.simulate_many(ball, parameters={"e": [0.5, 0.8]}, t_end=2.0)
        <Ensemble: 2 runs of bouncing_ball to t_end=2; causes: t_end 2; out of bounds: 0>
        """
        causes, counts = np.unique(self.causes, return_counts=True)
        ended = ", ".join(f"{c} {n}" for c, n in zip(causes.tolist(), counts.tolist(), strict=True))
        return (f"<Ensemble: {self._n} runs of {self.model.name} to t_end={self.settings.t_end:g}; "
                f"causes: {ended or 'none'}; out of bounds: {len(self.out_of_bounds)}>")  # fmt: skip

    @overload
    def __getitem__(self, i: int) -> Run: ...
    @overload
    def __getitem__(self, i: slice) -> list[Run]: ...
    def __getitem__(self, i: int | slice) -> Run | list[Run]:
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        i = self._index(i)
        if i in self._alone:
            return self._alone[i]
        c, r = self._where(i)
        arrays = self._chunks[c].row(r)
        model = self.model
        if int(arrays.oi[b.I_DETAIL]) in (b.D_EVAL, b.D_FLOW, b.D_FLOW_START):
            model = self.model_of(i)  # the message evaluates the model: with this run's values
        compiled = self.compiled
        run = run_from(compiled.native, compiled.layout, model, self.settings, arrays)
        run.out_of_bounds = self.out_of_bounds.get(i, ())
        return run

    def __iter__(self) -> Iterator[Run]:
        return (self[k] for k in range(len(self)))

    def _index(self, i: object, runs: int | None = None) -> int:
        """Run ``i`` of ``runs`` (default: those run so far) as a position (negative from the
        end), or an :class:`OutOfRange`."""
        runs = self._n if runs is None else runs
        if isinstance(i, bool) or not isinstance(i, numbers.Integral):
            raise OutOfRange(f"runs are indexed by whole numbers or slices, got {i!r}")
        k = int(i) + (runs if int(i) < 0 else 0)
        if not 0 <= k < runs:
            raise OutOfRange(f"run {int(i)} of an ensemble of {runs} runs")
        return k

    def model_of(self, i: int) -> System:
        """The model with run ``i``'s parameter values."""
        i = self._index(i, self.params.shape[0])  # every row's, also while the runs go on
        names = self.compiled.native.slot_names  # the held inputs' slots after them
        values = self.params[i].tolist()[: len(names)]
        return self.model.with_parameters(dict(zip(names, values, strict=True)))


@named_keywords
def simulate_many(
    model: Automaton | System,
    t_end: float | None = None,
    *,
    settings: Settings | None = None,
    parameters: Table = None,
    initial: Table = None,
    max_jumps: int | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    max_step: float | None = None,
    t_start: float | None = None,
    dt: float | None = None,
    zeno: bool | None = None,
    max_jumps_per_instant: int | None = None,
    threads: int | None = None,
    handle_sigint: bool = True,
) -> Ensemble:
    """Simulate ``model`` once per row of a table, compiled, on several threads.

    Parameters
    ----------
    model : Automaton or System
        From :func:`hybrid.load`.
    t_end : float, optional
        End time of every run; needed unless ``settings`` gives it.
    settings : Settings, optional
        The options of every run (:class:`hybrid.Settings`), overridden by the
        keywords given. Its ``backend`` and ``dense`` are not read (the runs are
        compiled and keep no interpolants) and its ``method`` must be ``RK45``.
    parameters : table, optional
        One row per run: a mapping of columns (``{"e": [0.7, 0.8]}``), a list
        of rows (``[{"e": 0.7}, {"e": 0.8}]``) or a data frame. Columns name
        parameters (``comp.name`` in a system) or, as ``init.x``, initial values.
    initial : table, optional
        Initial values of state variables, one row per run (same forms). A table
        given empty is refused (left out, it is one run with the spec's values).
    max_jumps, rtol, atol, max_step, t_start, dt, zeno, max_jumps_per_instant
        As for :func:`hybrid.simulate`, the same for every run.
    threads : int, optional
        Threads to use for this call (default: numba's, all cores; at most those).
    handle_sigint : bool
        Turn Ctrl-C into a clean end (cause ``interrupted``) of every run.

    Returns
    -------
    Ensemble
        One :class:`~hybrid.simulation.result.Run` per row (``ensemble[i]``),
        and per-run summaries (``causes``, ``t``, ``j``, ``n_jumps``).
        ``out_of_bounds`` maps each run that left its declared ``bounds:`` to
        where it did; each variable left in any run gives one
        :class:`~hybrid.simulation.bounds.BoundsWarning` with the number of such
        runs and the first one's ``t`` and ``j``.

    Examples
    --------
    >>> import hybrid
    >>> ball = hybrid.load("specs/bouncing_ball.yaml")
    >>> runs = hybrid.simulate_many(ball, t_end=2.0, parameters={"init.h": [5.0, 10.0, 20.0]})
    >>> runs.n_jumps.tolist(), [round(run.jumps[0].t, 6) for run in runs if run.jumps]
    ([1, 1, 0], [1.009638, 1.427843])
    """
    expect_model(model, "simulate_many")
    settings = merged(
        settings,
        t_end,
        t_start=t_start,
        max_jumps=max_jumps,
        rtol=rtol,
        atol=atol,
        max_step=max_step,
        dt=dt,
        zeno=zeno,
        max_jumps_per_instant=max_jumps_per_instant,
    )
    settings = replace(settings, backend="compiled", dense=False)
    table = _columns(parameters, "parameters")
    starts = {k[5:]: v for k, v in table.items() if k.startswith("init.")}
    params_table = {k: v for k, v in table.items() if not k.startswith("init.")}
    for name, column in _columns(initial, "initial").items():
        if name in starts:  # the last one used to win silently
            raise UsageError(
                f"initial value of '{name}' is given twice: as parameters' init.{name} and "
                "in initial; give it once"
            )
        starts[name] = column
    sizes = {len(v) for v in (*params_table.values(), *starts.values())}
    if len(sizes) > 1:
        raise UsageError(f"parameters and initial have different numbers of rows {sorted(sizes)}")
    n = sizes.pop() if sizes else 1
    model = as_system(model)  # the one model type below this entry point
    refuse_requirements(model)
    require_numba()
    check_supported(settings, None)  # a method other than RK45, given in settings
    with immediate("compiling the model (nothing was run)"):
        compiled = compiled_native(model)
    native = compiled.native
    params = np.tile(np.array(native.parameter_vector(model), dtype=float), (n, 1))
    for key, column in params_table.items():
        params[:, _slot(model, compiled, key)] = column
    x0s = np.tile(np.array(model.initial_vector(), dtype=float), (n, 1))
    for name, column in starts.items():
        x0s[:, state_slot(native.state_names, name)] = column
    ensemble = Ensemble(model, compiled, settings, params, params_table, starts)
    if threads is not None and (isinstance(threads, bool) or not isinstance(threads, numbers.Integral)
                                or threads < 1):  # fmt: skip
        raise UsageError(f"threads must be a whole number >= 1, got {threads!r}")
    restore: int | None = None
    if threads is not None:  # this call's, not the process's: put back after
        import numba

        idle_threads_sleep_soon()  # numba starts its threads when asked their number
        most = int(getattr(numba.config, "NUMBA_NUM_THREADS", 1))
        restore = numba.get_num_threads()
        numba.set_num_threads(max(1, min(int(threads), most)))
    try:
        return _simulate_rows(ensemble, compiled, model, settings, params, x0s, n,
                              handle_sigint)  # fmt: skip
    finally:
        if restore is not None:
            numba.set_num_threads(restore)  # imported above, where restore was set


def _simulate_rows(ensemble: Ensemble, compiled: CompiledNative, model: System,
                   settings: Settings, params: NDArray[np.float64], x0s: NDArray[np.float64],
                   n: int, handle_sigint: bool) -> Ensemble:  # fmt: skip
    """The runs of :func:`simulate_many` and the ensemble's bounds (its threads set)."""
    cfg = config(settings)
    m0 = compiled.initial_mode(model)
    flag = np.zeros(1, dtype=np.int64)  # after a Ctrl-C, the remaining runs end at once
    # A Ctrl-C between the compiled calls (while a chunk's rows are copied, a rerun is
    # assembled) is counted by the watch and sets the flag at the next call: it never
    # raises there, and every later run ends at once.
    with sigint_watch(handle_sigint):  # run_here sees its requests at each call
        _run_all(ensemble, compiled, model, settings, params, x0s, m0, cfg, flag, handle_sigint)
    alone = {i: run.out_of_bounds for i, run in ensemble._alone.items() if run.out_of_bounds}
    ensemble.out_of_bounds = dict(sorted({**ensemble.out_of_bounds, **alone}.items()))
    warn_ensemble(ensemble.out_of_bounds, n)
    return ensemble


def _run_all(ensemble: Ensemble, compiled: CompiledNative, model: System, settings: Settings,
             params: NDArray[np.float64], x0s: NDArray[np.float64], m0: int, cfg: Any,
             flag: NDArray[np.int64], handle_sigint: bool) -> None:  # fmt: skip
    """Every run of :func:`simulate_many`, chunk by chunk, into ``ensemble``."""
    n = params.shape[0]
    # sizes the rows; a Ctrl-C while it runs sets the flag (every run then ends at once)
    pilot = run_arrays(compiled, params[0], x0s[0], m0, settings, handle_sigint, flag=flag)
    points = 2 * int(pilot.oi[b.I_POINTS]) + 16
    jumps = 2 * int(pilot.oi[b.I_JUMPS]) + 4
    room: b.RunArrays | None = None  # the chunks' room, one allocation (its memory touched once)
    for lo in range(0, n, CHUNK):
        hi = min(n, lo + CHUNK)
        if room is None or room.pts.shape[1] != points or room.jps.shape[1] != jumps:
            room = compiled.buffers(points, jumps, 1, runs=min(n, CHUNK))
        arrays = _rows(room, slice(hi - lo))
        done = 0  # rows of this chunk already run
        if lo == 0:  # row 0 is the sizing run: its arrays are copied, it is not run again
            _put_first_row(arrays, pilot)
            done = 1
        rest = _rows(arrays, slice(done, None))

        def call(flag: NDArray[np.int64], rest: b.RunArrays = rest, start: int = lo + done,
                 hi: int = hi) -> None:  # fmt: skip
            compiled.run_many(params[start:hi], x0s[start:hi], settings.t_start, m0, cfg, rest,
                              flag)  # fmt: skip

        if hi - lo > done:
            run_in_worker(call, handle_sigint, flag)
        overflowed = np.flatnonzero(arrays.oi[:, b.I_OVERFLOW])
        for r in overflowed.tolist():
            one = _alone(ensemble, settings, lo + r, x0s[lo + r], m0, cfg, handle_sigint, flag)
            ensemble._alone[lo + r] = one
            one.out_of_bounds = _run_excursions(model, settings, one.state_names, one.t,
                                                one.j, one.states)  # fmt: skip
        _chunk_excursions(ensemble, arrays, lo)
        ensemble._add(_kept(arrays), hi - lo)
        if overflowed.size:  # give later chunks the room the longest run needed
            longest = max(len(ensemble._alone[lo + r]) for r in overflowed.tolist())
            most = max(len(ensemble._alone[lo + r].jumps) for r in overflowed.tolist())
            points, jumps = max(points, 2 * longest), max(jumps, 2 * most + 4)


def _put_first_row(arrays: b.RunArrays, run: b.RunArrays) -> None:
    """Row 0 of a chunk's ``arrays`` made what the single ``run`` recorded (it fits: the
    rows were sized from it)."""
    p, j, k = (int(run.oi[slot]) for slot in (b.I_POINTS, b.I_JUMPS, b.I_STORED_STEPS))
    arrays.pts[0, :p] = run.pts[:p]
    arrays.jps[0, :j] = run.jps[:j]
    arrays.sts[0, :k] = run.sts[:k]
    for name in ("oi", "of", "wf", "wi"):
        getattr(arrays, name)[0] = getattr(run, name)


def _rows(arrays: b.RunArrays, part: slice) -> b.RunArrays:
    """The rows ``part`` of a chunk's arrays (views)."""
    return b.RunArrays(arrays.pts[part], arrays.jps[part], arrays.sts[part], arrays.oi[part],
                       arrays.of[part], arrays.wf[part], arrays.wi[part])  # fmt: skip


def _kept(arrays: b.RunArrays) -> b.RunArrays:
    """What an ensemble keeps of a chunk: copies of the rows its runs filled, no scratch.

    The room of each row is twice the pilot run's; a run that outgrew it is
    run alone (its row is never read), so the points, jumps and steps of the
    others fit in as many as the most of them recorded.
    """
    fitted = arrays.oi[arrays.oi[:, b.I_OVERFLOW] == 0]
    p, j, s = (int(fitted[:, slot].max()) if fitted.size else 0
               for slot in (b.I_POINTS, b.I_JUMPS, b.I_STORED_STEPS))  # fmt: skip
    rows = arrays.oi.shape[0]
    return b.RunArrays(arrays.pts[:, :p].copy(), arrays.jps[:, :j].copy(),
                       arrays.sts[:, :s].copy(), arrays.oi.copy(), arrays.of.copy(),
                       np.zeros((rows, 0)), np.zeros((rows, 0), dtype=np.int64))  # fmt: skip


def _run_excursions(model: System, settings: Settings, names: Sequence[str],
                    t: NDArray[np.float64], j: NDArray[np.int64],
                    states: NDArray[np.float64]) -> tuple[BoundExcursion, ...]:  # fmt: skip
    """Where one run's stored points leave the declared bounds (as :func:`hybrid.simulate`)."""
    return bound_excursions(model.states, names, t, j, states, rtol=settings.rtol,
                            atol=settings.atol)  # fmt: skip


def _chunk_excursions(ensemble: Ensemble, arrays: b.RunArrays, lo: int) -> None:
    """Record the runs of a chunk (from run ``lo``) whose stored points leave the bounds.

    Each run's loop kept the smallest and largest value of each state over its
    stored points (NaN left out) in its scratch, as a single run's does
    (:func:`~hybrid.simulation.bounds.bound_excursions` reads them the same way):
    only the runs whose extremes pass a bound are read, point by point.
    """
    settings, names = ensemble.settings, ensemble.compiled.layout.state_names
    limits = bound_limits(ensemble.model.states, names, settings.rtol, settings.atol)
    if not limits:
        return
    d = len(names)
    at = int(arrays.wi[0, b.W_EXTREMES])  # the same layout in every row
    beyond = np.zeros(arrays.oi.shape[0], dtype=bool)
    for k, _, low, high in limits:
        beyond |= (arrays.wf[:, at + k] < low) | (arrays.wf[:, at + d + k] > high)
    beyond &= arrays.oi[:, b.I_OVERFLOW] == 0  # overflowed: run alone, checked there
    for r in np.flatnonzero(beyond).tolist():
        pts = arrays.pts[r, : int(arrays.oi[r, b.I_POINTS])]
        found = _run_excursions(ensemble.model, settings, names, pts[:, b.P_T],
                                pts[:, b.P_J].astype(np.int64), pts[:, b.P_X : b.P_X + d])  # fmt: skip
        if found:
            ensemble.out_of_bounds[lo + r] = found


def _alone(ensemble: Ensemble, settings: Settings, i: int, x0: NDArray[np.float64], m0: int,
           cfg: Any, handle_sigint: bool, flag: NDArray[np.int64]) -> Run:  # fmt: skip
    """Run ``i`` on its own (it outgrew its row in the chunk), with the ensemble's compiled
    model and its row's values, reading the ensemble's interrupt flag: after a Ctrl-C it
    ends at once as ``interrupted``, as every run does (nothing is compiled again)."""
    compiled = ensemble.compiled
    arrays = run_arrays(compiled, ensemble.params[i], x0, m0, settings, handle_sigint, cfg=cfg,
                        flag=flag)  # fmt: skip
    return run_from(compiled.native, compiled.layout, ensemble.model_of(i), settings, arrays)
