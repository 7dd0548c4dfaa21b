"""``simulate``: the public entry to the simulator.

It validates the settings (:class:`~hybrid.simulation.settings.Settings`) and
the overrides (finite numbers, callable inputs), applies the overrides to the
model, compiles it (once per model and thread,
:class:`~hybrid.simulation.compiled.CompiledModel`) and runs the
:class:`~hybrid.simulation.loop.EventLoop` with Ctrl-C turned into a clean end
(:mod:`~hybrid.simulation.interrupts`) and progress reported through
:mod:`hybrid.progress`.
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Mapping
from dataclasses import replace
from types import ModuleType
from typing import Any

import numpy as np

from hybrid.compose import System, as_system
from hybrid.errors import UsageError
from hybrid.model import Automaton
from hybrid.progress import Reporter, Tracker
from hybrid.simulation.apart import independent_groups, simulate_apart
from hybrid.simulation.bounds import bound_excursions, warn_excursions
from hybrid.simulation.compiled import CompiledModel
from hybrid.simulation.interrupts import sigint_watch
from hybrid.simulation.loop import EventLoop
from hybrid.simulation.monitor import (
    Monitor,
    cut_results,
    join_groups,
    margin_table,
    with_group_requirements,
)
from hybrid.simulation.result import Run
from hybrid.simulation.settings import Settings, finite_number, merged_values
from hybrid.simulation.start import describe_start, run_inputs

__all__ = ["simulate"]

_OPTIONS = ("t_start", "max_jumps", "rtol", "atol", "max_step", "method", "dt", "dense", "zeno",
            "max_jumps_per_instant", "backend")  # fmt: skip
"""The options :func:`simulate` passes to :func:`~hybrid.simulation.settings.merged_values`."""


def simulate(
    model: Automaton | System,
    t_end: float | None = None,
    *,
    settings: Settings | None = None,
    max_jumps: int | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    max_step: float | None = None,
    method: str | None = None,
    parameters: Mapping[str, float] | None = None,
    initial: Mapping[str, float] | None = None,
    initial_location: str | None = None,
    inputs: Mapping[str, Callable[[float], float]] | None = None,
    t_start: float | None = None,
    dt: float | None = None,
    zeno: bool | None = None,
    max_jumps_per_instant: int | None = None,
    handle_sigint: bool = True,
    dense: bool | None = None,
    progress: Reporter | None = None,
    backend: str | None = None,
) -> Run:
    """Simulate ``model`` from ``t_start`` to ``t_end``.

    Parameters
    ----------
    model : Automaton or System
        From :func:`hybrid.load`.
    t_end : float, optional
        End time; the run ends there with cause ``t_end`` unless it ends before.
        Needed unless ``settings`` gives it (then it overrides that one).
    settings : Settings, optional
        The options of the run as one object (:class:`hybrid.Settings`);
        every option below given as a keyword overrides its field. Not given:
        the defaults.
    max_jumps : int
        Stop with cause ``max_jumps`` after this many jumps (default 10 000).
    rtol, atol, max_step, method
        Passed to :func:`scipy.integrate.solve_ivp` (defaults 1e-6, 1e-9, not
        limited, ``"RK45"``). Lower ``max_step`` so that a guard that is true
        only briefly is not stepped over.
    parameters : mapping, optional
        Parameter overrides (``comp.name`` in a system), finite numbers.
    initial : mapping, optional
        Initial values of some state variables, finite numbers.
    initial_location : str, optional
        Start location of an automaton.
    inputs : mapping, optional
        Free inputs (of an automaton, or those of a system no component
        provides): name to a function of ``t`` returning a number (see
        :mod:`hybrid.simulation.inputs` for expressions and time series). A
        free input with a ``range`` given none is held at its nominal value.
    t_start : float
        Start time (default 0).
    dt : float, optional
        Store points on a uniform grid (jump points are always stored).
    zeno : bool
        Detect geometric accumulation of jumps (cause ``zeno``; default on).
    max_jumps_per_instant : int
        Jumps allowed at one instant before the run ends as ``zeno`` (default 1000).
    handle_sigint : bool
        Turn Ctrl-C into a clean end (cause ``interrupted``), keeping the output.
    dense : bool
        Keep each segment's interpolant in ``run.segments`` (smooth plots).
    progress : callable, optional
        Called with a :class:`hybrid.progress.Status` (simulated time of
        ``t_end``, ``jumps`` and ``points`` so far, rate, time left) at most
        five times a second while the run goes on, and once when it ends.
    backend : str
        ``"scipy"`` (the reference engine, default), ``"compiled"`` (the same
        semantics compiled to machine code with numba: the ``fast`` extra;
        docs/backends.md) or ``"auto"``: compiled only when the model's compiled
        code is loaded in this process already (a loop of runs after its first),
        else scipy; ``run.settings["backend"]`` says which ran.

    The options (``t_end`` to ``backend`` but ``parameters``, ``initial``,
    ``initial_location``, ``inputs``, ``handle_sigint`` and ``progress``) are
    the fields of :class:`hybrid.Settings`; one given as ``None`` is not given.

    Returns
    -------
    Run
        The trajectory, jumps and termination (``run.termination.cause``).
        ``run.settings["start"]`` says where the run started and why: the
        initial location and state, the inputs held at their nominal values,
        and ``notes`` when a point of a set was chosen (a nominal value, a
        midpoint, the first of several initial locations).
        ``run.out_of_bounds`` says where a state variable first left its declared
        ``bounds:``; each such variable also gives one
        :class:`~hybrid.simulation.bounds.BoundsWarning` (``hybrid.BoundsWarning``).

    Examples
    --------
    >>> import hybrid
    >>> ball = hybrid.load("specs/bouncing_ball.yaml")
    >>> run = hybrid.simulate(ball, t_end=3.0, rtol=1e-10, atol=1e-12)
    >>> round(run.jumps[0].t, 9)  # sqrt(2 * 10 / 9.81)
    1.427843123
    >>> same = hybrid.simulate(ball, settings=hybrid.Settings(t_end=3.0, rtol=1e-10, atol=1e-12))
    >>> same.jumps[0].t == run.jumps[0].t
    True
    """
    settings = merged_values(
        settings,
        t_end,
        _OPTIONS,
        (t_start, max_jumps, rtol, atol, max_step, method, dt, dense, zeno,
         max_jumps_per_instant, backend),
    )  # fmt: skip
    t_start, t_end = settings.t_start, settings.t_end
    parameters = _numbers("parameter", parameters) if parameters else None
    if settings.backend != "compiled" and settings.backend != "scipy":  # not given, or auto
        settings = replace(settings, backend=_one_run_backend(model, settings, inputs))
    initial = _numbers("initial value of", initial) if initial else None
    if inputs is not None:
        _check_inputs(inputs)
    model = model.with_parameters(parameters) if parameters else model
    if isinstance(model, System) and initial_location:
        raise UsageError("initial_location applies to an automaton; set it per component")
    start = describe_start(model, inputs, initial, initial_location, t_start)
    if isinstance(model, Automaton) and (initial or initial_location):
        model = model.with_initial(initial_location, initial)
    model = as_system(model)  # the one model type below this entry point
    tracker = None
    if progress is not None:
        tracker = Tracker("simulate", total=t_end, unit="s", start=t_start, report=progress)
    progressed = None if tracker is None else _updater(tracker)
    if settings.backend == "compiled":
        run = _simulate_compiled(model, settings, initial, inputs, handle_sigint, progressed)
    else:
        run = _simulate_scipy(model, settings, initial, inputs, handle_sigint, progressed)
    run.settings["start"] = start
    run.out_of_bounds = bound_excursions(
        model.states,
        run.state_names,
        run.t,
        run.j,
        run.states,
        rtol=settings.rtol,
        atol=settings.atol,
    )
    if run.out_of_bounds:
        warn_excursions(run.out_of_bounds)
    if tracker is not None:
        tracker.finish(run.termination.t, jumps=len(run.jumps), points=len(run))
    return run


def _simulate_scipy(
    model: System,
    settings: Settings,
    initial: Mapping[str, float] | None,
    inputs: Mapping[str, Callable[[float], float]] | None,
    handle_sigint: bool,
    progress: Callable[[float, int, int], None] | None,
) -> Run:
    """A run on the scipy backend: the event loop, or components apart when independent."""
    compiled = _compiled(model, inputs)
    x0 = np.array(_initial_vector(model, compiled, initial), dtype=float)
    # a solution that blows up overflows inside the solver's linear algebra; the run
    # sees the non-finite state and ends with a message, so numpy's warnings are noise
    with sigint_watch(handle_sigint) as interrupts, np.errstate(all="ignore"):
        if len(groups := _groups(model)) > 1:
            # components that share no label and read no signal of each other: simulated
            # apart and merged in hybrid time, never as a product
            parts: list[tuple[Run, CompiledModel]] = []
            whole = model

            def run_group(
                sub: System, start: np.ndarray, how: Settings
            ) -> tuple[Run, CompiledModel]:
                mine = {k: v for k, v in (inputs or {}).items() if k in sub.free_inputs}
                part = _compiled(with_group_requirements(whole, sub), mine)
                loop = EventLoop(part, how, interrupts, None)
                loop.recorder.monitor = _monitor(part, how)
                parts.append((loop.recorder.run(sub.name, loop.run(how.t_start, start)), part))
                return parts[-1]

            run = simulate_apart(model, groups, x0, settings, run_group)
            run.requirements = cut_results(parts, run, settings)
        else:
            loop = EventLoop(compiled, settings, interrupts, progress)
            loop.recorder.monitor = _monitor(compiled, settings)
            run = loop.recorder.run(model.name, loop.run(settings.t_start, x0))
    return run


def _simulate_compiled(
    model: System,
    settings: Settings,
    initial: Mapping[str, float] | None,
    inputs: Mapping[str, Callable[[float], float]] | None,
    handle_sigint: bool,
    progress: Callable[[float, int, int], None] | None,
) -> Run:
    """A run on the compiled backend; requirements monitored over its steps afterwards."""
    native = _NATIVE[0] if _NATIVE else _native_engine()
    # the scipy backend's compiled form only for a model with requirements (its monitor):
    # a run without any pays nothing for them
    if not _has_requirements(model):
        only: Run = native.simulate_compiled(
            model, settings, initial=initial, inputs=inputs, handle_sigint=handle_sigint,
            progress=progress,
        )  # fmt: skip
        return only
    reference = _compiled(model, None)
    monitor = _monitor(reference, settings)
    kept = settings if monitor is None or settings.dense else replace(settings, dense=True)
    run: Run = native.simulate_compiled(
        model, kept, initial=initial, inputs=inputs, handle_sigint=handle_sigint, progress=progress
    )
    if monitor is not None:  # shown every step's curve
        from hybrid.simulation.native.monitoring import replay

        run.requirements = replay(monitor, reference, native.compiled_native(model).layout, run)
    if kept is not settings:
        run.segments = []
        run.settings["dense"] = False
    return run


_NATIVE: list[ModuleType] = []
""":mod:`hybrid.simulation.native.engine` once imported (an import statement costs a short run's
tenth)."""


def _native_engine() -> ModuleType:
    """:mod:`hybrid.simulation.native.engine`, imported on the first compiled run."""
    from hybrid.simulation.native import engine

    _NATIVE[:] = [engine]
    return engine


def _one_run_backend(
    model: Automaton | System, settings: Settings, inputs: Mapping[str, Any] | None
) -> str:
    """The backend of one run when it is not given (scipy) or ``auto`` (compiled only if
    nothing is to be loaded or compiled first: :func:`hybrid.simulation.native.choice.choose`)."""
    if settings.backend is None:
        return "scipy"
    from hybrid.simulation.native.choice import choose

    return choose(model, 1, method=settings.method, inputs=bool(inputs)).backend


def _has_requirements(model: System) -> bool:
    """Whether the system or a component declares a requirement (the last model without: kept)."""
    if _PLAIN[0] is model:
        return False
    if model.requirements or any(c.automaton.requirements for c in model.components):
        return True
    _PLAIN[0] = model  # frozen: it never gains one
    return False


_PLAIN: list[System | None] = [None]
"""The last model :func:`_has_requirements` found without requirements."""


def _groups(model: System) -> list[tuple[int, ...]]:
    """The groups simulated apart: independent components, joined where a requirement spans them."""
    groups = independent_groups(model)
    return join_groups(model, groups) if len(groups) > 1 and model.requirements else groups


def _monitor(compiled: CompiledModel, settings: Settings) -> Monitor | None:
    """A requirement monitor for one run of ``compiled`` (None if it has no requirement)."""
    table = margin_table(compiled)
    return None if table is None else Monitor(table, settings)


def _updater(tracker: Tracker | None) -> Callable[[float, int, int], None] | None:
    if tracker is None:
        return None
    update = tracker.update

    def progress(t: float, jumps: int, points: int) -> None:
        update(t, jumps=jumps, points=points)

    return progress


def _numbers(what: str, values: Mapping[str, float] | None) -> dict[str, float] | None:
    """``values`` with each checked to be a finite number (a :class:`UsageError` if not)."""
    if not values:
        return None
    if not isinstance(values, Mapping):
        raise UsageError(f"{what} overrides must be a mapping of names to numbers, got {values!r}")
    return {str(k): finite_number(f"{what} '{k}'", v) for k, v in values.items()}


def _check_inputs(inputs: Mapping[str, Callable[[float], float]] | None) -> None:
    if inputs is None:
        return
    if not isinstance(inputs, Mapping):
        raise UsageError(
            f"inputs must be a mapping of input names to functions of t, got {inputs!r}"
        )
    for name, fn in inputs.items():
        if not callable(fn):
            raise UsageError(
                f"input '{name}' must be a function of t (e.g. lambda t: 0.5), got {fn!r}"
            )


_CACHE = threading.local()
_CACHE_SIZE = 8


def _compiled(
    model: System, inputs: Mapping[str, Callable[[float], float]] | None
) -> CompiledModel:
    """The compiled model of ``model``, reused across runs of the same model in a thread.

    Compiling a mode's functions costs far more than a jump; a parameter sweep or
    a benchmark simulates one model many times. Models given external inputs are
    compiled afresh (the inputs are bound into the code); free inputs given none
    are held at their nominal values (:func:`run_inputs`).
    """
    if inputs:
        return CompiledModel(model, run_inputs(model, inputs))
    cache: dict[int, tuple[Automaton | System, CompiledModel]] = (
        getattr(_CACHE, "models", None) or {}
    )
    _CACHE.models = cache
    hit = cache.get(id(model))
    if hit is not None and hit[0] is model:
        # a failure recorded by an earlier run of this model must not end this one
        hit[1].failure.clear()
        hit[1].flow_failure.clear()
        return hit[1]
    compiled = CompiledModel(model, run_inputs(model, None))
    if len(cache) >= _CACHE_SIZE:
        cache.pop(next(iter(cache)))
    cache[id(model)] = (model, compiled)
    return compiled


def _initial_vector(
    model: System, compiled: CompiledModel, initial: Mapping[str, float] | None
) -> list[float]:
    x0 = model.initial_vector()
    if initial:
        for name, value in initial.items():
            if name not in compiled.state_names:
                raise UsageError(f"initial value for unknown state variable '{name}'")
            x0[compiled.state_names.index(name)] = float(value)
    return x0
