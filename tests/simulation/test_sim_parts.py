"""Modes assembled from parts: the same run as modes compiled whole, and no N² build.

A ring of thermostats, each heating faster while its neighbour's heater is on
(a signal read through an input), some with a reset and a state-valued signal:
simulated with its modes assembled from parts and compiled whole, the two runs
must agree exactly (the same expressions evaluated in the same order), and a
failure must be worded the same. Built per component: the parts of one
component read a fixed number of neighbours, whatever the ring's size.
"""

from __future__ import annotations

import numpy as np
import pytest

import hybrid
from hybrid.simulation import parts
from hybrid.simulation.compiled import CompiledModel


def thermostat(i: int, n: int, flow: str = "") -> str:
    prev = (i - 1) % n
    extra = flow or f"0.05*p{prev}"
    return f"""
automaton: th{i}
state: {{T{i}: {{initial: {18 + (i % 5) * 0.7}}}, c{i}: {{initial: 0}}}}
signals: {{p{i}: 0, w{i}: 0.1*T{i}}}
inputs: [p{prev}]
locations:
  off: {{flow: {{T{i}: -0.1*(T{i} - 10) + {extra}, c{i}: 1}}, invariant: T{i} >= 18}}
  on:
    flow: {{T{i}: 0.1*(30 - T{i}) + {extra}, c{i}: 1}}
    signals: {{p{i}: 1, w{i}: 0.2*T{i}}}
    invariant: T{i} <= 22
edges:
  - {{name: heat, from: off, to: on, guard: T{i} <= 18, reset: {{c{i}: 0}}}}
  - {{name: rest, from: on, to: off, guard: T{i} >= 22}}
"""


def ring(n: int, broken: int | None = None) -> hybrid.System:
    texts = [thermostat(i, n, f"sqrt(12 - c{i})" if i == broken else "") for i in range(n)]
    return hybrid.compose(*[hybrid.load_text(t) for t in texts])


def both(n: int, monkeypatch: pytest.MonkeyPatch, broken: int | None = None) -> list[hybrid.Run]:
    """The run of the ring assembled from parts, then compiled whole."""
    runs = []
    for threshold in (parts.PARTS_FROM, 10**9):
        monkeypatch.setattr(parts, "PARTS_FROM", threshold)
        system = ring(n, broken)
        assert (CompiledModel(system).parts is not None) == (threshold <= n)
        runs.append(hybrid.simulate(system, t_end=15.0, handle_sigint=False))
    return runs


def test_a_ring_runs_the_same_assembled_from_parts_as_compiled_whole(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    assembled, whole = both(parts.PARTS_FROM + 1, monkeypatch)
    assert len(assembled.jumps) > 20  # the components switch, at shared instants too
    assert assembled.jumps == whole.jumps
    np.testing.assert_array_equal(assembled.t, whole.t)
    np.testing.assert_array_equal(assembled.states, whole.states)
    np.testing.assert_array_equal(assembled.signals, whole.signals)
    assert list(assembled.location) == list(whole.location)
    assert assembled.termination == whole.termination


def test_a_failing_flow_in_a_part_is_said_as_in_the_whole_mode(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # th3's flow gains sqrt(12 - c3): it warms while off, never heats (so its clock c3
    # is never reset) and the square root fails at t = 12
    assembled, whole = both(parts.PARTS_FROM, monkeypatch, broken=3)
    assert assembled.termination == whole.termination
    assert assembled.termination.cause == "nonfinite"
    assert "sqrt(" in assembled.termination.message
    assert assembled.termination.message.startswith("the flow of th0.")


@pytest.mark.parametrize("n", [parts.PARTS_FROM, 3 * parts.PARTS_FROM])
def test_a_ring_builds_a_few_parts_per_component_whatever_its_size(n: int) -> None:
    system = ring(n)
    run = hybrid.simulate(system, t_end=15.0, handle_sigint=False)
    compiled = CompiledModel(system)
    assert compiled.parts is not None
    # each part reads itself and the neighbour whose signal it reads, not the whole ring
    assert compiled.parts.readers == [tuple(sorted({(i - 1) % n, i})) for i in range(n)]
    visited = {str(name) for name in run.location}
    assert len(visited) > 2 * n  # more modes than components: most are met once
    for name in visited:
        compiled.mode(tuple(part.split(".")[1] for part in name.split("|")))
    # each component in each of its 2 locations, its neighbour in either of 2: at most 4
    # parts a component, however many modes the run met
    assert len(compiled.parts._parts) <= 4 * n


def test_a_failure_worded_without_its_mode_names_the_mode_it_was_built_for(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # the compiled backend words a failure of the reference engine's mode without a mode
    from hybrid.simulation.failures import describe_failure

    words, n = [], parts.PARTS_FROM
    for threshold in (n, 10**9):
        monkeypatch.setattr(parts, "PARTS_FROM", threshold)
        compiled = CompiledModel(ring(n, broken=3))
        mode = compiled.mode(compiled.initial_key)
        x = np.array(compiled.system.initial_vector())
        x[compiled.state_names.index("c3")] = 13.0  # sqrt(12 - 13)
        assert all(np.isnan(mode.rhs(0.0, x)))
        words.append(describe_failure(compiled, compiled.flow_failure))
    assert words[0] == words[1]
    assert words[0].startswith("the flow of th0.off|th1.off|")
    assert words[0].endswith("failed: sqrt(-1): math domain error")


def test_each_point_refers_to_its_locations_one_name() -> None:
    # a product's name grows with its components (here about 20 characters each): a
    # fixed-width string column would hold it whole at every point
    n = 3 * parts.PARTS_FROM
    run = hybrid.simulate(ring(n), t_end=15.0, handle_sigint=False)
    # the location of each point, from the jumps alone: the initial mode until the first
    # jump, then each jump's target
    initial = "|".join(f"th{i}.off" for i in range(n))
    expected = [initial if j == 0 else run.jumps[j - 1].target for j in run.j.tolist()]
    assert run.location.tolist() == expected
    assert run.location.dtype == object
    assert run.location.nbytes == 8 * len(run)  # a reference a point
    assert len({id(name) for name in run.location}) == len(set(expected))
