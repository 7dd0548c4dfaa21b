"""``backend="auto"``: the compiled backend where it pays for its compile, else scipy, and why.

A compiled run costs about 1/80 of a scipy run (docs/performance.md), but the
first one on a machine compiles the kernel (about 8 s on the benchmark
machine) and each new model structure (its estimated seconds, from its
generated source's size); a process that finds both in the cache loads them in
about 0.4 s. :func:`choose` runs compiled when:

- the model and the kernel are both compiled in the cache (``manifest.json``
  beside each: compiled and loaded whole once), or already loaded in this process;
- or the campaign's runs are expected to save more than compiling costs:
  ``runs * run_s`` (one scipy run of the model, timed by the caller) above the
  compile estimate plus the cached load;

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
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from hybrid.errors import HybridError

__all__ = ["KERNEL_COMPILE_S", "LOAD_S", "Choice", "cached", "choose"]

KERNEL_COMPILE_S = 8.0
"""Seconds a first process on a machine spends compiling the kernel (bench: 7.7 s, 2 cores)."""
LOAD_S = 0.45
"""Seconds a process spends loading a cached kernel and model (bench: 0.43 s)."""
COMPILED_SHARE = 1.0 / 50.0
"""A compiled run's time as a share of a scipy run's (measured 1/75 to 1/100: rounded up)."""


@dataclass(frozen=True)
class Choice:
    """The backend chosen and why (one clause)."""

    backend: str
    reason: str


def cached(model: Any) -> tuple[bool, bool, float]:
    """``(model compiled, kernel compiled, model compile estimate s)`` for ``model``.

    Compiled means sealed in the cache (see :mod:`~hybrid.simulation.native.cache`)
    or loaded in this process. Generates the model's source (no numba import).
    """
    from hybrid.simulation.native.cache import _LOADED, cache_key, cache_root
    from hybrid.simulation.native.kernel_text import kernel_module
    from hybrid.simulation.native.source import generate
    from hybrid.simulation.native.structure import NativeModel

    version = _numba_version()
    generated = generate(NativeModel(model))
    keys = [cache_key(generated, version), cache_key(kernel_module(), version)]
    found = [key in _LOADED or _sealed(cache_root() / key) for key in keys]
    return found[0], found[1], generated.compile_estimate


def choose(model: Any, runs: int, *, method: str = "RK45", inputs: bool = False,
           run_s: Callable[[], float] | None = None) -> Choice:  # fmt: skip
    """The backend for ``runs`` runs of ``model`` (see the module docstring).

    ``inputs``: whether the runs hold inputs (the compiled backend refuses
    them); ``run_s()``: seconds of one scipy run of the model, called only when
    the cache does not decide (None: compiled only from the cache).
    """
    if method != "RK45":
        return Choice("scipy", f"method '{method}' is the scipy backend's")
    if inputs:
        return Choice("scipy", "inputs are held by expressions (the scipy backend)")
    if importlib.util.find_spec("numba") is None:
        return Choice("scipy", "numba is not installed")
    try:
        model_ready, kernel_ready, estimate = cached(model)
    except HybridError as exc:  # a model the compiled backend refuses
        return Choice("scipy", f"the compiled backend cannot run it: {exc}")
    if model_ready and kernel_ready:
        return Choice("compiled", "the compiled model is in the cache")
    cost = LOAD_S + (0.0 if kernel_ready else KERNEL_COMPILE_S) + (0.0 if model_ready else estimate)
    what = "the model" if kernel_ready else "the kernel and the model"
    if run_s is None:
        return Choice("scipy", f"{what} would be compiled first (about {cost:.0f} s)")
    saved = runs * run_s() * (1.0 - COMPILED_SHARE)
    if saved > cost:
        return Choice("compiled", f"{runs} runs save about {saved:.0f} s; compiling {what} "
                                  f"costs about {cost:.0f} s")  # fmt: skip
    return Choice("scipy", f"{runs} runs would save about {saved:.1f} s; compiling {what} "
                           f"costs about {cost:.0f} s")  # fmt: skip


def _sealed(directory: Path) -> bool:
    return (directory / "manifest.json").is_file()


def _numba_version() -> str:
    from importlib.metadata import version

    return version("numba")
