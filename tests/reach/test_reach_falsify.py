"""The quick refutation (hybrid.reach.falsify): a run found before any flowpipe, checked exactly.

- A ramp ``x' = u`` from ``x in [0, 1]``, ``u in [0, 1]``: the largest ``x`` at
  time ``t`` is ``1 + t`` (start at 1, input at 1), so ``x >= 1.5`` is first
  reached at ``t = 0.5``; at step 0.01 the walk finds it at the first step point
  past it by the entry margin, ``0.51``, and the time reported is where that
  run enters the set, followed exactly between its step points: ``0.5``. No
  flowpipe is computed with ``refute_first``, and nothing is simulated until the
  witness is read.
- The same ramp where ``x <= 1.2`` holds in the location (an invariant, with or
  without an edge out at ``x >= 1.2``): the maximiser would leave the invariant
  or meet the guard, so it is not a run of the model; by hand no run of the
  location exceeds 1.2, and the flowpipe proves ``x >= 1.5`` unreachable.
- An invariant that reads an input holds along the maximiser only if it holds for
  the maximiser's input: the run that climbs fastest is blocked, and the witness
  found instead replays into the set.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import hybrid

RAMP = """
automaton: ramp
state: {{x: {{initial: [0, 1]}}}}
inputs: {{u: {{range: [0, 1]}}}}
locations:
  up: {{flow: {{x: u}}{invariant}}}
  rest: {{flow: {{x: 0}}}}
edges: [{edges}]
properties: {{forbidden: [{{location: up, when: x >= 1.5}}]}}
"""


def test_a_ramp_is_refuted_at_the_first_step_past_its_closed_form_entry() -> None:
    model = hybrid.load_text(RAMP.format(invariant="", edges=""))
    result = hybrid.reach(model, 2.0, max_jumps=1, step=0.01, refute_first=True)
    (entry,) = result.properties
    assert entry.verdict == "refuted"
    assert result.sets == () and not result.complete and entry.first_contact is None
    # the closed form, not the step point 0.51 where the walk met the set
    assert entry.witness_time is not None and math.isclose(entry.witness_time, 0.5, abs_tol=1e-9)
    assert "reached at t = 0.5 " in entry.message
    assert entry.witness_initial == {"x": 1.0}
    u = entry.witness_inputs["u"]
    assert all(u(t) == 1.0 for t in np.linspace(0.0, 0.51, 52))
    replay = hybrid.simulate(
        model,
        entry.witness_time,
        initial=entry.witness_initial,
        inputs=entry.witness_inputs,
        handle_sigint=False,
    )
    assert replay.location[-1] == "up" and replay["x"][-1] == pytest.approx(1.5, rel=1e-9)
    # the witness is that run, simulated when read
    assert entry.witness is not None and entry.witness["x"][-1] >= 1.5


def test_an_exact_refutation_times_its_entry_without_simulating(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """The entry time was found by simulating the refuting run at once: 10.5 s of
    Building BDU02's verdict (48 variables to t = 20) against 0.04 s before. The heater
    ``x' = -0.7 x + 2 u`` from ``x = 2`` with ``u = 1.5`` passes 4 at ``ln(8) / 0.7``."""
    from hybrid.reach import api

    simulated: list[object] = []
    real = api.simulate_candidate

    def counted(*args: object, **kwargs: object) -> object:
        simulated.append(args)
        return real(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(api, "simulate_candidate", counted)
    heater = hybrid.load_text(
        "automaton: heater\nstate: {x: {initial: [1, 2]}}\ninputs: {u: {range: [0.5, 1.5]}}\n"
        "locations: {on: {flow: {x: -0.7 * x + 2 * u}}}\n"
        "properties: {forbidden: [{when: x > 4.0}]}\n"
    )
    result = hybrid.reach(heater, 6.0, max_jumps=0, refute_first=True)
    (entry,) = result.properties
    assert entry.verdict == "refuted" and "propagated exactly" in entry.message
    assert entry.witness_time == pytest.approx(math.log(8.0) / 0.7, rel=1e-12)
    assert simulated == []
    run = entry.witness
    assert len(simulated) == 1 and run is not None and entry.witness is run  # once, kept
    assert run.t[-1] > entry.witness_time and run["x"].max() > 4.0


def test_without_refute_first_the_sets_are_kept_and_the_same_run_refutes() -> None:
    model = hybrid.load_text(RAMP.format(invariant="", edges=""))
    result = hybrid.reach(model, 2.0, max_jumps=1, step=0.01)
    (entry,) = result.properties
    assert entry.verdict == "refuted" and len(result.sets) > 0 and result.complete
    assert entry.first_contact is not None and entry.first_contact <= 0.5
    assert entry.witness_time is not None and math.isclose(entry.witness_time, 0.5, abs_tol=1e-9)


@pytest.mark.parametrize(
    "edges", ["", "{from: up, to: rest, guard: x >= 1.2}"], ids=["invariant", "guard"]
)
def test_a_maximiser_that_is_not_a_run_of_the_model_refutes_nothing(edges: str) -> None:
    model = hybrid.load_text(RAMP.format(invariant=", invariant: x <= 1.2", edges=edges))
    result = hybrid.reach(model, 2.0, max_jumps=1, step=0.01, refute_first=True)
    (entry,) = result.properties
    assert entry.verdict == "proved" and result.complete
    _, hi = result.hull("up")
    assert 1.2 <= hi[0] < 1.5


def test_an_invariant_that_reads_an_input_must_hold_for_the_run_s_input() -> None:
    # x' = 1 + u from 1, invariant x <= 3.2 - 2 u: the run with u = 1 climbs fastest but
    # is blocked at x = 1.2 (t = 0.1); with u = 0 it reaches 1.5 at t = 0.5, with the
    # nominal u = 0.5 at t = 1/3. Read "for some u", the invariant (x <= 3.2) would let
    # the u = 1 run count as reaching 1.5 at t = 0.25; it must not.
    model = hybrid.load_text(
        """
automaton: pinched
state: {x: {initial: 1}}
inputs: {u: {range: [0, 1]}}
locations: {l: {flow: {x: 1 + u}, invariant: x <= 3.2 - 2 * u}}
properties: {forbidden: [{when: x >= 1.5}]}
"""
    )
    result = hybrid.reach(model, 1.0, max_jumps=0, step=0.01, refute_first=True)
    (entry,) = result.properties
    assert entry.verdict == "refuted" and entry.witness_time is not None
    # the witness enters where its run reaches 1.5 (x = 1 + (1 + u) t), before any block
    u = entry.witness_inputs["u"](0.0) if entry.witness_inputs else 0.5
    assert entry.witness_time == pytest.approx(0.5 / (1 + u), abs=1e-7)
    replay = hybrid.simulate(
        model,
        1.0,
        initial=entry.witness_initial,
        inputs=entry.witness_inputs,
        handle_sigint=False,
        rtol=1e-10,
        atol=1e-12,
    )
    assert replay["x"].max() >= 1.5 and replay.termination.t > entry.witness_time  # not blocked


CLOCKED = """
automaton: clk
state: {c: {initial: 1}, y: {initial: [0, 0.1]}}
locations: {a: {flow: {c: 0, y: 1}}}
properties: {forbidden: [{when: y >= 0.5 and c > 1}, {when: y >= 0.5 and t > 3}]}
"""
PINNED = """
automaton: biginv
state: {x: {initial: 999999.0}, y: {initial: [0, 0.001]}}
locations: {a: {flow: {x: 1, y: 1}, invariant: x <= 1.0e6}}
properties: {forbidden: [{when: y >= 1.0022}]}
"""


def test_an_exact_refutation_holds_clock_rows_and_invariants_as_written() -> None:
    """c stays 1 (c' = 0), so 'c > 1' never holds; t > 3 does not hold at t = 3; and x
    reaches its invariant's 1e6 at t = 1, where y <= 1.001 < 1.0022. All three were
    refuted by the exact path: clock rows within 1e-9 and strictness dropped, the
    invariant within 1e-9 (1 + 2e6), twenty times the simulator's band."""
    clocked = hybrid.reach(hybrid.load_text(CLOCKED), 3.0, step=0.01, refute_first=True)
    assert [p.verdict for p in clocked.properties] == ["unknown", "unknown"]
    pinned = hybrid.load_text(PINNED)
    (entry,) = hybrid.reach(pinned, 3.0, step=0.01, refute_first=True).properties
    assert entry.verdict != "refuted"
    run = hybrid.simulate(pinned, 3.0, initial={"y": 0.001}, handle_sigint=False)
    assert run.termination.cause == "blocked" and run["y"].max() < 1.0022
