"""The compiled backend: the simulator's semantics as numba-compiled machine code.

``hybrid.simulate(model, ..., backend="compiled")`` and
``hybrid.simulate_many(model, parameters=table, ...)``. Importing this package
imports no numba; numba is imported when a model is first compiled.

Modules: :mod:`~hybrid.simulation.native.structure` (the model with parameter
slots), :mod:`~hybrid.simulation.native.printer` and
:mod:`~hybrid.simulation.native.source` (the generated modules; the model's
one function with :mod:`~hybrid.simulation.native.mathlib` inlined),
:mod:`~hybrid.simulation.native.cache` (on disk); the kernel, compiled once
per machine, whose modules mirror the reference engine function by function
(:mod:`~hybrid.simulation.native.integrator`,
:mod:`~hybrid.simulation.native.boundary`, :mod:`~hybrid.simulation.native.recorder`,
:mod:`~hybrid.simulation.native.events`, :mod:`~hybrid.simulation.native.stay`,
:mod:`~hybrid.simulation.native.loop`, :mod:`~hybrid.simulation.native.ensemble`;
their layouts and types in :mod:`~hybrid.simulation.native.buffers` and
:mod:`~hybrid.simulation.native.kernel_types`); and on the Python side
:mod:`~hybrid.simulation.native.engine` (one run),
:mod:`~hybrid.simulation.native.many` (ensembles) and
:mod:`~hybrid.simulation.native.assemble` (the ``Run``).
"""

from typing import TYPE_CHECKING

from hybrid.lazy import lazy_attributes

if TYPE_CHECKING:
    from hybrid.simulation.native.many import Ensemble, simulate_many

__all__ = ["Ensemble", "simulate_many"]

__getattr__, __dir__ = lazy_attributes(
    __name__,
    {"Ensemble": "hybrid.simulation.native.many", "simulate_many": "hybrid.simulation.native.many"},
)
