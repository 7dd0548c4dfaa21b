"""Compiled models reused across runs of one model in a thread (the scipy backend's).

Compiling a mode's functions costs far more than a jump; a sweep, a falsification,
reach's candidate runs, a compiled run's requirement monitor or a benchmark use one
model many times. :func:`compiled_model` keeps the last models' compiled forms per
thread; :func:`running` marks one in use while a run steps it. Neither imports
scipy: a compiled run that only monitors requirements loads none of it.

Examples
--------
>>> import hybrid
>>> from hybrid.compose import as_system
>>> ball = as_system(hybrid.load("specs/bouncing_ball.yaml"))
>>> compiled_model(ball, None) is compiled_model(ball, None)
True
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager

from hybrid.compose import System
from hybrid.model import Automaton
from hybrid.simulation.compiled import CompiledModel
from hybrid.simulation.start import run_inputs

__all__ = ["compiled_model", "running"]


_CACHE = threading.local()
_CACHE_SIZE = 8


def compiled_model(
    model: System, inputs: Mapping[str, Callable[[float], float]] | None
) -> CompiledModel:
    """The compiled model of ``model``, reused across runs of the same model in a thread.

    Compiling a mode's functions costs far more than a jump; a sweep, a falsification,
    reach's candidate runs or a benchmark simulate one model many times, with other
    inputs or none. The run's inputs are put in the compiled functions' slots
    (:meth:`~hybrid.simulation.compiled.CompiledModel.bind_inputs`); free inputs given
    none are held at their nominal values (:func:`run_inputs`). A model a run of this
    thread is still using (an input that simulates it again) is compiled afresh.
    """
    cache: dict[int, tuple[Automaton | System, CompiledModel]] = (
        getattr(_CACHE, "models", None) or {}
    )
    _CACHE.models = cache
    hit = cache.get(id(model))
    if hit is not None and hit[0] is model:
        if not hit[1].running:
            hit[1].bind_inputs(run_inputs(model, inputs))
            # a failure recorded by an earlier run of this model must not end this one
            hit[1].failure.clear()
            hit[1].flow_failure.clear()
            hit[1].terms_failure.clear()
            return hit[1]
        return CompiledModel(model, run_inputs(model, inputs))
    compiled = CompiledModel(model, run_inputs(model, inputs))
    if len(cache) >= _CACHE_SIZE:
        cache.pop(next(iter(cache)))
    cache[id(model)] = (model, compiled)
    return compiled


@contextmanager
def running(compiled: CompiledModel) -> Iterator[CompiledModel]:
    """``compiled`` marked in use while a run steps it (:func:`compiled_model` leaves it be)."""
    before, compiled.running = compiled.running, True
    try:
        yield compiled
    finally:
        compiled.running = before
