"""Large systems: independent components are never multiplied out; a huge product ends
with a note at the explorer's bound instead of exhausting memory.

Time and memory are measured in bench/check_scaling.py; here the behaviour.
"""

from __future__ import annotations

import pytest

import hybrid
from hybrid.analysis import analyse, check
from hybrid.analysis.explore import explore, explore_reference
from hybrid.analysis.product import ProductTables
from hybrid.analysis.reach import groups


def thermostat(i: int, *, shared: bool = False) -> hybrid.Automaton:
    label = "labels: [sync]\n" if shared else ""
    sync = ", label: sync" if shared else ""
    model = hybrid.load_text(
        f"""
automaton: th{i}
state: {{T{i}: {{initial: 20, bounds: [0, 40]}}}}
{label}locations:
  off: {{flow: {{T{i}: -0.1*(T{i} - 10)}}, invariant: T{i} >= 18}}
  on: {{flow: {{T{i}: 0.1*(30 - T{i})}}, invariant: T{i} <= 22}}
edges:
  - {{name: heat, from: off, to: on, guard: T{i} <= 18{sync}}}
  - {{name: rest, from: on, to: off, guard: T{i} >= 22}}
""",
        file=f"th{i}.yaml",
    )
    assert isinstance(model, hybrid.Automaton)
    return model


def test_two_hundred_independent_components_are_explored_apart():
    system = hybrid.compose(*[thermostat(i) for i in range(200)])
    assert len(groups(system)) == 200
    analysis = analyse(system)
    exploration = analysis.exploration
    assert exploration.complete
    assert exploration.states == 2**200  # the product of 200 explorations of 2 modes
    assert all(r.all() for r in exploration.reached)
    assert check(system).findings == ()


@pytest.fixture(scope="module")
def wide() -> hybrid.System:
    """70 components sharing a label: 2**70 modes, two int64 words per code."""
    return hybrid.compose(*[thermostat(i, shared=True) for i in range(70)])


def test_a_product_beyond_the_bound_ends_with_a_note_naming_it(wide):
    report = check(wide, max_bytes=1024 * 1024)
    (note,) = report.findings
    assert note.rule == "analysis-incomplete" and note.severity == "note"
    assert "bound of 9,362 modes" in note.message  # 1 MiB / (16 * (3 * 2 words + 1))
    assert "70 interacting component(s)" in note.message
    assert report.ok


def test_wide_codes_agree_with_the_reference_explorer(wide):
    tables = ProductTables(wide)
    # levels: all off (1), all on (1), one off (70), two off (2415): 2487 modes, then the bound
    fast = explore(tables, max_states=2487)
    slow = explore_reference(tables, max_states=2487)
    assert not fast.complete and not slow.complete
    assert fast.states == slow.states == 2487
    assert set(fast.modes()) == set(slow.modes())
    for index in (0, 1, 2, 100, 2486):
        mode = tables.initial
        for transition, target in fast.path_to(index):
            assert transition in tables.successors(mode)
            mode = target
        assert mode == fast.mode(index)


def test_progress_is_reported_while_exploring():
    system = hybrid.compose(*[thermostat(i, shared=True) for i in range(12)])
    seen: list[tuple[int, int]] = []
    result = explore(ProductTables(system), progress=lambda n, f: seen.append((n, f)))
    assert result.complete and result.states == 2**12
    assert seen and seen[-1][0] == result.states
    assert [n for n, _ in seen] == sorted(n for n, _ in seen)
