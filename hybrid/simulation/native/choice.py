"""``backend="auto"``: the compiled backend where it pays for its compile, else scipy, and why.

A compiled run costs about 1/80 of a scipy run (docs/performance.md), but the
first one on a machine compiles the kernel (about 8 s of waiting and 18 s of CPU
on the benchmark machine) and each new model structure (its estimated seconds, from its
generated source's size), and a process that finds both in the cache still
spends about 0.9 s of CPU importing numba and loading them: more than a short
scipy run costs. :func:`choose` runs compiled when:

- the model and the kernel are already loaded in this process;
- or the campaign's runs are expected to save more than loading (and, what is
  not in the cache, compiling) costs: ``runs * run_s`` (one scipy run of the
  model, timed by the caller) above :data:`LOAD_S` plus the compile estimate;
  these costs are constants from the benchmark machine, so near the break-even
  they are scaled by how fast this machine is (:func:`machine_factor`: a
  reference scipy run timed here against :data:`PROBE_S`), as the timed run is;
  a campaign so long that scipy would cost more even at its cheapest
  (:data:`SCIPY_RUN_FLOOR_S` a run, and :data:`SCIPY_LOAD_S` to load the
  scipy engine where it is not loaded yet) is not timed: timing would load it;

and scipy when the compiled backend cannot run the campaign (numba missing, a
method other than RK45, inputs given as Python functions or expressions) or
when it does not pay. The :class:`Choice` says which and why, in words a
command line prints.

Examples
--------
>>> choose(None, 10, method="LSODA")
Choice(backend='scipy', reason="method 'LSODA' is the scipy backend's")
>>> choose(None, 10, inputs=True)
Choice(backend='scipy', reason='inputs are held by expressions (the scipy backend)')
"""

from __future__ import annotations

import importlib.util
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any

from hybrid.errors import HybridError
from hybrid.simulation.native.features import METHOD

__all__ = [
    "KERNEL_COMPILE_CPU_S",
    "KERNEL_COMPILE_S",
    "LOAD_S",
    "PROBE_S",
    "SCIPY_LOAD_S",
    "SCIPY_RUN_FLOOR_S",
    "Choice",
    "announce",
    "cached",
    "choose",
    "compile_notice",
    "compile_notices",
    "expected_wait",
    "generated_notice",
    "generated_wait",
    "machine_factor",
    "waiting_notice",
]

KERNEL_COMPILE_S = 8.0
"""Seconds a first process on a machine waits for the kernel's compile (bench: 7.7 to
10.8 s, 2 cores: worker processes compile shares of it meanwhile)."""
KERNEL_COMPILE_CPU_S = 18.0
"""CPU seconds the kernel's first compile costs, over every process that shares it: what
the choice weighs (a machine's cores are not free). Bench: a cold compiled sweep of
1,000 thermostat points took 22.2 s of CPU, 1.58 s warm; one process alone compiles
the kernel and the model in 18.1 s."""
LOAD_S = 0.9
"""CPU seconds a process spends importing numba and loading a cached kernel and model
(``hybrid simulate`` of the thermostat for 2 s, whole process, medians of 5: 1.46 s
compiled, 0.92 s scipy, which loads the scipy engine instead: :data:`SCIPY_LOAD_S`)."""
SCIPY_LOAD_S = 0.4
"""CPU seconds a campaign's process spends importing the scipy engine (scipy's integrators
and optimizers; measured 0.49 to 0.75 s): what its first scipy run costs beside the run."""
SCIPY_RUN_FLOOR_S = 6e-4
"""CPU seconds of the cheapest scipy run a campaign makes (a sweep point of a model with
one state and no event, over 1e-9 s: measured 0.82 ms)."""
COMPILED_SHARE = 1.0 / 50.0
"""A compiled run's time as a share of a scipy run's (measured 1/75 to 1/100: rounded up)."""
PROBE_S = 2.2e-3
"""CPU seconds of :func:`machine_factor`'s reference run on the benchmark machine of the
constants above. Derived: on a slower machine the reference run and a one-process compile
of the kernel and a model, timed back to back, gave 2.17 and 2.19 ms times 17.9 s (that
compile on the benchmark machine) over 52.5 and 51.5 s. The run read about 5 ms or about
7.7 ms there as the machine's speed changed; the compile's 52 s spans both."""
NEAR = 4.0
"""Within this factor of the break-even (saving / cost, at the constants) the costs are
scaled by :func:`machine_factor`; beyond it no machine is that much slower or faster."""
FACTOR_RANGE = (0.25, 4.0)
"""The least and most :func:`machine_factor` returns."""
PROBE_SPEC = """\
automaton: speed_probe
parameters: {a: 0.1, T_out: 10.0, T_heat: 30.0, T_low: 18.0, T_high: 22.0}
state: {T: {initial: 20.0}}
locations:
  off: {flow: {T: -a*(T - T_out)}, invariant: T >= T_low}
  on: {flow: {T: a*(T_heat - T)}, invariant: T <= T_high}
initial: {location: off}
edges:
  - {from: off, to: on, guard: T <= T_low}
  - {from: on, to: off, guard: T >= T_high}
"""
"""The reference model: a thermostat (specs/thermostat.yaml's flows and switches)."""


@dataclass(frozen=True)
class Choice:
    """The backend chosen and why (one clause)."""

    backend: str
    reason: str


def cached(model: Any) -> tuple[str, str, float]:
    """``(model, kernel, model compile estimate s)``: each ``"loaded"`` (in this process),
    ``"cached"`` (sealed in the cache, :mod:`~hybrid.simulation.native.cache`) or ``"missing"``.

    Generates the model's source (no numba import).
    """
    from hybrid.compose import as_system
    from hybrid.simulation.native.source import native_source

    return _cached_source(native_source(as_system(model))[1])  # a user's model: either type


def _cached_source(generated: Any) -> tuple[str, str, float]:
    """:func:`cached` of a model whose source is ``generated`` already."""
    from hybrid.simulation.native.cache import cache_key, key_state
    from hybrid.simulation.native.kernel_text import kernel_module

    version = _numba_version()
    keys = [cache_key(generated, version), cache_key(kernel_module(), version)]
    found = [key_state(key) for key in keys]
    return found[0], found[1], generated.compile_estimate


def choose(model: Any, runs: int, *, method: str = "RK45", inputs: bool = False,
           run_s: Callable[[], float] | None = None) -> Choice:  # fmt: skip
    """The backend for ``runs`` runs of ``model`` (see the module docstring); compiled
    only where numba imports (installed but broken, it would fail every run)."""
    choice = _choose(model, runs, method=method, inputs=inputs, run_s=run_s)
    if choice.backend == "compiled":
        from hybrid.errors import UsageError
        from hybrid.simulation.native.cache import require_numba

        try:
            require_numba()  # imported anyway by the compiled runs
        except UsageError:
            return Choice("scipy", "numba is installed but does not import")
    return choice


def _choose(model: Any, runs: int, *, method: str = "RK45", inputs: bool = False,
            run_s: Callable[[], float] | None = None) -> Choice:  # fmt: skip
    """The backend for ``runs`` runs of ``model`` (see the module docstring).

    ``inputs``: whether the runs hold inputs (the compiled backend refuses
    them); ``run_s()``: CPU seconds of one scipy run of the model, called only
    when nothing is to be loaded or compiled (None: unknown; then compiled
    only if the compiled code is loaded in this process already).
    """
    if method != METHOD:
        return Choice("scipy", f"method '{method}' is the scipy backend's")
    if inputs:
        return Choice("scipy", "inputs are held by expressions (the scipy backend)")
    if importlib.util.find_spec("numba") is None:
        return Choice("scipy", "numba is not installed")
    held = sys.modules.get("hybrid.simulation.native.cache")
    if run_s is None and (held is None or not held._LOADED):  # nothing compiled is loaded here
        return Choice("scipy", f"one run: loading compiled code (about {LOAD_S:.1f} s) "
                               "would cost more than it saves")  # fmt: skip
    try:
        model_state, kernel_state, estimate = cached(model)
    except HybridError as exc:  # a model the compiled backend refuses
        return Choice("scipy", f"the compiled backend cannot run it: {exc}")
    if model_state == kernel_state == "loaded":
        return Choice("compiled", "the compiled model is loaded in this process")
    compiling = (KERNEL_COMPILE_CPU_S if kernel_state == "missing" else 0.0) + (
        estimate if model_state == "missing" else 0.0
    )
    cost = LOAD_S + compiling
    doing = "compiling and loading" if compiling else "loading the cached compiled code"
    what = f"{doing} (about {cost:.0f} s of CPU)" if compiling else f"{doing} (about {cost:.1f} s)"
    if run_s is None:
        return Choice("scipy", f"one run: {what} would cost more than it saves")
    least = runs * SCIPY_RUN_FLOOR_S + (0.0 if _scipy_loaded() else SCIPY_LOAD_S)
    if least > cost:
        return Choice("compiled", f"{runs} runs would cost at least {least:.1f} s on scipy "
                                  f"(loading it included); {what}")  # fmt: skip
    saved = runs * run_s() * (1.0 - COMPILED_SHARE)
    if 1.0 / NEAR < saved / cost < NEAR:  # the run was timed on this machine: the costs too
        factor = machine_factor()
        cost *= factor
        what = (f"{doing} (about {cost:.1f} s of CPU here, {factor:.1f} times the benchmark "
                "machine's)")  # fmt: skip
    verdict = "compiled" if saved > cost else "scipy"
    return Choice(verdict, f"{runs} runs would save about {saved:.1f} s; {what}")


def machine_factor() -> float:
    """How much more CPU time this machine takes than the benchmark machine, now.

    A reference scipy run (a thermostat for 10 s, :data:`PROBE_SPEC`), timed after one
    untimed run (best of two), over :data:`PROBE_S`; within :data:`FACTOR_RANGE`.
    It is the same work as a campaign's timed run, so it slows with it. Loads the scipy
    engine (a campaign's timed run has already).

    Examples
    --------
    >>> FACTOR_RANGE[0] <= machine_factor() <= FACTOR_RANGE[1]
    True
    """
    import time

    from hybrid.compose import as_system
    from hybrid.reader.loader import load_text
    from hybrid.simulation.reference import simulate_reference
    from hybrid.simulation.settings import merged

    model, settings = as_system(load_text(PROBE_SPEC, file="<speed probe>")), merged(None, 10.0)
    times = []
    for _ in range(3):
        start = time.process_time()
        simulate_reference(model, settings, None, None, False, None)
        times.append(time.process_time() - start)
    least, most = FACTOR_RANGE
    return min(most, max(least, min(times[1:]) / PROBE_S))


def compile_notice(model: Any) -> str | None:
    """What a first compiled run of ``model`` compiles before it starts, and about how long
    that takes; ``None`` when the model and the compiled loop are both cached.

    A command prints it as a run starts to compile (:func:`compile_notices`), so that
    a user knows why a first run waits (and that later ones will not). The estimates
    are the benchmark machine's; one of 5 s or more is scaled by how long the last
    long compile on this machine took against its own
    (:mod:`~hybrid.simulation.native.pace`; the text then says "here").
    """
    return _notice(*cached(model))


def expected_wait(model_state: str, kernel_state: str, estimate: float) -> float:
    """Seconds a compile of what :func:`cached` says is missing waits on the benchmark
    machine: the kernel's :data:`KERNEL_COMPILE_S` and the model's ``estimate`` (at
    least 1 s); 0 when both are cached.

    Examples
    --------
    >>> expected_wait("missing", "cached", 0.4), expected_wait("cached", "missing", 0.4)
    (1.0, 8.0)
    """
    kernel_s = KERNEL_COMPILE_S if kernel_state == "missing" else 0.0
    return kernel_s + (max(1.0, estimate) if model_state == "missing" else 0.0)


def _pace_kind(kernel_state: str) -> str:
    """The kind of a compile (:mod:`~hybrid.simulation.native.pace`): ``"kernel"`` when the
    kernel is missing (it is compiled with the model), else ``"model"``."""
    return "kernel" if kernel_state == "missing" else "model"


def _notice(
    model_state: str, kernel_state: str, estimate: float, waiting: bool = False
) -> str | None:
    from hybrid.simulation.native.pace import MIN_ESTIMATE_S, pace

    # this machine's pace, from its last compile of the kind; None: the benchmark machine's
    factor = pace(_pace_kind(kernel_state))

    def about(seconds: float) -> str:  # a short compile's wait is mostly loading: not scaled
        if factor is None or seconds < MIN_ESTIMATE_S:
            return f"about {seconds:.0f} s"
        return f"about {seconds * factor:.0f} s here"

    parts = []
    if kernel_state == "missing":
        parts.append(f"the compiled loop (once per machine, {about(KERNEL_COMPILE_S)})")
    if model_state == "missing":
        parts.append(f"the model ({about(max(1.0, estimate))})")
    if not parts:
        return None
    if waiting:
        return f"waiting for another process compiling {' and '.join(parts)}; then loading them"
    return f"compiling {' and '.join(parts)}; later runs load them from the cache"


_SAY: ContextVar[Callable[[str], None] | None] = ContextVar("hybrid_compile_notices", default=None)


@contextmanager
def compile_notices(say: Callable[[str], None]) -> Iterator[None]:
    """Within it, ``say(text)`` when a compiled run is about to compile: once its model is
    accepted, after every check that may refuse the run (:func:`announce`).

    A command that printed :func:`compile_notice` before calling the run printed it also
    for a run then refused (another method, a held input, a campaign's ``--resume``).

    Examples
    --------
    >>> said = []
    >>> with compile_notices(said.append):
    ...     announce(lambda: "compiling the model")
    ...     announce(lambda: None)  # all of it cached
    >>> announce(lambda: "compiling the loop")  # outside: nothing asked, nothing worked out
    >>> said
    ['compiling the model']
    """
    token = _SAY.set(say)
    try:
        yield
    finally:
        _SAY.reset(token)


def announce(notice: Callable[[], str | None]) -> None:
    """``say(notice())`` within :func:`compile_notices` when the notice is not ``None``;
    ``notice`` is called only there. The compiled backend calls it with
    :func:`generated_notice` before it compiles or loads a model."""
    say = _SAY.get()
    if say is None:
        return
    text = notice()
    if text is not None:
        say(text)


def generated_notice(generated: Any) -> str | None:
    """:func:`compile_notice` of a model whose source is ``generated`` already."""
    return _notice(*_cached_source(generated))


def waiting_notice(generated: Any) -> str | None:
    """What this process waits for when another is compiling what :func:`generated_notice`
    would have this one compile (:func:`~hybrid.simulation.native.cache.compiling`)."""
    return _notice(*_cached_source(generated), waiting=True)


def generated_wait(generated: Any) -> tuple[float, str]:
    """:func:`expected_wait` of a model whose source is ``generated`` already, and the kind
    of that compile (:mod:`~hybrid.simulation.native.pace`): ``"kernel"`` when the kernel
    is missing, else ``"model"``."""
    model_state, kernel_state, estimate = _cached_source(generated)
    return expected_wait(model_state, kernel_state, estimate), _pace_kind(kernel_state)


def _scipy_loaded() -> bool:
    """Whether this process has loaded the scipy engine (a scipy run costs no import then).

    Its module is :mod:`hybrid.simulation.reference`; ``simulate``'s own module is loaded
    by compiled runs too, without scipy.
    """
    return "hybrid.simulation.reference" in sys.modules


def _numba_version() -> str:
    from importlib.metadata import version

    return version("numba")
