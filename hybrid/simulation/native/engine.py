"""``backend="compiled"``: one run of a model on its generated, numba-compiled loop.

The counterpart of :mod:`hybrid.simulation.engine` past its settings: the
model's structure is generated and loaded once per structure
(:class:`CompiledNative`, cached per process; numba's disk cache across
processes), the run's parameter vector, initial point and mode are arguments,
and the arrays the loop fills become a :class:`~hybrid.simulation.result.Run`.
A run that fills its buffers is run again with four times the room. Ctrl-C:
the loop runs in a worker thread (numba releases the GIL) while the main
thread turns the first Ctrl-C into a flag the loop reads at every step, as
:func:`hybrid.simulation.interrupts.sigint_watch` does for the reference engine.
"""

from __future__ import annotations

import threading
import warnings
from collections.abc import Callable, Mapping
from types import ModuleType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hybrid.compose import System, as_system
from hybrid.errors import UsageError
from hybrid.model import Automaton
from hybrid.simulation.interrupts import sigint_watch
from hybrid.simulation.native import buffers as b
from hybrid.simulation.native.assemble import Layout, run_from
from hybrid.simulation.native.cache import load_generated, require_numba
from hybrid.simulation.native.kernel_types import PIECES
from hybrid.simulation.native.source import generate, kernel_module
from hybrid.simulation.native.structure import NativeModel
from hybrid.simulation.result import Run
from hybrid.simulation.settings import Settings

__all__ = [
    "CompiledNative",
    "compiled_native",
    "config",
    "run_arrays",
    "run_in_worker",
    "simulate_compiled",
]

_CACHE_SIZE = 16
_CACHE: dict[tuple[Any, ...], tuple[tuple[Any, ...], CompiledNative]] = {}
_CACHE_LOCK = threading.Lock()


_KERNEL: dict[str, ModuleType] = {}
_PIECES: dict[str, tuple[int, ...]] = {}
"""The addresses of the kernel's pieces (C wrapper, compiled code), in ``PIECES`` order."""


def kernel(parallel: bool = False, wait: bool = True) -> ModuleType:
    """The compiled loop, or its ensemble loop (compiled or loaded once per process).

    ``wait=False``: return once this process's share of a first compile is
    done, worker processes still compiling theirs (see
    :mod:`~hybrid.simulation.native.shares`); a later ``kernel()`` waits.
    """
    require_numba()
    with _CACHE_LOCK:
        if not _KERNEL:
            from numba.core.errors import NumbaExperimentalFeatureWarning

            # numba warns on every use of function pointers (its "first-class functions")
            warnings.filterwarnings("ignore", category=NumbaExperimentalFeatureWarning)
        if "one" not in _KERNEL:
            _KERNEL["one"] = load_generated(kernel_module())
        if not wait and not parallel:
            return _KERNEL["one"]
        if "one" not in _PIECES:
            _KERNEL["one"].finish_compiling()
            from hybrid.simulation.native.pointers import addresses

            _PIECES["one"] = tuple(
                address for name, _ in PIECES for address in addresses(getattr(_KERNEL["one"], name))
            )
        if parallel and "many" not in _KERNEL:
            _KERNEL["many"] = load_generated(kernel_module(_KERNEL["one"].__name__))
        return _KERNEL["many" if parallel else "one"]


class CompiledNative:
    """A model structure, generated and loaded: what every run of it shares."""

    def __init__(self, model: Automaton | System) -> None:
        self.native = NativeModel(model)
        self.layout = Layout.of(self.native)
        self.generated = generate(self.native)
        kernel(wait=False)  # the first time, worker processes compile the rest meanwhile
        try:
            self.module: ModuleType = load_generated(self.generated)
        except Exception as exc:  # numba refusing a library's compiled form, say
            lines = [line for line in str(exc).splitlines() if line.strip()]
            what = ", ".join(sorted(self.native.functions)) or "its expressions"
            raise UsageError(
                f"the compiled backend could not compile {self.native.system.name} "
                f"(library functions: {what}): {lines[0] if lines else type(exc).__name__}"
            ) from exc
        self.kernel = kernel()
        self.functions: Any = self.module.model
        self.fp = np.array([self.functions.address, 0, *_PIECES["one"]], dtype=np.int64)
        """The addresses the compiled loop calls: the model (a ``cfunc``), then the pieces."""
        assert self.fp.size == b.N_FP
        self.tab = self.generated.tab
        self.max_transitions = max(1, *(len(m.transitions) for m in self.native.modes))
        self._one = _entry_point(self.kernel.run_one)
        self._many: Callable[..., None] | None = None

    def run_one(self, p: Any, x0: Any, t0: float, m0: int, cfg: Any, arrays: b.RunArrays,
                flag: Any) -> None:  # fmt: skip
        """One run into ``arrays`` (see :func:`hybrid.simulation.native.loop.run_one`)."""
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # numba: "first-class function type is experimental"
            self._run_one(p, x0, t0, m0, cfg, arrays, flag)

    def _run_one(self, p: Any, x0: Any, t0: float, m0: int, cfg: Any, arrays: b.RunArrays,
                 flag: Any) -> None:  # fmt: skip
        self._one(self.fp, self.tab, p, x0, t0, m0, cfg[0], cfg[1], arrays.pts, arrays.jps,
                  arrays.sts, arrays.oi, arrays.of, flag)  # fmt: skip

    def run_many(self, ps: Any, x0s: Any, t0: float, m0: int, cfg: Any, arrays: b.RunArrays,
                 flag: Any) -> None:  # fmt: skip
        """Runs into the rows of ``arrays`` (see :func:`hybrid.simulation.native.ensemble.run_many`)."""
        if self._many is None:
            self._many = _entry_point(kernel(parallel=True).run_many)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # numba: "first-class function type is experimental"
            self._many_call(ps, x0s, t0, m0, cfg, arrays, flag)

    def _many_call(self, ps: Any, x0s: Any, t0: float, m0: int, cfg: Any, arrays: b.RunArrays,
                   flag: Any) -> None:  # fmt: skip
        assert self._many is not None
        self._many(self.fp, self.tab, ps, x0s, t0, m0, cfg[0], cfg[1], arrays.pts, arrays.jps,
                   arrays.sts, arrays.oi, arrays.of, flag)  # fmt: skip

    def buffers(self, points: int, jumps: int, steps: int, runs: int | None = None) -> b.RunArrays:
        return b.allocate(
            len(self.native.state_names),
            len(self.native.columns),
            self.max_transitions,
            points,
            jumps,
            steps,
            runs,
        )

    def initial_mode(self, model: Automaton | System) -> int:
        return self.native.index[as_system(model).initial_mode]


def _entry_point(dispatcher: Any) -> Callable[..., None]:
    """The compiled function behind a dispatcher of one signature, called without dispatch.

    Resolving the argument types (a tuple of function pointers among them) on
    every call costs far more than a short run; the types never change.
    """
    (signature,) = dispatcher.signatures
    entry: Callable[..., None] = dispatcher.overloads[signature].entry_point
    return entry


def _structure_key(model: Automaton | System) -> tuple[tuple[Any, ...], tuple[Any, ...]]:
    """``(key, objects)``: what identifies a model's structure, parameter and initial values aside.

    ``with_parameters`` and ``with_initial`` keep the locations, edges and
    signals objects, so the models of a sweep share one entry. The key holds
    their ids; the cache holds the objects, so no other object can take an id.
    """
    system = as_system(model)
    objects = tuple(
        (c.automaton.locations, c.automaton.edges, c.automaton.signals) for c in system.components
    )
    names = tuple((c.name, c.automaton.name) for c in system.components)
    key = (system.name, system.single, names, tuple(id(o) for trio in objects for o in trio))
    return key, objects


def compiled_native(model: Automaton | System) -> CompiledNative:
    """The :class:`CompiledNative` of ``model``'s structure (generated once per process)."""
    key, objects = _structure_key(model)
    with _CACHE_LOCK:
        hit = _CACHE.get(key)
        if hit is not None:
            return hit[1]
    compiled = CompiledNative(model)
    with _CACHE_LOCK:
        if len(_CACHE) >= _CACHE_SIZE:
            _CACHE.pop(next(iter(_CACHE)))
        _CACHE[key] = (objects, compiled)
    return compiled


def config(settings: Settings) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The settings as the compiled loop reads them (``cfg_f``, ``cfg_i``)."""
    cfg_f = np.empty(b.N_CFG_F)
    cfg_f[b.CF_T_END] = settings.t_end
    cfg_f[b.CF_RTOL] = settings.rtol
    cfg_f[b.CF_ATOL] = settings.atol
    cfg_f[b.CF_MAX_STEP] = settings.max_step
    cfg_f[b.CF_DT] = np.nan if settings.dt is None else settings.dt
    cfg_f[b.CF_T_START] = settings.t_start
    cfg_i = np.empty(b.N_CFG_I, dtype=np.int64)
    cfg_i[b.CI_MAX_JUMPS] = settings.max_jumps
    cfg_i[b.CI_ZENO] = int(settings.zeno)
    cfg_i[b.CI_PER_INSTANT] = settings.max_jumps_per_instant
    cfg_i[b.CI_DENSE] = int(settings.dense)
    return cfg_f, cfg_i


def check_supported(settings: Settings, inputs: Mapping[str, Any] | None) -> None:
    """Refuse what the compiled backend does not do, naming it (never run otherwise)."""
    require_numba()
    if settings.method != "RK45":
        raise UsageError(
            f"the compiled backend integrates with RK45 (Dormand–Prince 5(4)); method "
            f"'{settings.method}' needs backend='scipy'"
        )
    if inputs:
        raise UsageError(
            "the compiled backend cannot call external inputs given as Python functions "
            "(inputs=...); use backend='scipy'"
        )


def run_in_worker(
    call: Callable[[NDArray[np.int64]], None],
    handle_sigint: bool,
    flag: NDArray[np.int64] | None = None,
) -> bool:
    """Run ``call(flag)``; with ``handle_sigint`` a first Ctrl-C sets ``flag``. True if it did."""
    flag = np.zeros(1, dtype=np.int64) if flag is None else flag
    if not handle_sigint or threading.current_thread() is not threading.main_thread():
        call(flag)
        return False
    errors: list[BaseException] = []

    def work() -> None:
        try:
            call(flag)
        except BaseException as exc:  # re-raised in the caller's thread
            errors.append(exc)

    with sigint_watch(True) as interrupted:
        worker = threading.Thread(target=work, name="hybrid-compiled", daemon=True)
        worker.start()
        try:
            while worker.is_alive():
                worker.join(0.05)
                if interrupted.requested:
                    flag[0] = 1
        except KeyboardInterrupt:
            flag[0] = 1  # a second Ctrl-C: stop the loop too, and abandon the run
            raise
    if errors:
        raise errors[0]
    return bool(flag[0])


def simulate_compiled(
    model: Automaton | System,
    settings: Settings,
    *,
    initial: Mapping[str, float] | None = None,
    inputs: Mapping[str, Callable[[float], float]] | None = None,
    handle_sigint: bool = True,
) -> Run:
    """One run of ``model`` (parameters and initial location already applied) with ``settings``."""
    check_supported(settings, inputs)
    compiled = compiled_native(model)
    native = compiled.native
    p = np.array(native.parameter_vector(model), dtype=float)
    x0 = np.array(initial_vector(model, native.state_names, initial), dtype=float)
    m0 = compiled.initial_mode(model)
    arrays = run_arrays(compiled, p, x0, m0, settings, handle_sigint)
    return run_from(native, compiled.layout, model, settings, arrays)


def run_arrays(
    compiled: CompiledNative,
    p: NDArray[np.float64],
    x0: NDArray[np.float64],
    m0: int,
    settings: Settings,
    handle_sigint: bool,
) -> b.RunArrays:
    """One run's arrays, run again with four times the room until they hold it all."""
    cfg = config(settings)
    points, jumps = 256, 64
    steps = 256 if settings.dense else 1
    while True:
        arrays = compiled.buffers(points, jumps, steps)

        def call(flag: NDArray[np.int64], arrays: b.RunArrays = arrays) -> None:
            compiled.run_one(p, x0, settings.t_start, m0, cfg, arrays, flag)

        run_in_worker(call, handle_sigint)
        if not arrays.oi[b.I_OVERFLOW]:
            return arrays
        points, jumps = points * 4, jumps * 4
        steps = steps * 4 if settings.dense else 1


def initial_vector(
    model: Automaton | System, state_names: tuple[str, ...], initial: Mapping[str, float] | None
) -> list[float]:
    """The initial state; for a system, ``initial`` overrides some values (as the engine does)."""
    x0 = model.initial_vector()
    if isinstance(model, System) and initial:
        for name, value in initial.items():
            if name not in state_names:
                raise UsageError(f"initial value for unknown state variable '{name}'")
            x0[state_names.index(name)] = float(value)
    return x0
