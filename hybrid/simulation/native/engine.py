"""``backend="compiled"``: one run of a model on its generated, numba-compiled loop.

The counterpart of :mod:`hybrid.simulation.engine` past its settings: the
model's structure is generated and loaded once per structure
(:class:`CompiledNative`, cached per process; numba's disk cache across
processes), the run's parameter vector, initial point and mode are arguments,
and the arrays the loop fills become a :class:`~hybrid.simulation.result.Run`.
A run that fills its buffers is run again with four times the room. The
first Ctrl-C sets a flag the loop reads at every step
(:mod:`hybrid.simulation.native.interruptible`). What does not change between runs
of one model (its structure, the loop's inputs, the run's arrays) is kept
between calls, never stale: a short compiled run costs little more than its loop.
"""

from __future__ import annotations

import math
import os
import threading
import time
import warnings
from collections.abc import Callable, Mapping
from functools import partial
from types import ModuleType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from hybrid.compose import System
from hybrid.errors import UsageError
from hybrid.held import HeldCache
from hybrid.model import Automaton
from hybrid.simulation.interrupts import immediate
from hybrid.simulation.native import buffers as b
from hybrid.simulation.native.assemble import Layout, run_from
from hybrid.simulation.native.cache import compiling, load_generated, require_numba, seal
from hybrid.simulation.native.choice import (
    announce,
    generated_notice,
    generated_wait,
    waiting_notice,
)
from hybrid.simulation.native.features import check_supported
from hybrid.simulation.native.interruptible import run_here, run_in_worker
from hybrid.simulation.native.kernel_text import kernel_module
from hybrid.simulation.native.kernel_types import PIECES
from hybrid.simulation.native.loop import lay_out_work
from hybrid.simulation.native.pace import record as record_pace
from hybrid.simulation.native.shares import compiling_beside
from hybrid.simulation.native.source import native_source
from hybrid.simulation.native.structure import structure_key
from hybrid.simulation.result import Run
from hybrid.simulation.settings import Settings
from hybrid.simulation.start import initial_vector

__all__ = [
    "CompiledNative",
    "compiled_native",
    "config",
    "idle_threads_sleep_soon",
    "run_arrays",
    "simulate_compiled",
]

_KERNEL_LOCK = threading.Lock()
_LAST: list[tuple[System, CompiledNative] | None] = [None]
"""The model of the last :func:`compiled_native` call and its answer."""


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
    with _KERNEL_LOCK:
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
            idle_threads_sleep_soon()  # before numba starts its threads with this load
            many = kernel_module(_KERNEL["one"].__name__)
            with compiling(many):  # another process compiling it: awaited, then loaded
                _KERNEL["many"] = load_generated(many)
            # compiled whole (its signature is explicit): numba writes nothing more to its
            # cache files, on its first calls either (checked in a fresh cache, compiling
            # process and loading one), so they are held to a manifest like the others
            seal(_KERNEL["many"])
        return _KERNEL["many" if parallel else "one"]


IDLE_SPINS = "10000"
"""``GOMP_SPINCOUNT`` set when the process chose nothing: about a millisecond of spinning."""


def idle_threads_sleep_soon() -> None:
    """Have numba's OpenMP threads sleep soon when idle, unless the process chose how they wait.

    libgomp's threads spin after each parallel loop (300,000 rounds by
    default, a few milliseconds) before they sleep: an ensemble's other thread
    spun while Python copied each chunk's runs out, CPU time a tenth of the
    ensemble's (10,000 thermostat runs: 1.85 times the floor's CPU instead of
    2.03; the wall time the same). Read by libgomp when numba first starts its
    threads, so called before that; ``OMP_WAIT_POLICY`` or ``GOMP_SPINCOUNT``
    already set are kept, and once libgomp runs the setting has no effect.
    """
    if "OMP_WAIT_POLICY" not in os.environ and "GOMP_SPINCOUNT" not in os.environ:
        os.environ["GOMP_SPINCOUNT"] = IDLE_SPINS


class CompiledNative:
    """A model structure, generated and loaded: what every run of it shares."""

    def __init__(self, model: System) -> None:
        self.native, self.generated = native_source(model)
        self.layout = Layout.of(self.native)
        require_numba()  # imported before the clock starts: the import is not the compile
        # another process's compile of the same code is awaited, saying so; then what is
        # left to compile is said (nothing, after such a wait)
        waiting = partial(announce, partial(waiting_notice, self.generated))
        with compiling(kernel_module(), self.generated, waiting=waiting):
            announce(partial(generated_notice, self.generated))  # the model is accepted
            expected, kind = generated_wait(self.generated)  # what is left to compile
            started = time.perf_counter()
            self.module, self.kernel = self._compile_or_load()
            if expected:
                record_pace(time.perf_counter() - started, expected, kind)  # for later notices
        self.functions: Any = self.module.model
        from hybrid.simulation.native.pointers import model_addresses

        self.fp = np.array([*model_addresses(self.functions), *_PIECES["one"]], dtype=np.int64)
        """The addresses the compiled loop calls: the model (a ``cfunc``), then the pieces."""
        assert self.fp.size == b.N_FP
        self.tab = self.generated.tab
        floats, ints = lay_out_work(self.tab, np.zeros(b.WI_HEADER, dtype=np.int64))
        self.work = (int(floats), int(ints))
        """The lengths of a run's scratch space (``wf``, ``wi``): Python allocates it."""
        self.max_transitions = max(1, *(len(m.transitions) for m in self.native.modes))
        self._one = _entry_point(self.kernel.run_one)
        self._many: Callable[..., None] | None = None
        self._scratch = threading.local()

    def _compile_or_load(self) -> tuple[ModuleType, ModuleType]:
        """The model's module and the kernel, compiled or loaded, and sealed."""
        with compiling_beside(self.generated.compile_estimate):
            kernel(wait=False)  # the first time, worker processes compile the rest meanwhile
        try:
            module = load_generated(self.generated)
        except Exception as exc:  # numba refusing a library's compiled form, say
            lines = [line for line in str(exc).splitlines() if line.strip()]
            what = ", ".join(sorted(self.native.functions)) or "its expressions"
            raise UsageError(
                f"the compiled backend could not compile {self.native.system.name} "
                f"(library functions: {what}): {lines[0] if lines else type(exc).__name__}"
            ) from exc
        loop = kernel()
        seal(loop)  # both compiled whole now: their cache files are held to a manifest
        seal(module)
        return module, loop

    def run_one(self, p: Any, x0: Any, t0: float, m0: int, cfg: Any, arrays: b.RunArrays,
                flag: Any) -> None:  # fmt: skip
        """One run into ``arrays`` (see :func:`hybrid.simulation.native.loop.run_one`).

        The compiled code is called without numba's dispatcher (:func:`_entry_point`),
        so nothing is typed or compiled here and numba has nothing to warn about.
        """
        self._one(self.fp, self.tab, p, x0, t0, m0, cfg[0], cfg[1], arrays.pts, arrays.jps,
                  arrays.sts, arrays.oi, arrays.of, flag, arrays.wf, arrays.wi)  # fmt: skip

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
                   arrays.sts, arrays.oi, arrays.of, flag, arrays.wf, arrays.wi)  # fmt: skip

    def buffers(self, points: int, jumps: int, steps: int, runs: int | None = None) -> b.RunArrays:
        return b.allocate(
            len(self.native.state_names),
            len(self.native.columns),
            self.max_transitions,
            points,
            jumps,
            steps,
            runs,
            self.work,
        )

    def scratch(self, points: int, jumps: int, steps: int) -> b.RunArrays:
        """:meth:`buffers` of these sizes, this thread's own, as the last run left them.

        The compiled loop resets what it counts on (``oi``, ``of``) itself,
        which costs less than resetting from Python; the caller must be done with
        the arrays (every value copied out) before it asks for them again.
        """
        arrays: b.RunArrays | None = getattr(self._scratch, "arrays", None)
        if arrays is None or self._scratch.sizes != (points, jumps, steps):
            arrays = self._scratch.arrays = self.buffers(points, jumps, steps)
            self._scratch.sizes = (points, jumps, steps)
        return arrays

    def initial_mode(self, model: System) -> int:
        if isinstance(model, Automaton):  # as_system's view without building it
            return self.native.index[(model.initial_location,)]
        return self.native.index[model.initial_mode]


def _entry_point(dispatcher: Any) -> Callable[..., None]:
    """The compiled function behind a dispatcher of one signature, called without dispatch.

    Resolving the argument types (a tuple of function pointers among them) on
    every call costs far more than a short run; the types never change.
    """
    (signature,) = dispatcher.signatures
    entry: Callable[..., None] = dispatcher.overloads[signature].entry_point
    return entry


_COMPILED = HeldCache[CompiledNative](16)
"""Each model structure's compiled model (:func:`structure_key`)."""


def compiled_native(model: System) -> CompiledNative:
    """The :class:`CompiledNative` of ``model``'s structure (generated once per process)."""
    last = _LAST[0]  # the model of the last call, first: a run repeated costs no key
    if last is not None and last[0] is model:
        return last[1]
    key, objects = structure_key(model)
    compiled = _COMPILED.get(key, objects, lambda: CompiledNative(model))
    _LAST[0] = (model, compiled)  # one tuple, replaced at once; it holds the model (and its id)
    return compiled


def config(settings: Settings) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """The settings as the compiled loop reads them (``cfg_f``, ``cfg_i``)."""
    floats = [0.0] * b.N_CFG_F  # filled as lists, one array each: cheaper than item by item
    floats[b.CF_T_END] = settings.t_end
    floats[b.CF_RTOL] = settings.rtol
    floats[b.CF_ATOL] = settings.atol
    floats[b.CF_MAX_STEP] = settings.max_step
    floats[b.CF_DT] = math.nan if settings.dt is None else settings.dt
    floats[b.CF_T_START] = settings.t_start
    ints = [0] * b.N_CFG_I
    ints[b.CI_MAX_JUMPS] = settings.max_jumps
    ints[b.CI_ZENO] = int(settings.zeno)
    ints[b.CI_PER_INSTANT] = settings.max_jumps_per_instant
    ints[b.CI_DENSE] = int(settings.dense)
    return np.array(floats, dtype=np.float64), np.array(ints, dtype=np.int64)


def simulate_compiled(
    model: System,
    settings: Settings,
    *,
    initial: Mapping[str, float] | None = None,
    inputs: Mapping[str, Callable[[float], float]] | None = None,
    handle_sigint: bool = True,
    progress: Callable[[float, int, int], None] | None = None,
) -> Run:
    """One run of ``model`` (parameters and initial location already applied) with ``settings``.

    ``progress(t, jumps, points)``: see :func:`run_arrays`.

    What the loop is given (parameter vector, initial point and mode, settings
    arrays) is kept for the last model object (frozen) and settings run without
    ``initial``; the loop only reads these arrays. Running them again costs no
    conversions.
    """
    last = _LAST_RUN[0]
    if (last is not None and last[0] is model and not initial and not inputs
            and _same_config(last[1], settings)):  # fmt: skip
        compiled, p, x0, m0, cfg = last[2:]  # settings equal to those checked then
    else:
        require_numba()
        check_supported(settings, inputs)
        with immediate("compiling the model (nothing was run)"):
            compiled = compiled_native(model)
        native = compiled.native
        p = np.array(native.parameter_vector(model), dtype=float)
        x0 = np.array(initial_vector(model, native.state_names, initial), dtype=float)
        m0 = compiled.initial_mode(model)
        cfg = config(settings)
        if not initial:
            _LAST_RUN[0] = (model, settings, compiled, p, x0, m0, cfg)  # replaced at once
    arrays = run_arrays(
        compiled, p, x0, m0, settings, handle_sigint, reuse=True, cfg=cfg, progress=progress
    )
    return run_from(compiled.native, compiled.layout, model, settings, arrays)  # copies all it keeps


def _same_config(a: Settings, b: Settings) -> bool:
    """Whether ``config(a)`` and ``config(b)`` hold the same numbers (signed zeros too)."""
    return a is b or (
        a == b
        and math.copysign(1.0, a.t_start) == math.copysign(1.0, b.t_start)
        and math.copysign(1.0, a.t_end) == math.copysign(1.0, b.t_end)
    )


_LAST_RUN: list[tuple[Any, ...] | None] = [None]
"""``(model, settings, compiled, p, x0, m0, cfg)`` of the last :func:`simulate_compiled` call."""


def run_arrays(
    compiled: CompiledNative,
    p: NDArray[np.float64],
    x0: NDArray[np.float64],
    m0: int,
    settings: Settings,
    handle_sigint: bool,
    reuse: bool = False,
    cfg: tuple[NDArray[np.float64], NDArray[np.int64]] | None = None,
    progress: Callable[[float, int, int], None] | None = None,
    flag: NDArray[np.int64] | None = None,
) -> b.RunArrays:
    """One run's arrays, run again with four times the room until they hold it all.

    With ``reuse``, a run in this thread (not in a worker) may fill the thread's
    :meth:`CompiledNative.scratch` arrays (the first, smallest sizes only: a
    process keeps no longer run's room): the caller copies out what it keeps
    before the next run. A worker's arrays are always its own (after a second
    Ctrl-C an abandoned worker may still be writing). With ``handle_sigint`` the
    loop runs here (:func:`~hybrid.simulation.native.interruptible.run_in_worker`).
    ``cfg``: ``config(settings)``.
    ``progress(t, jumps, points)`` is called in the calling thread while the
    loop runs on another (:func:`~hybrid.simulation.native.interruptible.run_in_worker`),
    with the time reached (never going back, also when a run is repeated with
    more room). ``flag``: the interrupt flag the loop reads (shared with an
    ensemble's runs; set already, the run ends at once as ``interrupted``).
    """
    cfg = config(settings) if cfg is None else cfg
    points, jumps = 256, 64
    steps = 256 if settings.dense else 1
    in_worker, first = progress is not None, True  # first: a longer run's room is its own
    watched = handle_sigint and threading.current_thread() is threading.main_thread()
    reached: list[float] = [settings.t_start, 0, 0]  # time, jumps, points: see _ticker
    while True:
        if reuse and not in_worker and first:
            arrays = compiled.scratch(points, jumps, steps)
        else:
            arrays = compiled.buffers(points, jumps, steps)
        if in_worker:

            def call(flag: NDArray[np.int64], arrays: b.RunArrays = arrays) -> None:
                compiled.run_one(p, x0, settings.t_start, m0, cfg, arrays, flag)

            run_in_worker(call, handle_sigint, flag, tick=_ticker(arrays, reached, progress))
        elif watched:  # what run_in_worker does then, without its checks
            run_here(partial(compiled.run_one, p, x0, settings.t_start, m0, cfg, arrays),
                     np.zeros(1, dtype=np.int64) if flag is None else flag)  # fmt: skip
        else:  # what run_in_worker does then, without its closure and thread check
            compiled.run_one(p, x0, settings.t_start, m0, cfg, arrays,
                             np.zeros(1, dtype=np.int64) if flag is None else flag)  # fmt: skip
        if not arrays.oi[b.I_OVERFLOW]:
            return arrays
        points, jumps, first = points * 4, jumps * 4, False
        steps = steps * 4 if settings.dense else 1


def _ticker(
    arrays: b.RunArrays, reached: list[float], progress: Callable[[float, int, int], None] | None
) -> Callable[[], None] | None:
    """``progress`` fed from the arrays the loop is filling (how far it has got)."""
    if progress is None:
        return None

    def tick() -> None:
        # numbers the loop's thread writes (each read whole on 64-bit); a run repeated
        # with more room starts again, so each is the furthest any attempt has reached
        now = (float(arrays.of[b.F_NOW]), int(arrays.oi[b.I_JUMPS]), int(arrays.oi[b.I_POINTS]))
        if now[0] >= reached[0]:
            reached[:] = now
        progress(reached[0], int(reached[1]), int(reached[2]))

    return tick


