"""What the analysis knows of each component of a system: its facts, its inputs' intervals.

Examples
--------
>>> import hybrid
>>> lag = hybrid.load_text(
...     "automaton: lag\\nstate: {y: {}}\\ninputs: [x]\\nlocations: {l: {flow: {y: x - y}}}\\n"
... )
>>> src = hybrid.load_text(
...     "automaton: src\\nstate: {x: {bounds: [0, 1]}}\\nlocations: {l: {}}\\n"
... )
>>> facts = component_facts(hybrid.compose(src, lag), 1)
>>> facts.inputs, facts.volatile
({'x': Interval(lo=0.0, hi=1.0)}, frozenset({'x'}))
"""

from __future__ import annotations

import math

from hybrid.analysis.static import AutomatonFacts
from hybrid.compose import System
from hybrid.expr.interval import Interval

__all__ = ["component_facts"]


def component_facts(system: System, index: int) -> AutomatonFacts:
    """The static facts of a component, with what its inputs are known to be.

    A free input ranges over its declared range; an input reading another
    component's state variable over that variable's declared bounds; one
    reading a signal is unknown. Inputs another component provides may change
    when that component jumps (``volatile``).
    """
    automaton = system.components[index].automaton
    if system.single:
        return AutomatonFacts(automaton)
    ranges = system._input_ranges
    states = system.state_vars
    inputs: dict[str, Interval] = {}
    volatile: set[str] = set()
    for name in automaton.inputs:
        if name in ranges:
            inputs[name] = Interval(ranges[name].lo, ranges[name].hi)
        elif name in system.providers:
            volatile.add(name)
            s = states.get(name)
            if s is not None and (math.isfinite(s.lower) or math.isfinite(s.upper)):
                inputs[name] = Interval(s.lower, s.upper)
    return AutomatonFacts(automaton, inputs, frozenset(volatile))
