"""The product graph: exactly the synchronised combinations, explored on the fly."""

from __future__ import annotations

import random
from collections import deque

import pytest

import hybrid
from hybrid.analysis import check, product_graph
from hybrid.analysis.explore import explore, explore_reference
from hybrid.analysis.product import ProductTables
from hybrid.analysis.static import AutomatonFacts
from hybrid.compose import System
from hybrid.modes import transitions_of

HEATER = """
automaton: heater
state: {T: {initial: 20, bounds: [0, 40]}}
signals: {temp: T}
labels: [switch_on, switch_off]
locations:
  off: {flow: {T: -0.1*(T - 10)}}
  on: {flow: {T: 0.1*(30 - T)}}
edges:
  - {name: turn_on, from: off, to: on, label: switch_on}
  - {name: turn_off, from: on, to: off, label: switch_off}
"""
CONTROLLER = """
automaton: controller
inputs: [temp]
labels: [switch_on, switch_off]
locations: {waiting: {}, heating: {}}
edges:
  - {name: cold, from: waiting, to: heating, label: switch_on, guard: temp <= 18}
  - {name: hot, from: heating, to: waiting, label: switch_off, guard: temp >= 22}
  - {name: cold_again, from: heating, to: heating, label: switch_on, guard: temp <= 15}
"""


def compose(*texts: str) -> System:
    return hybrid.compose(*[hybrid.load_text(t) for t in texts])


def test_product_graph_holds_exactly_the_synchronised_combinations():
    system = compose(HEATER, CONTROLLER)
    graph = product_graph(ProductTables(system))
    assert set(graph.nodes) == {"heater.off|controller.waiting", "heater.on|controller.heating"}
    edges = {(u, v, k) for u, v, k in graph.edges(keys=True)}
    assert edges == {
        (
            "heater.off|controller.waiting",
            "heater.on|controller.heating",
            "heater.turn_on+controller.cold",
        ),
        (
            "heater.on|controller.heating",
            "heater.off|controller.waiting",
            "heater.turn_off+controller.hot",
        ),
    }
    data = graph.edges[
        "heater.off|controller.waiting",
        "heater.on|controller.heating",
        "heater.turn_on+controller.cold",
    ]
    assert data["label"] == "switch_on" and data["guard"] == "temp <= 18"
    # heater.on offers switch_on nowhere, so controller.cold_again never fires: no edge at all
    assert not any("cold_again" in k for _, _, k in graph.edges(keys=True))
    # no component moves alone on a shared label
    assert all("+" in k for _, _, k in graph.edges(keys=True))


def test_unsynchronised_combinations_are_absent_but_free_edges_interleave():
    free = """
automaton: lamp
labels: [blink]
locations: {dark: {}, lit: {}}
edges:
  - {name: light, from: dark, to: lit, label: blink}
  - {name: douse, from: lit, to: dark}
"""
    system = compose(HEATER, CONTROLLER, free)
    graph = product_graph(ProductTables(system))
    assert graph.number_of_nodes() == 4  # 2 synchronised heater/controller modes x 2 lamp states
    lamp_moves = [k for _, _, k in graph.edges(keys=True) if k.startswith("lamp.")]
    assert sorted(set(lamp_moves)) == ["lamp.douse", "lamp.light"]  # 'blink' is the lamp's alone


def _reference_modes(system: System) -> set[str]:
    """Brute force over :func:`hybrid.modes.transitions_of`, following only live edges."""
    facts = [AutomatonFacts(c.automaton) for c in system.components]

    def live(tr) -> bool:
        return all(facts[i].edges[e.index].live for i, e in tr.edges)

    seen = {system.initial_mode}
    queue = deque(seen)
    while queue:
        mode = queue.popleft()
        for tr in transitions_of(system, mode, bind=False):
            if live(tr) and tr.target not in seen:
                seen.add(tr.target)
                queue.append(tr.target)
    return {system.mode_name(m) for m in seen}


def test_product_graph_agrees_with_compose_transitions():
    system = compose(HEATER, CONTROLLER)
    graph = product_graph(ProductTables(system))
    assert set(graph.nodes) == _reference_modes(system)
    for node in graph.nodes:
        mode = tuple(part.split(".", 1)[1] for part in node.split("|"))
        expected = {tr.name for tr in transitions_of(system, mode, bind=False)}
        got = {k for _, _, k in graph.out_edges(node, keys=True)}
        assert got <= expected


def _timer(i: int, shared: bool = False) -> str:
    label = "labels: [sync]\n" if shared else ""
    sync = ", label: sync" if shared else ""
    return f"""
automaton: t{i}
state: {{x{i}: {{initial: 0, bounds: [0, 10]}}}}
{label}locations:
  a: {{flow: {{x{i}: 1}}, invariant: x{i} <= 2}}
  b: {{flow: {{x{i}: 1}}, invariant: x{i} <= 2}}
  c: {{flow: {{x{i}: 1}}, invariant: x{i} <= 2}}
edges:
  - {{from: a, to: b, guard: x{i} >= 1, reset: {{x{i}: 0}}{sync}}}
  - {{from: b, to: c, guard: x{i} >= 1, reset: {{x{i}: 0}}}}
  - {{from: c, to: a, guard: x{i} >= 1, reset: {{x{i}: 0}}}}
"""


def test_six_copies_explore_every_combination():
    system = compose(*[_timer(i) for i in range(6)])
    tables = ProductTables(system)
    result = explore(tables)
    assert result.states == 3**6 and result.complete
    assert result.deadlocks == 0 and result.conflicts == 0
    assert all(r.all() for r in result.reached)
    reference = explore_reference(tables)
    assert reference.states == result.states
    far = list(result.modes()).index((2,) * 6)
    assert len(result.path_to(far)) == 12  # two steps per copy, breadth-first
    assert check(system).findings == ()


def test_six_copies_sharing_a_label_move_together_on_it():
    system = compose(*[_timer(i, shared=True) for i in range(6)])
    tables = ProductTables(system)
    result = explore(tables)
    # a -> b only all together; then each copy goes b -> c -> a alone, and waits in a
    assert result.states == 1 + (3**6 - 1)
    assert result.states == explore_reference(tables).states == len(_reference_modes(system))


def _random_system(rng: random.Random) -> System:
    texts = []
    for i in range(rng.randint(2, 3)):
        n = rng.randint(2, 4)
        labels = rng.sample(["a", "b", "c"], rng.randint(0, 2))
        lines = [
            f"automaton: r{i}",
            f"state: {{x{i}: {{initial: 0, bounds: [0, 10]}}}}",
            f"labels: [{', '.join(labels)}]",
            "locations:",
        ]
        for k in range(n):
            inv = rng.choice(["true", f"x{i} <= 5"])
            lines.append(f"  l{k}: {{flow: {{x{i}: 1}}, invariant: '{inv}'}}")
        lines.append("edges:")
        for _ in range(rng.randint(1, 2 * n)):
            src, dst = rng.randrange(n), rng.randrange(n)
            guard = rng.choice(["true", f"x{i} >= 5", f"x{i} > 100", f"x{i} <= 3"])
            label = rng.choice([None, *labels])
            extra = f", label: {label}" if label else ""
            lines.append(f"  - {{from: l{src}, to: l{dst}, guard: '{guard}'{extra}}}")
        texts.append("\n".join(lines) + "\n")
    return compose(*texts)


@pytest.mark.parametrize("seed", range(25))
def test_numpy_and_reference_explorers_agree(seed, monkeypatch):
    system = _random_system(random.Random(seed))
    tables = ProductTables(system)
    fast = explore(tables)
    slow = explore_reference(tables)
    assert fast.states == slow.states == len(_reference_modes(system))
    assert [r.tolist() for r in fast.reached] == [r.tolist() for r in slow.reached]
    assert fast.fired == slow.fired
    assert fast.stuck_at == slow.stuck_at and fast.conflicted_at == slow.conflicted_at
    assert fast.deadlocks == slow.deadlocks and fast.conflicts == slow.conflicts
    assert set(product_graph(tables).nodes) == _reference_modes(system)
    # the sparse visited set (used for very large products) gives the same answer
    monkeypatch.setattr("hybrid.analysis.explore.DENSE_LIMIT", 0)
    assert explore(tables).states == fast.states
    # every witness is a real path of live transitions ending where it should
    for (i, k), index in fast.first_reach.items():
        steps = fast.path_to(index)
        mode = tables.initial
        for transition, target in steps:
            assert transition in tables.successors(mode)
            mode = target
        assert mode[i] == k


def test_exploration_stops_at_the_state_limit():
    system = compose(*[_timer(i) for i in range(4)])
    result = explore(ProductTables(system), max_states=10)
    assert not result.complete and result.states == 10
    assert not explore_reference(ProductTables(system), max_states=10).complete
