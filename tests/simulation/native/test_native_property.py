"""Property: on generated small models, the compiled backend agrees with the scipy backend.

The models are one structure (so one compilation) with generated parameters
and initial states: speeds, levels, growth rates, reset factors, a priority
race between a level guard and a threshold, an invariant that can block.
Both backends run with the step capped, so that the scipy engine's step-end
checks see every crossing the compiled backend's first-crossing rule sees.
``HYBRID_FUZZ=1`` (``make fuzz``) runs many more examples.
"""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import hybrid

pytest.importorskip("numba")

TEMPLATE = """
automaton: generated
parameters: {va: 1.0, vb: 1.0, hi: 1.0, lo: -1.0, wa: 0.0, ua: 0.5, wb: 0.0, ub: -0.5,
             r: 0.9, ymax: 10.0, ycut: 2.0}
state: {x: {initial: 0.0}, y: {initial: 0.0}}
locations:
  A: {flow: {x: va, y: wa*y + ua}, invariant: y <= ymax}
  B: {flow: {x: -vb, y: wb*y + ub}}
  C: {flow: {x: 0.5*va, y: -1}}
edges:
  - {name: ab, from: A, to: B, guard: x >= hi, reset: {y: r*y}}
  - {name: ac, from: A, to: C, guard: y >= ycut, priority: 1}
  - {name: ba, from: B, to: A, guard: x <= lo}
  - {name: ca, from: C, to: A, guard: y <= 0 and x >= lo, reset: {x: lo + 0.5*(hi - lo)}}
"""

EXAMPLES = 400 if os.environ.get("HYBRID_FUZZ") else 15

MODEL = hybrid.load_text(TEMPLATE)

parameters = st.fixed_dictionaries(
    {
        "va": st.floats(0.3, 3.0),
        "vb": st.floats(0.3, 3.0),
        "hi": st.floats(0.5, 2.0),
        "lo": st.floats(-2.0, -0.2),
        "wa": st.floats(-0.5, 0.5),
        "ua": st.floats(0.2, 1.5),
        "wb": st.floats(-0.5, 0.5),
        "ub": st.floats(-1.5, 1.5),
        "r": st.floats(-1.0, 1.0),
        "ymax": st.floats(1.0, 20.0),
        "ycut": st.floats(0.5, 5.0),
    }
)


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(values=parameters, x0=st.floats(-0.1, 0.4), y0=st.floats(-1.0, 0.4),
       dt=st.one_of(st.none(), st.floats(0.05, 1.0)))  # fmt: skip
def test_generated_models_agree(
    values: dict[str, float], x0: float, y0: float, dt: float | None
) -> None:
    model = MODEL.with_parameters(values)
    common = {"t_end": 6.0, "max_jumps": 40, "rtol": 1e-10, "atol": 1e-12, "dt": dt,
              "initial": {"x": x0, "y": y0}, "handle_sigint": False}  # fmt: skip
    compiled, reference = both_backends(model, common)
    if dt is not None:  # the grid's points away from the jumps, at the same times and states
        # (a grid point that falls on a jump's time is kept or not as the two event times,
        # equal to an ulp or so, fall on either side of it)
        mine, theirs = _away_from_jumps(compiled), _away_from_jumps(reference)
        np.testing.assert_allclose(compiled.t[mine], reference.t[theirs], rtol=1e-10, atol=1e-9)
        for name in ("x", "y"):
            np.testing.assert_allclose(
                compiled[name][mine], reference[name][theirs], rtol=1e-7, atol=1e-8
            )


def both_backends(model: hybrid.Automaton, common: dict[str, object]) -> tuple[hybrid.Run, hybrid.Run]:
    """``(compiled, scipy)`` runs of ``model``, held to the same jumps, times and end."""
    compiled = hybrid.simulate(model, backend="compiled", **common)  # type: ignore[arg-type]
    reference = hybrid.simulate(model, **common)  # type: ignore[arg-type]
    assert [(j.edge, j.target) for j in compiled.jumps] == [(j.edge, j.target) for j in reference.jumps]
    np.testing.assert_allclose(compiled.jump_times, reference.jump_times, rtol=1e-10, atol=1e-9)
    assert compiled.termination.cause == reference.termination.cause
    assert compiled.termination.location == reference.termination.location
    return compiled, reference


def _away_from_jumps(run: hybrid.Run) -> np.ndarray:
    times = np.asarray(run.jump_times, dtype=float)
    if times.size == 0:
        return np.ones(len(run.t), dtype=bool)
    return np.min(np.abs(run.t[:, None] - times[None, :]), axis=1) > 1e-9


# Boundary cases the field's models start in (the SpaceEx ball is dropped from rest on
# its floor): a guard and an invariant on their boundaries at the start, left at second
# order; conjuncts that cannot change or keep a rho at a flat zero; an equality level
# the state sits on. Each spelling is its own structure (compiled once).
EDGE = """
automaton: edge
parameters: {c: 0.0, g: 1.0, e: 0.5, k: 1.0}
state: {x: {initial: 0.0}, y: {initial: 0.0}}
locations:
  A: {flow: {x: y, y: -g}, invariant: 'INV'}
  B: {flow: {x: k, y: 0}}
edges:
  - {name: hit, from: A, to: A, guard: 'GUARD', reset: {y: -e*y}}
  - {name: out, from: A, to: B, guard: 'y <= -2', priority: 1}
  - {name: back, from: B, to: A, guard: 'x >= c + 1', reset: {x: c + 0.5, y: 0}}
"""
SPELLINGS = [
    ("x <= c and y < 0", "x >= c"),
    ("x <= c and y < 0 and 0 >= 0", "x >= c and x <= x"),
    ("max(x - c, 0) <= 0 and y < 0", "x >= c"),
    ("x - c == 0 and y <= 0", "x >= c - 1"),
]
EDGE_MODELS = [
    hybrid.load_text(EDGE.replace("GUARD", guard).replace("INV", inv)) for guard, inv in SPELLINGS
]


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(which=st.integers(0, len(SPELLINGS) - 1), c=st.sampled_from([0.0, -0.5, 1.0]),
       g=st.floats(0.5, 2.0), e=st.floats(0.3, 0.9),
       x_off=st.sampled_from([0.0, 0.0, 1e-12, 0.25]),
       y0=st.sampled_from([0.0, 1e-16, -1e-16, 0.5, -0.5]))  # fmt: skip
def test_models_starting_on_their_boundaries_agree(
    which: int, c: float, g: float, e: float, x_off: float, y0: float
) -> None:
    # with the Zeno detector on: past a Zeno time (zeno=False) the bounces within the band
    # of the floor follow rounding errors of 1e-25, where the backends' arithmetic differs
    model = EDGE_MODELS[which].with_parameters({"c": c, "g": g, "e": e})
    common = {"t_end": 4.05, "max_jumps": 60, "rtol": 1e-10, "atol": 1e-12,
              "initial": {"x": c + x_off, "y": y0}, "handle_sigint": False}  # fmt: skip
    compiled, _ = both_backends(model, common)
    if which < 3:  # never through the floor by more than its band (1e-10 (1 + |state|))
        assert float(np.min(compiled["x"] - c)) >= -1e-9 * (1.0 + abs(c))


# Systems whose components jump at one instant (docs/semantics.md, "Several components at
# one instant"): three clocks with equality guards at levels that are exact in binary, so
# that their events fall on the very same instants; a component that gets stuck (its
# invariant ends at `T`) and one that loops without time passing from `T2` (either left out
# by putting its time beyond the run). Three structures: the clocks independent (the scipy
# backend simulates them apart and merges the runs), joined by a label none of their edges
# carries (one group), or with two of them synchronised on their `back` edges.
CLOCK = """
automaton: clock_K_
parameters: {a: 1.0, b: 1.0, c: 2.0}
state: {x_K_: {initial: 0.0}, n_K_: {initial: 0.0}}
_LABELS_
locations:
  u: {flow: {x_K_: 1, n_K_: 0}}
  v: {flow: {x_K_: 1, n_K_: 0}}
edges:
  - {name: go, from: u, to: v, guard: x_K_ == a, reset: {x_K_: 0}}
  - {name: tick, from: v, to: v, guard: x_K_ == b, reset: {n_K_: n_K_ + 1}, priority: _PRIORITY_}
  - {name: back, from: v, to: u, guard: x_K_ == c, reset: {x_K_: 0}_BACK_}
"""
STUCK = """
automaton: stuck
parameters: {T: 100.0}
state: {s: {initial: 0.0}}
locations:
  wait: {flow: {s: 1}, invariant: s <= T}
"""
LOOPER = """
automaton: looper
parameters: {T2: 100.0}
state: {w: {initial: 0.0}}
locations:
  p: {flow: {w: 1}}
  q: {flow: {w: 0}}
edges:
  - {name: there, from: p, to: q, guard: w >= T2}
  - {name: back, from: q, to: p}
"""
COUPLINGS = ("apart", "declared", "synchronised")
LEVELS = st.sampled_from([0.5, 1.0, 1.5, 2.0, 3.0])


def _clock(k: int, coupling: str) -> hybrid.Automaton:
    labels = {"apart": "", "declared": "labels: [s]", "synchronised": "labels: [s]"}[coupling]
    synchronised = coupling == "synchronised" and k < 3
    text = (
        CLOCK.replace("_K_", str(k))
        .replace("_LABELS_", labels)
        .replace("_PRIORITY_", "1" if k == 1 else "0")
        .replace("_BACK_", ", label: s" if synchronised else "")
    )
    return hybrid.load_text(text)


SYSTEMS = {
    coupling: hybrid.compose(
        *(_clock(k, coupling) for k in (1, 2, 3)),
        hybrid.load_text(STUCK),
        hybrid.load_text(LOOPER),
        names=["c1", "c2", "c3", "stuck", "looper"],
    )
    for coupling in COUPLINGS
}
SYSTEM_EXAMPLES = 500 if os.environ.get("HYBRID_FUZZ") else 12
"""In make test, the synchronised structure alone (each structure is a compile of its own);
all three under make fuzz."""


@pytest.mark.fuzz
@settings(max_examples=SYSTEM_EXAMPLES, deadline=None,
          suppress_health_check=[HealthCheck.too_slow])
@given(coupling=st.sampled_from(COUPLINGS if os.environ.get("HYBRID_FUZZ") else COUPLINGS[2:]),
       levels=st.lists(st.tuples(LEVELS, LEVELS, LEVELS), min_size=3, max_size=3),
       starts=st.lists(st.sampled_from([0.0, 0.5, 1.0]), min_size=3, max_size=3),
       stuck_at=st.sampled_from([0.0, 2.0, 3.0, 100.0]),
       loop_at=st.sampled_from([1.0, 3.0, 100.0]),
       max_jumps=st.sampled_from([30, 1500]))  # fmt: skip
def test_systems_jumping_at_one_instant_agree(
    coupling: str,
    levels: list[tuple[float, float, float]],
    starts: list[float],
    stuck_at: float,
    loop_at: float,
    max_jumps: int,
) -> None:
    values = {"stuck.T": stuck_at, "looper.T2": loop_at}
    for k, (a, b, c) in enumerate(levels, start=1):
        values.update({f"c{k}.a": a, f"c{k}.b": b, f"c{k}.c": c})
    model = SYSTEMS[coupling].with_parameters(values)
    initial = {f"x{k}": x for k, x in enumerate(starts, start=1)}
    # t_end off the grid of event times (multiples of 0.5): no jump falls on it
    common = {"t_end": 6.75, "max_jumps": max_jumps, "initial": initial,
              "handle_sigint": False}  # fmt: skip
    compiled, reference = both_backends(model, common)  # type: ignore[arg-type]
    # the same choices at every instant, listed alike, and the same end
    assert [(j.enabled, j.chosen_by) for j in compiled.jumps] == [
        (j.enabled, j.chosen_by) for j in reference.jumps
    ]
    assert compiled.termination.j == reference.termination.j
    assert abs(compiled.termination.t - reference.termination.t) <= 1e-9
