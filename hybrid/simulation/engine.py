"""``simulate``: the public entry to the simulator.

It validates the settings (:class:`~hybrid.simulation.settings.Settings`) and
the overrides (finite numbers, callable inputs), applies the overrides to the
model, and runs it on the backend chosen: the reference engine
(:mod:`~hybrid.simulation.reference`: scipy's integrators, the event loop) or
the compiled one (:mod:`~hybrid.simulation.native.engine`), each imported on
its first run, so that a process loads only the backend it runs. Progress is
reported through :mod:`hybrid.progress`; the bounds are checked on the result.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Mapping
from dataclasses import replace
from types import ModuleType
from typing import Any

import numpy as np

from hybrid.compose import System, as_system, expect_model
from hybrid.errors import UsageError
from hybrid.keywords import named_keywords
from hybrid.model import Automaton
from hybrid.progress import Reporter, Tracker
from hybrid.simulation.bounds import run_excursions, warn_excursions
from hybrid.simulation.result import Run
from hybrid.simulation.settings import Settings, finite_number, merged_values
from hybrid.simulation.start import describe_start

__all__ = ["simulate"]

_OPTIONS = ("t_start", "max_jumps", "rtol", "atol", "max_step", "method", "dt", "dense", "zeno",
            "max_jumps_per_instant", "backend")  # fmt: skip
"""The options :func:`simulate` passes to :func:`~hybrid.simulation.settings.merged_values`."""


@named_keywords
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
    expect_model(model, "simulate")
    settings = merged_values(
        settings,
        t_end,
        _OPTIONS,
        (t_start, max_jumps, rtol, atol, max_step, method, dt, dense, zeno,
         max_jumps_per_instant, backend),
    )  # fmt: skip
    t_start, t_end = settings.t_start, settings.t_end
    parameters = _numbers("parameters", "parameter", parameters, model)
    if settings.backend != "compiled" and settings.backend != "scipy":  # not given, or auto
        settings = replace(settings, backend=_one_run_backend(model, settings, inputs))
    initial = _numbers("initial", "initial value of", initial, model)
    if inputs is not None:
        _check_inputs(inputs, t_start, t_end)
    model = model.with_parameters(parameters) if parameters else model
    if isinstance(model, System) and initial_location:
        raise UsageError("initial_location applies to an automaton; set it per component")
    if initial_location is not None and not isinstance(initial_location, str):
        raise UsageError(f"initial_location must be a location's name, got {initial_location!r}")
    if progress is not None and not callable(progress):
        raise UsageError(f"progress must be a function of a status, got {progress!r}")
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
        from hybrid.simulation.reference import simulate_reference

        run = simulate_reference(model, settings, initial, inputs, handle_sigint, progressed)
    run.settings["start"] = start
    run.out_of_bounds = run_excursions(model.states, run, rtol=settings.rtol, atol=settings.atol)
    if run.out_of_bounds:
        warn_excursions(run.out_of_bounds)
    if tracker is not None:
        tracker.finish(run.termination.t, jumps=len(run.jumps), points=len(run))
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
    from hybrid.simulation.monitor import monitor_for
    from hybrid.simulation.reuse import compiled_model

    reference = compiled_model(model, None)
    monitor = monitor_for(reference, settings)
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


def _updater(tracker: Tracker | None) -> Callable[[float, int, int], None] | None:
    if tracker is None:
        return None
    update = tracker.update

    def progress(t: float, jumps: int, points: int) -> None:
        update(t, jumps=jumps, points=points)

    return progress


def _numbers(keyword: str, item: str, values: Any, model: Automaton | System) -> dict[str, float] | None:
    """``values`` with each checked to be a finite number (a :class:`UsageError` if not).

    A pandas Series (one row of a table) is read as the mapping its index gives;
    a vector (MATLAB's ``x0``) is refused with the way to name its values.
    """
    if values is None:
        return None
    if not isinstance(values, Mapping) and callable(getattr(values, "to_dict", None)):
        values = values.to_dict()  # a pandas Series: its index names the values
    if not isinstance(values, Mapping):
        names: Any = ["comp.name"] if isinstance(model, System) else model.parameters
        if keyword == "initial":
            names = model.state_names
        example = ", ".join(f"{n!r}: ..." for n in list(names)[:3])
        vector = ""
        if keyword == "initial" and isinstance(values, (list, tuple, np.ndarray)):
            vector = "; values in state order: dict(zip(model.state_names, x0))"
        raise UsageError(
            f"{keyword}= takes a mapping of names to numbers, e.g. {{{example}}}, got "
            f"{type(values).__name__} {values!r}{vector}"
        )
    return {str(k): finite_number(f"{item} '{k}'", v) for k, v in values.items()} or None


def _check_inputs(inputs: Mapping[str, Callable[[float], float]] | None, t_start: float,
                  t_end: float = math.inf) -> None:  # fmt: skip
    """Each input a function of ``t`` that gives a number at ``t_start``, else a :class:`UsageError`.

    A :class:`~hybrid.simulation.inputs.TimeSeries` must span the run, as the command
    line's ``--input-csv`` must (past its samples it would be held without a word).

    A function that cannot be called as ``f(t)``, or gives something other than a
    number (a list, an array of one value), used to end the run at once as
    ``nonfinite``, with a message about the flow. One that cannot be computed at
    some ``t`` (``log(t)`` at ``t = 0``, a division by zero) still ends the run so.
    """
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
        covers = getattr(fn, "check_covers", None)  # a TimeSeries
        if callable(covers) and math.isfinite(t_end):
            covers(t_start, t_end)
        try:
            value = fn(t_start)
        except TypeError as exc:  # called wrongly (f(t, x)); a failing value is the run's
            raise UsageError(
                f"input '{name}' cannot be called as f(t): {exc} (at t={t_start:g})"
            ) from None
        except Exception:
            continue  # cannot be computed at t_start (log(t) at 0): the run ends nonfinite
        if not isinstance(value, numbers.Real) and not (
            isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "biuf"
        ):
            shape = f" of shape {value.shape}" if isinstance(value, np.ndarray) else ""
            raise UsageError(
                f"input '{name}' must give a number at each t, got {type(value).__name__}"
                f"{shape} at t={t_start:g}"
            )
