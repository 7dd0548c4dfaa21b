"""Decisions carried across the jumps of one instant: the same run as deciding everything.

Systems of many components (their modes built from parts) whose components
jump together: each is simulated with the decisions and signals of one
instant carried from jump to jump (:mod:`hybrid.simulation.same_instant`) and
with that switched off (every entry decides every transition, every point
computes every signal). The two runs must agree to the bit, in every column,
jump and termination, on seeded variations of the features that read what a
jump changes: signals of the state and of other components' signals, resets,
equality guards reached together (levels used at the instant), priorities,
urgent locations, invariants, and a failing flow or signal met in the middle
of an instant. And the carrying must be real: at an instant where all
components jump, it decides a few transitions per jump, not all of them.
"""

from __future__ import annotations

import os
import random
from typing import Any

import numpy as np
import pytest

import hybrid
from hybrid.simulation import boundary, loop, recorder
from hybrid.simulation.compiled import CompiledModel

T_END = 6.0
FUZZ_SYSTEMS = 400
"""Seeded systems of 8 to 14 components compared under ``make fuzz`` (``HYBRID_FUZZ=1``)."""


def component(i: int, n: int, rng: random.Random, broken: tuple[str, str] = ("", "")) -> str:
    """Component ``i`` of ``n``: a clock ``x{i}`` reaching levels, reading ``i-1``'s signal.

    ``broken``: ``("flow", e)`` or ``("signal", e)``, the flow or the signal of location b.
    """
    prev = (i - 1) % n
    start = rng.choice([0.0, 0.0, 0.25, 0.5])
    level = rng.choice(["x{i} >= 1", "x{i} == 1", "x{i} >= 1 and q{p} <= 1.5", "x{i} >= q{p}"])
    level = level.format(i=i, p=prev)
    reset = rng.choice(["{}", f"{{x{i}: 0}}", "{}"])
    speed = rng.choice(["1", f"1 + 0*q{prev}", "1"])
    signal = rng.choice(["x{i}", "2*x{i} + q{p}", "1"]).format(i=i, p=prev)
    second = rng.choice(["", f"  - {{name: also, from: a, to: c, guard: {level}, priority: 1}}\n"])
    urgent = rng.choice(["", "", "urgent: true, "])
    leave = f"q{prev} >= 1 or x{i} >= " + ("0" if urgent else "1")  # urgent: never blocked
    flow_b = broken[1] if broken[0] == "flow" else "1"
    signal_b = broken[1] if broken[0] == "signal" else f"0.5*x{i}"
    return f"""
automaton: c{i}
state: {{x{i}: {{initial: {start}}}}}
signals: {{q{i}: 0}}
inputs: [q{prev}]
locations:
  a: {{flow: {{x{i}: {speed}}}, signals: {{q{i}: {signal}}}, invariant: x{i} <= 4}}
  b: {{flow: {{x{i}: {flow_b}}}, signals: {{q{i}: {signal_b}}}, invariant: x{i} <= 2.5}}
  c: {{{urgent}flow: {{x{i}: 1}}, signals: {{q{i}: 3}}}}
edges:
  - {{name: go, from: a, to: b, guard: {level}, reset: {reset}}}
{second}  - {{name: back, from: b, to: a, guard: x{i} >= 2, reset: {{x{i}: 0}}}}
  - {{name: out, from: c, to: a, guard: {leave}, reset: {{x{i}: 0}}}}
"""


def system(
    seed: int, n: int = 10, broken: dict[int, tuple[str, str]] | None = None
) -> hybrid.System:
    rng = random.Random(seed)
    texts = [component(i, n, rng, (broken or {}).get(i, ("", ""))) for i in range(n)]
    return hybrid.compose(*[hybrid.load_text(t) for t in texts])


class _DecideEverything:
    """The memo switched off: every entry decided whole."""

    def __init__(self, compiled: CompiledModel) -> None:
        pass

    enabled_at_entry = staticmethod(boundary.enabled_at_entry)


def run_both(make: Any, monkeypatch: pytest.MonkeyPatch) -> tuple[hybrid.Run, hybrid.Run]:
    """The run with the instant's decisions carried, then with everything decided."""
    carried = hybrid.simulate(make(), t_end=T_END, handle_sigint=False)
    with monkeypatch.context() as m:
        m.setattr(loop, "InstantMemo", _DecideEverything)
        m.setattr(recorder, "signals_after", lambda *args: None)
        whole = hybrid.simulate(make(), t_end=T_END, handle_sigint=False)
    return carried, whole


def assert_same(a: hybrid.Run, b: hybrid.Run) -> None:
    assert a.jumps == b.jumps
    for column in ("t", "j", "states", "signals"):
        assert getattr(a, column).tobytes() == getattr(b, column).tobytes(), column
    assert list(a.location) == list(b.location)
    assert a.termination == b.termination


@pytest.mark.parametrize("seed", range(12))
def test_a_system_jumping_together_runs_the_same_with_decisions_carried(
    seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    make = lambda: system(seed)  # noqa: E731
    assert CompiledModel(make()).parts is not None
    carried, whole = run_both(make, monkeypatch)
    assert_same(carried, whole)
    times = [j.t for j in carried.jumps]
    assert len(times) - len(set(times)) >= 5  # several jumps share their instant


@pytest.mark.fuzz
@pytest.mark.skipif(not os.environ.get("HYBRID_FUZZ"), reason="make fuzz runs it (HYBRID_FUZZ=1)")
def test_many_systems_run_the_same_with_decisions_carried(monkeypatch: pytest.MonkeyPatch) -> None:
    shared = 0
    for seed in range(100, 100 + FUZZ_SYSTEMS):
        n = 8 + seed % 7
        carried, whole = run_both(lambda s=seed, n=n: system(s, n), monkeypatch)
        assert_same(carried, whole)
        times = [j.t for j in carried.jumps]
        shared += len(times) - len(set(times))
    assert shared >= FUZZ_SYSTEMS  # jumps at shared instants, on average one a system


@pytest.mark.parametrize(
    ("broken", "words"),
    [
        # fails where c4 enters b with x4 >= 1 (unless its reset set x4 to 0)
        ({4: ("flow", "sqrt(0.5 - x4)")}, "the flow of"),
        ({6: ("flow", "1 + log(x6 - 1)")}, "the flow of"),  # at x6 == 1 exactly
        # the signal of the point stored after c4's jump into b
        ({4: ("signal", "sqrt(0.5 - x4)")}, "the signals of"),
    ],
)
def test_a_failure_met_in_the_middle_of_an_instant_is_said_the_same(
    broken: dict[int, tuple[str, str]], words: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    failed = 0
    for seed in range(6):
        carried, whole = run_both(lambda s=seed: system(s, broken=broken), monkeypatch)
        assert_same(carried, whole)
        if carried.termination.cause == "nonfinite":
            failed += 1
            assert carried.termination.message.startswith(words)
    assert failed >= 1


def test_an_instant_where_all_jump_decides_a_few_transitions_per_jump(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # 16 clocks from 0 at rate 1 reach x >= 1 together at t = 1: 16 jumps at one instant.
    # Deciding everything at each entry decides 16 + 15 + ... transitions; carried, each
    # jump decides the parts of the one that moved and of the one reading it.
    n = 16
    text = """
automaton: k{i}
state: {{x{i}: {{initial: 0}}}}
signals: {{q{i}: 0}}
inputs: [q{p}]
locations:
  a: {{flow: {{x{i}: 1}}}}
  b: {{flow: {{x{i}: 1}}, signals: {{q{i}: 1}}}}
edges: [{{from: a, to: b, guard: x{i} >= 1}}]
"""
    make = lambda: hybrid.compose(  # noqa: E731
        *[hybrid.load_text(text.format(i=i, p=(i - 1) % n)) for i in range(n)]
    )
    counts = []
    for off in (False, True):
        calls = [0]
        decide = boundary.decide_at_entry

        def counted(*args: Any, decide: Any = decide, calls: list[int] = calls) -> Any:
            calls[0] += 1
            return decide(*args)

        with monkeypatch.context() as m:
            m.setattr(boundary, "decide_at_entry", counted)
            if off:
                m.setattr(loop, "InstantMemo", _DecideEverything)
            run = hybrid.simulate(make(), t_end=1.5, handle_sigint=False)
        times = [j.t for j in run.jumps]
        assert times == [times[0]] * n and times[0] == pytest.approx(1.0, abs=1e-12)
        np.testing.assert_array_equal(run.signals[-1], np.ones(n))
        counts.append(calls[0])
    carried, whole = counts
    # whole: n at the start of the run, then after each jump of the instant n - 1, ..., 0
    # (a clock in b has no edge; the first jump is decided where the stay stopped)
    assert whole == n + n * (n - 1) // 2
    # carried: n at the start, n when the instant starts, then at most the reader of the
    # one that moved (the mover, in b, has none)
    assert carried <= 3 * n


def test_a_jump_that_enables_its_reader_puts_it_before_a_later_component(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Eight clocks from 0 reach 1 together. k0 and k7 can jump at once; k1 can only after
    # k0 has (it reads k0's signal, 5 until k0 jumps, then 0). File order picks k0, then
    # k1 (enabled by k0's jump), then k7: a decision of k1 carried from before k0's jump
    # would pick k7 first. The others wait for x >= 5.
    n = 8

    def guard(i: int) -> str:
        return {0: "x0 >= 1", 1: "x1 >= 1 and q0 <= 1", n - 1: f"x{n - 1} >= 1"}.get(i, f"x{i} >= 5")

    text = """
automaton: k{i}
state: {{x{i}: {{initial: 0}}}}
signals: {{q{i}: 5}}
inputs: [q{p}]
locations:
  a: {{flow: {{x{i}: 1}}}}
  b: {{flow: {{x{i}: 1}}, signals: {{q{i}: 0}}}}
edges: [{{from: a, to: b, guard: {g}}}]
"""

    def make() -> hybrid.System:
        texts = [text.format(i=i, p=(i - 1) % n, g=guard(i)) for i in range(n)]
        return hybrid.compose(*[hybrid.load_text(t) for t in texts])

    carried, whole = run_both(make, monkeypatch)
    assert_same(carried, whole)
    assert [j.edge.split(".")[0] for j in carried.jumps[:3]] == ["k0", "k1", f"k{n - 1}"]


def test_a_reader_of_a_flow_that_a_jump_changed_is_decided_again(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # At t = 1 k0 (priority 2), k3 (priority 1) and k2 (q1 >= 1) are enabled together; k0
    # jumps first. q1 is x1, which rises at rate q3 = 1 until k3 jumps, then falls at
    # q3 = -1: once k3 has jumped k2's guard sits on its boundary while being left, so
    # k2 must not jump at that instant. Its decision from before k3's jump said it could:
    # it reads the flow of k1, whose part k3's move changed. (Each component reads its
    # predecessor's signal, times 0, so that they are one system and not simulated apart.)
    n = 8

    def spec(i: int) -> str:
        p = (i - 1) % n
        level, priority = {0: ("x0 >= 1", 2), 3: ("x3 >= 1", 1), 2: ("q1 >= 1", 0)}.get(
            i, (f"x{i} >= 5", 0)
        )
        rate = f"q3 + 0*q{p}" if i == 1 else f"0*q{p}" if i == 2 else f"1 + 0*q{p}"
        signal, moved = ("x1", "x1") if i == 1 else ("1", "-1")
        inputs = "[q0, q3]" if i == 1 else f"[q{p}]"
        return f"""
automaton: k{i}
state: {{x{i}: {{initial: 0}}}}
signals: {{q{i}: {signal}}}
inputs: {inputs}
locations:
  a: {{flow: {{x{i}: {rate}}}}}
  b: {{flow: {{x{i}: {rate}}}, signals: {{q{i}: {moved}}}}}
edges: [{{from: a, to: b, guard: {level}, priority: {priority}}}]
"""

    def make() -> hybrid.System:
        return hybrid.compose(*[hybrid.load_text(spec(i)) for i in range(n)])

    assert CompiledModel(make()).parts is not None
    carried, whole = run_both(make, monkeypatch)
    assert_same(carried, whole)
    assert [j.edge.split(".")[0] for j in carried.jumps if j.t < 2] == ["k0", "k3"]
