"""Compiling the modes a run meets pauses the cyclic garbage collector, as loading a model does.

A system of many components compiles thousands of small objects at its first run
and keeps most of them; with the collector running, its passes walk the process's
objects again and again meanwhile, full passes among them (50 to 90 ms each in a
process with numpy and scipy loaded). The truth here is the collector's own
report (``gc.callbacks``): no pass starts while a mode compiles, and the collector
is on again after, unless it was off before.
"""

from __future__ import annotations

import gc
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

from bench.scaling_ring import ring
from hybrid.compose import as_system
from hybrid.simulation.compiled import CompiledModel

SIZE = 40


def _ring(n: int) -> CompiledModel:
    """The compiled model of the benchmark's ring of ``n`` coupled thermostats."""
    return CompiledModel(as_system(ring(n)))


@contextmanager
def _passes_while_compiling(compiled: CompiledModel) -> Iterator[list[int]]:
    """The generations of the collector's passes that start while a mode of ``compiled``
    is being built from its parts."""
    seen: list[int] = []
    inside = [False]
    parts = compiled.parts
    assert parts is not None
    build = parts.mode

    def building(*args: Any, **kwargs: Any) -> Any:
        inside[0] = True
        try:
            return build(*args, **kwargs)
        finally:
            inside[0] = False

    def note(phase: str, info: dict[str, int]) -> None:
        if phase == "start" and inside[0]:
            seen.append(info["generation"])

    parts.mode = building  # type: ignore[method-assign]
    gc.callbacks.append(note)
    try:
        yield seen
    finally:
        gc.callbacks.remove(note)
        parts.mode = build  # type: ignore[method-assign]


def test_no_collection_starts_while_the_modes_compile() -> None:
    compiled = _ring(SIZE)
    gc.collect()
    with _passes_while_compiling(compiled) as seen:
        mode = compiled.mode(compiled.initial_key)
        for k in range(6):  # modes met one jump after another, built from their neighbours
            mode = compiled.target(mode, mode.transitions[7 * k % SIZE])
        whole = compiled.mode(tuple("on" for _ in range(SIZE)))
    assert seen == [], f"collections while the modes compiled: generations {seen}"
    assert gc.isenabled()
    assert len(mode.transitions) == len(whole.invariants) == SIZE


def test_a_collector_the_caller_turned_off_stays_off() -> None:
    compiled = _ring(4)
    gc.disable()
    try:
        compiled.mode(compiled.initial_key)
        assert not gc.isenabled()
    finally:
        gc.enable()
