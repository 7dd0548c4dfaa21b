"""Generated source: the kernel module, one per version of hybrid (and the ``Generated`` record).

**The kernel** (:func:`kernel_module`): a copy of the kernel modules
(everything below their ``# --- kernel ---`` line: integrator, boundary,
recorder, events, crossing, pieces, stay, loop, ensemble), each function
compiled by numba with the explicit signature its annotations give (:mod:`~hybrid.simulation.native.kernel_types`).
It does not depend on any model: it receives the model as five C function
pointers and a table of integers, so it is compiled once per machine. Each
model's module is :mod:`~hybrid.simulation.native.source`'s.

**Textual dependencies.** The modules named in :data:`KERNEL_MODULES`, and
those a ``kernel_source((...))`` call names (``mathlib`` in ``source``), are
dependencies by text, not by import: their code below the marker is copied
here, so it may import nothing (the generated module's header imports what it
needs). ``tests/test_architecture.py`` reads both forms as imports, so the
layer and circle rules hold for them, and checks that copied code imports
nothing.

Examples
--------
>>> code, names = kernel_source(("integrator",))
>>> names[:3]
['remember_flow_failure', 'eval_rhs', 'min_step_at']
"""

from __future__ import annotations

import functools
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from hybrid.simulation.native.kernel_types import PIECES

__all__ = ["JIT", "KERNEL_MODULES", "Generated", "kernel_module", "kernel_source"]

KERNEL_MODULES = (
    "integrator", "boundary", "recorder", "events", "crossing", "pieces", "stay", "loop",
    "ensemble",
)  # fmt: skip
"""The kernel modules, in this order (callees first); the last is the parallel ensemble loop."""

MARKER = "# --- kernel ---"
INLINE = {
    "sample": ("first_event",),
    "watch_terms": (),
    "watch_min": ("first_event", "locate"),
    "watch_at": ("locate",),
    "watch_on_curve": ("locate",),
    "curve_at": ("locate", "first_event"),
    "dense_eval": ("locate", "first_event"),
    "note_used": (),
    "note_reached": (),
    "failed": (),
    "parts": (),
    "value_checked": (),
    "band": (),
    "step_ahead": (),
    "choose": (),
}
"""The kernel functions numba inlines (at its IR level), and into which functions being compiled
(the hot loops: the search's samples, Brent's evaluations; empty: everywhere). LLVM left each a
call (its arrays passed as seven words apiece, a status checked on return): inlined, the loop
of the ball's 40 bounces takes 3/4 of the time. Each copy is compiled again, so a function is
inlined only where it is called often: into every caller, the kernel's first compile took 25 s
of one core instead of 15 (one process); as here, 17.5 s, for the same speed."""
JIT = 'cache=True, nogil=True, error_model="numpy"'


@dataclass(frozen=True)
class Generated:
    """A generated module's source, what it imports beside hybrid, and the model's table."""

    source: str
    library_modules: tuple[str, ...] = ()
    tab: NDArray[np.int64] = field(default_factory=lambda: np.zeros(0, dtype=np.int64))
    compile_estimate: float = 0.0
    """Seconds of one core numba takes to compile it (estimated from its size)."""


def kernel_source(modules: Sequence[str] = KERNEL_MODULES) -> tuple[str, list[str]]:
    """The modules' code below their marker, and every function they define, in order."""
    here = Path(__file__).resolve().parent
    parts, names = [], []
    for module in modules:
        text = (here / f"{module}.py").read_text(encoding="utf-8")
        code = text.split(MARKER, 1)[1]
        parts.append(f"# ---- {module} ----{code}")
        names += _TOP_LEVEL_DEF.findall(code)
    return "\n".join(parts), names


_TOP_LEVEL_DEF = re.compile(r"^def (\w+)\(", re.MULTILINE)
"""A function the kernel's code defines at its top level (read without parsing the code: every
process that runs compiled makes the kernel's source, to find it in the cache)."""


@functools.lru_cache(maxsize=4)
def kernel_module(parallel_over: str = "") -> Generated:
    """The source of the kernel module, or of the ensemble loop over the kernel module named.

    Every function of the kernel is compiled with the explicit signature its
    annotations give; the pieces (:data:`~hybrid.simulation.native.kernel_types.PIECES`)
    also get a C wrapper, so that they can be passed as function pointers. A
    second process finds every piece in numba's cache and compiles nothing; on
    a miss every function is compiled, callees first (each one found in the
    cache is loaded instead). Made once per process (the files are read, not
    parsed: what compiling needs of their syntax is worked out when compiling),
    however often the cache is asked for it.
    """
    parallel = bool(parallel_over)
    modules = ("ensemble",) if parallel else KERNEL_MODULES[:-1]
    code, names = kernel_source(modules)
    pieces = ("run_many",) if parallel else tuple(name for name, _ in PIECES)
    types = (
        f"dict(__import__({parallel_over!r}, fromlist=['_TYPES'])._TYPES)"
        if parallel
        else "numba_types()"
    )
    lines = [
        '"""Generated by hybrid: the compiled loop (see docs/backends.md). Do not edit."""',
        "from __future__ import annotations",
        "import math",
        "import warnings",
        "import numpy as np",
        "from numba import njit, prange, types",
        "from numba.core.errors import NumbaExperimentalFeatureWarning",
        "from hybrid.simulation.native.buffers import *  # noqa: F403",
        "from hybrid.simulation.native.kernel_types import FUNCTION_TYPES, PIECES",
        "from hybrid.simulation.native.kernel_types import numba_signature, numba_types",
        "from hybrid.simulation.native.pointers import at, function_at",
        "from hybrid.simulation.native.shares import compile_kernel, maybe_cached",
        code,
        "",
        "# ---- compiled with numba, callees first (cached on disk beside this file) ----",
        f"_NAMES = {tuple(names)!r}",
        f"_PIECES = {pieces!r}",
        "_ALIASES = dict(PIECES)",
        "# only the ensemble's loop allocates (numba's threads); the others never keep an array,",
        "# so they need no reference counting (numba's runtime, NRT: code per array view made or",
        "# dropped, a third of what compiling run_one took)",
        "_ALLOCATING = ('run_many',)",
        "_PLAIN = {_name: globals()[_name] for _name in _NAMES}",
        f"_INLINE = {INLINE!r}",
        "def _inline(_name):  # numba's inline option: never, always, or into some callers",
        "    if _name not in _INLINE:",
        "        return 'never'",
        "    if not _INLINE[_name]:",
        "        return 'always'",
        "    _into = _INLINE[_name]",
        "    return lambda _expr, _caller, _callee: _caller.func_id.func_name in _into",
        "def _jit(_name):",
        "    _sig = numba_signature(_PLAIN[_name].__annotations__, _TYPES)",
        "    _options = dict(no_cpython_wrapper=_name not in ('run_one', 'run_many'),",
        "                    no_cfunc_wrapper=_name not in _ALIASES,",
        "                    _nrt=_name in _ALLOCATING,",
        "                    inline=_inline(_name))",
        f"    return njit(_sig, parallel={parallel}, {JIT}, **_options)(_PLAIN[_name])",
        "def finish_compiling():",
        '    """Nothing left: every piece is loaded or compiled (else: compile_kernel\'s finish)."""',
        "def build():",
        '    """Compile or load the pieces: importing this module does no work, this does."""',
        "    global _TYPES, finish_compiling",
        "    with warnings.catch_warnings():",
        "        warnings.simplefilter('ignore', NumbaExperimentalFeatureWarning)",
        f"        _TYPES = {types}",
        "        for _name, _alias in PIECES:",
        "            if _name in _PLAIN:",
        "                _sig = numba_signature(_PLAIN[_name].__annotations__, _TYPES)",
        "                _TYPES[_alias] = types.FunctionType(_sig)",
        "        for _alias, _global in FUNCTION_TYPES:",
        "            globals()[_global] = _TYPES[_alias]",
        "        try:",
        "            if not maybe_cached(__file__, __name__, _PIECES):",
        "                raise LookupError('not in numba cache')",
        "            for _name in _PIECES:",
        "                globals()[_name] = _jit(_name)",
        "        except Exception:  # not cached: compiled, in shares by several processes",
        "            finish_compiling = compile_kernel(",
        "                globals(), _jit, _NAMES, _PIECES, __file__, __name__)",
        "",
    ]
    return Generated("\n".join(lines))
