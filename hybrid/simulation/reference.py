"""The scipy backend's runs (the reference engine): the event loop, or components apart.

:func:`simulate_reference` is what :func:`hybrid.simulate` runs for ``backend="scipy"``:
it compiles the model (once per model and thread,
:class:`~hybrid.simulation.compiled.CompiledModel`) and runs the
:class:`~hybrid.simulation.loop.EventLoop` with Ctrl-C turned into a clean end
(:mod:`~hybrid.simulation.interrupts`), or runs independent components apart
and merges them (:mod:`~hybrid.simulation.apart`). A compiled run imports this
module only for a model with requirements (their monitor): scipy's integrators
are not loaded by a process that does not run them.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np

from hybrid.compose import System
from hybrid.frames import in_frame_room
from hybrid.simulation.apart import independent_groups, simulate_apart
from hybrid.simulation.compiled import CompiledModel
from hybrid.simulation.interrupts import sigint_watch
from hybrid.simulation.loop import EventLoop
from hybrid.simulation.monitor import cut_results, join_groups, monitor_for
from hybrid.simulation.result import Run
from hybrid.simulation.reuse import compiled_model, running
from hybrid.simulation.settings import Settings
from hybrid.simulation.start import initial_vector

__all__ = ["simulate_reference"]


@in_frame_room
def simulate_reference(
    model: System,
    settings: Settings,
    initial: Mapping[str, float] | None,
    inputs: Mapping[str, Callable[[float], float]] | None,
    handle_sigint: bool,
    progress: Callable[[float, int, int], None] | None,
) -> Run:
    """A run on the scipy backend: the event loop, or components apart when independent.

    Run with room on the frame stack (:mod:`hybrid.frames`): the model's functions,
    called thousands of times from one depth, would otherwise map a chunk of it each
    time at some depths of the caller's.
    """
    compiled = compiled_model(model, inputs)
    x0 = np.array(initial_vector(model, compiled.state_names, initial), dtype=float)
    # a solution that blows up overflows inside the solver's linear algebra; the run
    # sees the non-finite state and ends with a message, so numpy's warnings are noise
    with sigint_watch(handle_sigint) as interrupts, np.errstate(all="ignore"):
        if len(groups := _groups(model)) > 1:
            # components that share no label and read no signal of each other: simulated
            # apart and merged in hybrid time, never as a product
            parts: list[tuple[Run, CompiledModel]] = []

            def run_group(
                sub: System, start: np.ndarray, how: Settings
            ) -> tuple[Run, CompiledModel]:
                mine = {k: v for k, v in (inputs or {}).items() if k in sub.free_inputs}
                part = compiled_model(sub, mine)
                loop = EventLoop(part, how, interrupts, None)
                loop.recorder.monitor = monitor_for(part, how)
                with running(part):
                    parts.append((loop.recorder.run(sub.name, loop.run(how.t_start, start)), part))
                return parts[-1]

            run = simulate_apart(model, groups, x0, settings, run_group)
            run.requirements = cut_results(parts, run, settings)
        else:
            loop = EventLoop(compiled, settings, interrupts, progress)
            loop.recorder.monitor = monitor_for(compiled, settings)
            with running(compiled):
                run = loop.recorder.run(model.name, loop.run(settings.t_start, x0))
    return run


def _groups(model: System) -> list[tuple[int, ...]]:
    """The groups simulated apart: independent components, joined where a requirement spans them."""
    groups = independent_groups(model)
    return join_groups(model, groups) if len(groups) > 1 and model.requirements else groups


